"""
Goniophotometer bins in the kernel: a ray's outgoing direction → its bin
========================================================================

:class:`BinLayout` holds the plain arrays of a goniophotometer's θo × φo bins
(:meth:`virtspec_mi.instruments.goniophotometer.bins.GonioBins.layout` makes one) and is the kernel's exit
hook (:mod:`virtspec_mi.kernel.hooks`) that bins every reflected or transmitted ray by
its outgoing direction in the specimen frame, in the ray kernel itself:

- the hemisphere is the ray's fate (reflected: θo ≤ 90°, transmitted: θo ≥ 90°;
  grazing exits included), so the bins covering a hemisphere add up to its count exactly;
- θo: given edges are searched by their float32 keys sin²θ (θ ≤ 90°), 2 − sin²θ beyond;
  n bins per hemisphere uniform in θo or in sin²θo (``projected``) are found
  arithmetically and mirrored below the horizon;
- φo ∈ [0, 360) from the specimen's x axis, or folded to |φo − φi| wrapped into
  [0, 180]; equal bins arithmetically, given edges by a search;
- a ray that is absorbed, has no fate or falls outside the bins' range gets code K.

:class:`WarpedLayout` is the other binning (``binning="rgl"``): the cells of an RGL
``.bsdf``'s grid, found from the half vector of the ray's outgoing direction and its
reading's incidence direction (the cells:
:mod:`virtspec_mi.instruments.goniophotometer.warped`).

Dr.Jit and Mitsuba are imported where the bins are computed, not with the module: a
layout is built (and pickled for a Dask worker) before Mitsuba is set up.

References
----------
Nicodemus, F.E. et al. (1977). Geometrical considerations and nomenclature for
reflectance. NBS Monograph 160.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from virtspec_mi.kernel.counts import Fate
from virtspec_mi.kernel.hooks import ExitHook

__all__ = ["BinLayout", "WarpedLayout", "search_edges"]

# The largest float32 below 1: the key sin²θo of a reflected ray stays below the 90° edge.
_BELOW_ONE = float(np.nextafter(np.float32(1.0), np.float32(0.0)))


@dataclass(frozen=True, eq=False)
class BinLayout(ExitHook):
    """
    The goniophotometer's bins as the kernel uses them (plain values, picklable).

    Parameters
    ----------
    shape : tuple of int
        (θo bins, φo bins); the flat bin is θo bin · φo bins + φo bin.
    theta_keys : ndarray
        float32 keys of the θo edges (sin²θ up to 90°, 2 − sin²θ beyond): searched when
        ``regular_theta`` is ``None``.
    regular_theta : tuple or None
        (bins per hemisphere, reflection binned, transmission binned) for θo bins made by
        a binning (found arithmetically), else ``None``.
    projected : bool
        The regular θo bins are uniform in sin²θo (else in θo).
    phi_edges : ndarray
        float32 φo edges in degrees (folded: relative azimuth in [0, 180]).
    regular_phi : bool
        Equal φo bins over the whole range (found arithmetically).
    fold_phi : bool
        φo folded to |φo − φi| wrapped into [0, 180].
    """

    shape: tuple[int, int]
    theta_keys: np.ndarray
    regular_theta: tuple[int, bool, bool] | None
    projected: bool
    phi_edges: np.ndarray
    regular_phi: bool
    fold_phi: bool

    @property
    def size(self) -> int:
        return self.shape[0] * self.shape[1]

    def pairing(self, phi_i: float) -> int:
        """
        Pair the two φo bins either side of the mirror azimuth φi + 180° in one word:
        specular lobes lie in the plane of incidence and straddle that edge when the φo
        edges are symmetric about it (folded bins: 0, the lobes sit at the range's end).
        """

        if self.fold_phi:
            return 0
        mirror = (float(phi_i) + 180.0) % 360.0
        edges = self.phi_edges.astype(np.float64)
        distance = np.abs((edges - mirror + 180.0) % 360.0 - 180.0)
        edge = int(np.argmin(distance))
        if edge in (0, len(edges) - 1):  # the row's first and last bins meet there: never one word
            return 0
        return (edge - 1) % 2

    def bin(self, wo: Any, fate: Any, phi_i: Any) -> Any:
        """Flat bin of each ray; K for a ray that is not binned (see the module docstring)."""

        import drjit as dr
        import mitsuba as mi

        n_theta, n_phi = self.shape
        r2 = wo.x * wo.x + wo.y * wo.y
        sin2 = r2 / (r2 + wo.z * wo.z)
        reflected = fate == int(Fate.REFLECTED)
        transmitted = fate == int(Fate.TRANSMITTED)
        if self.regular_theta is None:  # given edges: search the keys
            key = dr.select(reflected, dr.minimum(sin2, _BELOW_ONE), 2.0 - sin2)
            theta_bin = search_edges(self.theta_keys, key)
        else:  # n bins per hemisphere, uniform in sin²θo or in θo: arithmetic, mirrored below
            per, reflection, transmission = self.regular_theta
            if self.projected:
                position = sin2 * float(per)
            else:
                position = dr.atan2(dr.sqrt(r2), dr.abs(wo.z)) * (2.0 * per / dr.pi)
            j = mi.UInt32(dr.clip(mi.Int32(dr.floor(position)), 0, per - 1))
            outside = mi.UInt32(n_theta)
            theta_bin = dr.select(reflected, j if reflection else outside,
                                  (mi.UInt32(per * reflection + per - 1) - j) if transmission else outside)
        phi = dr.atan2(wo.y, wo.x) * (180.0 / dr.pi)
        phi = dr.select(phi < 0.0, phi + 360.0, phi)
        if self.fold_phi:
            relative = phi - phi_i
            relative = relative - 360.0 * dr.floor(relative / 360.0)
            phi = dr.minimum(relative, 360.0 - relative)
        if self.regular_phi:
            top = 180.0 if self.fold_phi else 360.0
            phi_bin = mi.UInt32(dr.clip(mi.Int32(dr.floor(phi * (n_phi / top))), 0, n_phi - 1))
        else:
            phi_bin = search_edges(self.phi_edges, phi)
        binned = (reflected | transmitted) & (theta_bin < n_theta) & (phi_bin < n_phi)
        return dr.select(binned, theta_bin * n_phi + phi_bin, mi.UInt32(self.size))


def search_edges(edges: np.ndarray, key: Any) -> Any:
    """
    Bin of ``key`` among increasing float32 ``edges``: i with edges[i] <= key < edges[i + 1],
    the last bin closed (key == edges[-1] is in it); ≥ the number of bins when outside
    (binary lifting over a table padded with +inf to 2^k entries).
    """

    import drjit as dr
    import mitsuba as mi

    edges = np.asarray(edges, dtype=np.float32)
    steps = max(1, int(np.ceil(np.log2(len(edges) + 1))))
    padded = np.full(1 << steps, np.inf, dtype=np.float32)
    padded[: len(edges)] = edges
    table = mi.Float(padded)
    below = mi.UInt32(0)  # how many edges are <= key
    for step in reversed(range(steps)):
        probe = below + (1 << step)
        below = dr.select(dr.gather(mi.Float, table, probe - 1) <= key, probe, below)
    last = len(edges) - 1
    below = dr.select(key == float(edges[-1]), mi.UInt32(last), below)
    return below - 1  # no edge <= key: wraps to 2^32 - 1, outside


@dataclass(frozen=True, eq=False)
class WarpedLayout(ExitHook):
    """
    The cells of an RGL ``.bsdf``'s n × n grid (identity warp) as the kernel finds them
    (:mod:`virtspec_mi.instruments.goniophotometer.warped`): a reflected ray's half vector
    m ∝ wi + wo gives u = (√(2θm/π), (φm − φi + π)/2π), φi = atan2(wi_y, wi_x), in float32
    as Mitsuba's ``measured`` plugin computes it; the nearest node (i, j) = round(u·(n − 1))
    names the cell (row n − 1 is row 0; column 0 is one cell; at normal incidence, wi_x =
    wi_y = 0, each column is one cell). Transmitted, absorbed and unresolved rays get code K.

    Parameters
    ----------
    resolution : int
        n, nodes per axis.
    """

    resolution: int
    incidence: ClassVar[bool] = True

    @property
    def size(self) -> int:
        return 1 + (self.resolution - 1) ** 2

    def bin(self, wo: Any, fate: Any, phi_i: Any, wi: Any = None) -> Any:
        """Cell of each reflected ray (K for every other ray)."""

        import drjit as dr
        import mitsuba as mi

        n1 = self.resolution - 1
        h = wi + wo
        theta_m = dr.atan2(dr.sqrt(h.x * h.x + h.y * h.y), h.z)
        u1 = dr.sqrt(dr.maximum(theta_m, 0.0) * (2.0 / dr.pi))
        normal = (wi.x == 0.0) & (wi.y == 0.0)
        u2 = (dr.atan2(h.y, h.x) - dr.select(normal, 0.0, dr.atan2(wi.y, wi.x))) * (0.5 / dr.pi) + 0.5
        u2 = u2 - dr.floor(u2)
        c1 = mi.UInt32(dr.clip(mi.Int32(dr.floor(u1 * n1 + 0.5)), 0, n1))
        c2 = mi.UInt32(dr.clip(mi.Int32(dr.floor(u2 * n1 + 0.5)), 0, n1))
        c2 = dr.select((c2 == n1) | normal, mi.UInt32(0), c2)
        cell = dr.select(c1 == 0, mi.UInt32(0), (c1 - 1) * n1 + c2 + 1)
        return dr.select(fate == int(Fate.REFLECTED), cell, mi.UInt32(self.size))
