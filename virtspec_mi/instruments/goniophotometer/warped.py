"""
The RGL grid as goniophotometer bins: cells of Mitsuba's ``measured`` lookup
============================================================================

Mitsuba's ``measured`` BSDF (Dupuy & Jakob 2018) looks an outgoing direction wo up by the
half vector m = (wi + wo)/|wi + wo| of the pair: at

    u = (u₁, u₂) = (√(2θm/π), (φm − φi + π)/2π) ∈ [0, 1]²

(φi = atan2(wi_y, wi_x), the plugin's own), warped by the file's VNDF onto the n × n nodes
of ``spectra`` and interpolated bilinearly between them. The export writes the identity
warp (a uniform VNDF), so the nodes are the regular grid u = (i/(n−1), j/(n−1)), i (θm) and
j (φm) in 0 … n−1, and the plugin's lookup position of a direction is u itself.

:class:`WarpedGrid` makes that grid the goniophotometer's bins (``binning="rgl"``): the
**cell** of node (i, j) is the set of reflected directions whose lookup position is nearer
to that node than to any other, |u − u_node| ≤ h/2 on each axis (h = 1/(n−1)) — where the
plugin's interpolation gives the node its largest weight. Three rules make the cells a
partition of the reflected hemisphere:

- the rows j = 0 and j = n − 1 are one azimuth (φm − φi = −180° and +180°): one cell,
  u₂ within h/2 of either, stored at both rows;
- the column i = 0 is one direction (θm = 0: the mirror direction) whatever the row: one
  cell, the disc u₁ ≤ h/2, stored at every row of that column;
- at normal incidence (θi = 0) there is no azimuth of incidence (the plugin reads
  atan2(0, 0) = 0): each column i ≥ 1 is one cell, the ring of u₁ within h/2 of the node,
  stored at every row (rotation-invariant).

So there are K = 1 + (n − 1)² cell indices (cell 0: the disc; cell 1 + (i − 1)(n − 1) + j
for i ≥ 1, j < n − 1; at θi = 0 only j = 0 is used). Every reflected ray falls in exactly
one cell: the cells of a reading add up to its reflected count.

A cell's **solid angle** Ω_k = ∫ dωo over its reflected directions (wo_z > 0): with
dωo = 4 (m·wi) dωm (the reflection's Jacobian) and dωm = sin θm dθm dφm, the directions
of a row of azimuths φ = φm − φi with wo_z > 0 are θm < θh(φ) = (π/2 + α)/2,
α = atan2(sin θi cos φ, cos θi) (wo_z = A cos(2θm − α)). :meth:`WarpedGrid.cell_integral`
integrates any function of wo over a cell by Gauss–Legendre quadrature on the pieces of φ
between the points where θh crosses the cell's θm edges (the integrand is analytic on each
piece: the quadrature is exact to rounding for Ω_k, Σ_k Ω_k = 2π).

The goniophotometer's count of cell k estimates p_k = ∫_cell f(wi, wo) cos θo dωo (the
share of a collimated beam's rays reflected into the cell): m_k/(N Ω_k) is the
solid-angle **mean of f·cos θo over the cell** — the quantity ``spectra`` stores — and its
simultaneous Clopper–Pearson interval divided by Ω_k certifies that mean.

In the kernel (:class:`~virtspec_mi.instruments.goniophotometer.hook.WarpedLayout`) the
lookup position is computed in float32, as the plugin computes it: a direction within
~10⁻⁶ of a cell's edge in u may be counted in its neighbour (the count is of the cell as
float32 draws it; its solid angle is the exact cell's).

References
----------
Dupuy, J. and Jakob, W. (2018), An Adaptive Parameterization for Efficient Material
Acquisition and Rendering, ACM Trans. Graph. 37(6), 274 (Sect. 5, eq. 9: the half-vector
parameterization); Mitsuba 3, ``src/bsdfs/measured.cpp`` (``theta2u``, ``phi2u``, the
bilinear lookup); Walter, B. et al. (2007), Microfacet models for refraction, EGSR, eq. 14
(dωo = 4 |wo·m| dωm).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np

from virtspec_mi.instruments.goniophotometer.hook import WarpedLayout

__all__ = ["WarpedGrid", "check_resolution", "DEFAULT_RESOLUTION"]

DEFAULT_RESOLUTION = 32
"""Nodes per axis of the grid (n × n per θi and wavelength)."""

_MAX_RESOLUTION = 1025  # K = 1 + 1024² cells: MAX_BINS of one reading


def check_resolution(value: object) -> int:
    """A grid's nodes per axis, a whole number 3 … 1025; ``ValueError`` naming ``rgl_resolution``."""

    if isinstance(value, str) and value.strip().isdigit():
        value = int(value)
    if isinstance(value, float) and value.is_integer():
        value = int(value)
    if not isinstance(value, (int, np.integer)) or isinstance(value, bool) or not 3 <= value <= _MAX_RESOLUTION:
        raise ValueError(f"rgl_resolution must be a whole number of nodes per axis, 3 <= rgl_resolution <= "
                         f"{_MAX_RESOLUTION} (got {value!r})")
    return int(value)


def _incidence(theta_i: float, phi_i: float) -> tuple[np.ndarray, float]:
    """wi (unit, towards the emitter) and the plugin's azimuth of incidence atan2(wi_y, wi_x) (radians)."""

    t, p = math.radians(theta_i), math.radians(phi_i)
    wi = np.array([math.sin(t) * math.cos(p), math.sin(t) * math.sin(p), math.cos(t)])
    return wi, (0.0 if theta_i == 0.0 else math.atan2(wi[1], wi[0]))


@dataclass(frozen=True)
class WarpedGrid:
    """
    The n × n nodes of an RGL ``.bsdf`` (identity warp) and their cells as bins (see the
    module docstring).

    Attributes
    ----------
    resolution : int
        n, nodes per axis (3 … 1025).
    """

    resolution: int = DEFAULT_RESOLUTION

    def __post_init__(self) -> None:
        object.__setattr__(self, "resolution", check_resolution(self.resolution))

    @property
    def size(self) -> int:
        """K = 1 + (n − 1)²: the cell indices."""

        return 1 + (self.resolution - 1) ** 2

    def layout(self) -> WarpedLayout:
        """The kernel's exit hook that bins rays by cell."""

        return WarpedLayout(self.resolution)

    # -- nodes ---------------------------------------------------------------------------

    def node_directions(self, theta_i: float, phi_i: float) -> np.ndarray:
        """
        (n, n, 3): each node's outgoing direction (rows: the φm axis j, columns: the θm axis i,
        as ``spectra``'s last two axes) for incidence (θi, φi) in degrees.
        """

        n = self.resolution
        wi, reference = _incidence(theta_i, phi_i)
        u = np.arange(n) / (n - 1)
        theta_m = (np.pi / 2) * u ** 2
        phi_m = reference + 2 * np.pi * u - np.pi
        m = np.stack([np.cos(phi_m)[:, None] * np.sin(theta_m)[None, :],
                      np.sin(phi_m)[:, None] * np.sin(theta_m)[None, :],
                      np.broadcast_to(np.cos(theta_m)[None, :], (n, n))], axis=-1)
        return 2.0 * (m @ wi)[..., None] * m - wi

    def node_cells(self, theta_i: float) -> np.ndarray:
        """(n, n) the cell index each node stores (rows j, columns i; see the module docstring)."""

        n = self.resolution
        j = np.arange(n) % (n - 1)
        i = np.arange(n)
        if theta_i == 0.0:
            j = np.zeros(n, dtype=int)
        cells = 1 + (i[None, :] - 1) * (n - 1) + j[:, None]
        cells[:, 0] = 0
        return cells

    def cell_of(self, theta_i: float, phi_i: float, wo: np.ndarray) -> np.ndarray:
        """Cell index of reflected directions ``wo`` (…, 3) (float64: the kernel's rule without its rounding)."""

        n1 = self.resolution - 1
        wi, reference = _incidence(theta_i, phi_i)
        h = np.asarray(wo, dtype=np.float64) + wi
        u1 = np.sqrt(np.arctan2(np.hypot(h[..., 0], h[..., 1]), h[..., 2]) * (2 / np.pi))
        u2 = (np.arctan2(h[..., 1], h[..., 0]) - reference) / (2 * np.pi) + 0.5
        u2 = u2 - np.floor(u2)
        c1 = np.minimum(np.floor(u1 * n1 + 0.5), n1).astype(np.int64)
        c2 = np.floor(u2 * n1 + 0.5).astype(np.int64) % n1
        if theta_i == 0.0:
            c2 = np.zeros_like(c2)
        return np.where(c1 == 0, 0, 1 + (c1 - 1) * n1 + c2)

    # -- cells: their extent and integrals ---------------------------------------------

    def cell_bounds(self, theta_i: float) -> np.ndarray:
        """
        (K, 4): each cell's θm range and azimuth range φ = φm − φi (radians): θa, θb, φa, φb
        (φb − φa = 2π for the disc and, at θi = 0, the rings; NaN rows for indices unused).
        """

        n = self.resolution
        h = 1.0 / (n - 1)
        bounds = np.full((self.size, 4), np.nan)
        bounds[0] = (0.0, (np.pi / 2) * (h / 2) ** 2, -np.pi, np.pi)
        for i in range(1, n):
            theta_a = (np.pi / 2) * ((i - 0.5) * h) ** 2
            theta_b = (np.pi / 2) * min(1.0, (i + 0.5) * h) ** 2
            rows = [0] if theta_i == 0.0 else range(n - 1)
            for j in rows:
                k = 1 + (i - 1) * (n - 1) + j
                if theta_i == 0.0:
                    bounds[k] = (theta_a, theta_b, -np.pi, np.pi)
                else:
                    centre = 2 * np.pi * j * h - np.pi
                    bounds[k] = (theta_a, theta_b, centre - np.pi * h, centre + np.pi * h)
        return bounds

    def cell_integral(self, theta_i: float, phi_i: float, function: Callable[[np.ndarray], np.ndarray] | None = None,
                      order: int = 24, cells: np.ndarray | None = None) -> np.ndarray:
        """
        ∫ g(wo) dωo over the reflected directions (wo_z > 0) of each cell (``cells``: indices, default all;
        unused indices give NaN); g = ``function`` of wo (…, 3) (vectorised), 1 by default (the solid angle
        Ω_k). Gauss–Legendre of ``order`` points per axis on each piece of the azimuth range between the
        points where the horizon θh(φ) crosses the cell's θm edges, no piece wider than π/32 (see the module
        docstring).
        """

        wi, reference = _incidence(theta_i, phi_i)
        st, ct = math.sin(math.radians(theta_i)), math.cos(math.radians(theta_i))
        nodes, weights = np.polynomial.legendre.leggauss(order)
        bounds = self.cell_bounds(theta_i)
        chosen = np.arange(self.size) if cells is None else np.asarray(cells, dtype=np.int64)
        out = np.full(len(chosen), np.nan)

        def horizon(phi: np.ndarray) -> np.ndarray:
            return (np.pi / 2 + np.arctan2(st * np.cos(phi), ct)) / 2

        for index, k in enumerate(chosen):
            theta_a, theta_b, phi_a, phi_b = bounds[k]
            if np.isnan(theta_a):
                continue
            cuts = [phi_a, phi_b]
            if st > 0.0:
                for edge in (theta_a, theta_b):
                    c = ct * math.tan(2 * edge - np.pi / 2) / st if 0.0 < edge < np.pi / 2 else np.inf
                    if abs(c) <= 1.0:
                        root = math.acos(c)
                        for base in (root, -root):
                            for turn in (-2 * np.pi, 0.0, 2 * np.pi):
                                if phi_a < base + turn < phi_b:
                                    cuts.append(base + turn)
            cuts = np.unique(cuts)
            pieces = np.maximum(1, np.ceil(np.diff(cuts) / (np.pi / 32))).astype(int)  # no piece wider than π/32
            cuts = np.concatenate([np.linspace(a, b, p + 1)[:-1] for a, b, p in zip(cuts[:-1], cuts[1:], pieces)]
                                  + [cuts[-1:]])
            total = 0.0
            for low, high in zip(cuts[:-1], cuts[1:]):
                phi = (high - low) / 2 * nodes + (high + low) / 2
                top = np.minimum(theta_b, horizon(phi))
                span = np.maximum(top - theta_a, 0.0)
                theta = span[:, None] / 2 * nodes[None, :] + (theta_a + span[:, None] / 2)
                m = np.stack([np.sin(theta) * np.cos(phi + reference)[:, None],
                              np.sin(theta) * np.sin(phi + reference)[:, None], np.cos(theta)], axis=-1)
                dot = m @ wi
                jacobian = 4.0 * dot * np.sin(theta)
                value = jacobian if function is None else jacobian * function(2.0 * dot[..., None] * m - wi)
                inner = (value * weights[None, :]).sum(axis=1) * span / 2
                total += float((inner * weights).sum() * (high - low) / 2)
            out[index] = total
        return out

    def solid_angles(self, theta_i: float) -> np.ndarray:
        """Ω_k (sr) of every cell's reflected directions at θi (degrees); NaN for indices unused (θi = 0)."""

        return self.cell_integral(theta_i, 0.0)
