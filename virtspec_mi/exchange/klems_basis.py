"""
The Klems angle bases of WINDOW / Radiance BSDF files
=====================================================

A Klems basis divides a hemisphere into rings of polar angle, each cut into equal
azimuth patches centred on φ = 0 (patch j of a ring of n spans
φ ∈ [(j − ½)·360/n, (j + ½)·360/n)); the first ring is one polar cap. The three bases
as the Radiance BSDF library compiles them (its ``abase_list``; Klems 1994) — Radiance
takes a file's basis from its *name* and ignores the ring bounds written in the file:

========  =====================  ===================================================
basis     name in the file       ring lower bounds θ (deg) : patches per ring
========  =====================  ===================================================
full      LBNL/Klems Full        0:1 5:8 15:16 25:20 35:24 45:24 55:24 65:16 75:12 (145)
half      LBNL/Klems Half        0:1 6.5:8 19.5:12 32.5:16 45.5:20 58.5:12 71.5:8 (77)
quarter   LBNL/Klems Quarter     0:1 9:8 27:12 45:12 63:8 (41)
========  =====================  ===================================================

(the last ring ends at 90°). The reduced bases are those of the Radiance library built
into ``pyradiance`` 1.3.1 (read from its compiled table); older Radiance sources
(``bsdf_m.c`` revision 3.29, 2015) list a 73-patch half basis (… 46.5:20 61.5:12 76.5:4)
and a quarter basis with bounds 46 and 66 under the same names. A file is only as
portable as its reader's table: the full basis is the same in both. A patch's projected solid angle is
Λ = π (sin²θ_upper − sin²θ_lower)/n (Σ Λ = π over the hemisphere), and its centre is
the ring's middle polar angle (0 for the cap) at φ = 360 j/n.

Exact aggregation from goniophotometer bins: a uniform φ grid of M bins puts every
patch boundary on a bin edge when 360/M divides 180/n for every ring, i.e. when M is a
multiple of 2n for every n — 480 for the full and half bases (0.75° bins), 48 for the
quarter basis (:meth:`KlemsBasis.phi_bins`); with the ring bounds as θo edges (both
hemispheres) every bin lies inside exactly one patch, and the exact integer counts of
the bins add up to the patch's count (:meth:`KlemsBasis.aggregation`; wrapped patches
around φ = 0 collect the bins on both sides of 0).

References
----------
Klems, J.H. (1994). A new method for predicting the solar heat gain of complex
fenestration systems: I. Overview and derivation of the matrix layer calculation.
ASHRAE Transactions 100(1), 1065–1072.
Ward, G. The Radiance BSDF library (``ray/src/common/bsdf_m.c``: ``abase_list``,
``io_getohm``, ``fo_getndx``).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from math import gcd

import numpy as np

__all__ = ["BASES", "KlemsBasis", "klems_basis"]

BASES: dict[str, tuple[str, tuple[tuple[float, int], ...]]] = {
    "full": ("LBNL/Klems Full", ((0.0, 1), (5.0, 8), (15.0, 16), (25.0, 20), (35.0, 24), (45.0, 24), (55.0, 24),
                                 (65.0, 16), (75.0, 12))),
    "half": ("LBNL/Klems Half", ((0.0, 1), (6.5, 8), (19.5, 12), (32.5, 16), (45.5, 20), (58.5, 12), (71.5, 8))),
    "quarter": ("LBNL/Klems Quarter", ((0.0, 1), (9.0, 8), (27.0, 12), (45.0, 12), (63.0, 8))),
}
"""The Klems bases: name → (name in the file, (lower θ, patches) per ring)."""


@dataclass(frozen=True)
class KlemsBasis:
    """One Klems basis (see the module docstring)."""

    key: str
    name: str
    lower: np.ndarray
    upper: np.ndarray
    phis: np.ndarray

    @property
    def size(self) -> int:
        """Patches per hemisphere (145, 77 or 41: the half and quarter bases as Radiance reads them)."""

        return int(self.phis.sum())

    @cached_property
    def ring(self) -> np.ndarray:
        """Ring index of every patch (patch order: ring by ring, φ increasing from 0)."""

        return np.repeat(np.arange(len(self.phis)), self.phis)

    @cached_property
    def index_in_ring(self) -> np.ndarray:
        return np.concatenate([np.arange(n) for n in self.phis])

    @property
    def theta_centres(self) -> np.ndarray:
        """Polar centre of every ring: 0 for the cap, else the middle of its bounds (deg)."""

        middle = (self.lower + self.upper) / 2
        middle[self.lower == 0.0] = 0.0
        return middle

    @property
    def theta(self) -> np.ndarray:
        """Polar centre of every patch (deg)."""

        return self.theta_centres[self.ring]

    @property
    def phi(self) -> np.ndarray:
        """Azimuth centre of every patch, 360 j/n (deg)."""

        return 360.0 * self.index_in_ring / self.phis[self.ring]

    @property
    def projected_solid_angle(self) -> np.ndarray:
        """Λ = π (sin²θ_upper − sin²θ_lower)/n of every patch (sr); they add up to π."""

        s2 = np.sin(np.radians(self.upper)) ** 2 - np.sin(np.radians(self.lower)) ** 2
        return (np.pi * s2 / self.phis)[self.ring]

    def phi_bins(self) -> int:
        """Uniform φ bins over [0, 360) with every patch boundary on a bin edge: lcm of 2n."""

        m = 1
        for n in self.phis:
            m = m * int(2 * n) // gcd(m, int(2 * n))
        return m

    def theta_edges(self) -> np.ndarray:
        """θo edges for a goniophotometer reading: the ring bounds in both hemispheres (deg)."""

        top = np.append(self.lower, 90.0)
        return np.concatenate([top, 180.0 - top[::-1][1:]])

    def patch_of(self, theta: np.ndarray, phi: np.ndarray) -> np.ndarray:
        """
        Patch index of directions (θ ∈ [0, 90], φ in degrees) — Radiance's ``fo_getndx``
        rule: the ring with lower bound ≤ θ, then round(φ n/360) mod n. −1 outside.
        """

        theta, phi = np.broadcast_arrays(np.asarray(theta, dtype=np.float64), np.asarray(phi, dtype=np.float64))
        ring = np.searchsorted(self.lower, theta, side="right") - 1
        ok = (theta >= 0) & (theta <= 90.0) & (ring >= 0)
        ring = np.clip(ring, 0, len(self.phis) - 1)
        n = self.phis[ring]
        j = np.floor(np.mod(phi, 360.0) * n / 360.0 + 0.5).astype(np.int64) % n
        start = np.concatenate([[0], np.cumsum(self.phis)[:-1]])
        return np.where(ok, start[ring] + j, -1)

    def aggregation(self, theta_edges: np.ndarray, phi_edges: np.ndarray, transmitted: bool) -> np.ndarray:
        """
        Patch of every (θo bin, φo bin) of a goniophotometer reading in one hemisphere
        (``transmitted``: θo > 90°, polar angle 180° − θo from −z), shape (θo bins, φo
        bins); −1 for the other hemisphere's bins.

        Raises
        ------
        ValueError
            When a bin straddles two patches (its edges do not nest in the basis): name
            ``theta_o_bins`` / ``phi_o_bins`` and what they must hold.
        """

        theta_edges, phi_edges = np.asarray(theta_edges, np.float64), np.asarray(phi_edges, np.float64)
        low, high = theta_edges[:-1], theta_edges[1:]
        if transmitted:
            low, high = 180.0 - high, 180.0 - low
        inside = (low >= -1e-9) & (high <= 90.0 + 1e-9)
        bounds = np.append(self.lower, 90.0)
        ring_low = np.searchsorted(bounds, low + 1e-9, side="right") - 1
        ring_high = np.searchsorted(bounds, high - 1e-9, side="right") - 1
        if np.any(inside & (ring_low != ring_high)):
            raise ValueError(f"theta_o_bins must have every {self.name} ring bound as an edge (in both hemispheres: "
                             f"{', '.join(f'{t:g}' for t in self.theta_edges())})")
        if phi_edges[0] != 0.0 or phi_edges[-1] != 360.0:
            raise ValueError("phi_o_bins must cover [0, 360] without folding for a Klems basis")
        centre_phi = (phi_edges[:-1] + phi_edges[1:]) / 2
        table = np.full((len(low), len(centre_phi)), -1, dtype=np.int64)
        start = np.concatenate([[0], np.cumsum(self.phis)[:-1]])
        for b in np.nonzero(inside)[0]:
            r = ring_low[b]
            n = self.phis[r]
            width = 360.0 / n
            j_low = np.floor(phi_edges[:-1] / width + 0.5 + 1e-9)
            j_high = np.floor(phi_edges[1:] / width + 0.5 - 1e-9)
            if np.any(j_low != j_high):
                raise ValueError(f"phi_o_bins must put every {self.name} patch boundary on a bin edge (e.g. "
                                 f"{self.phi_bins()} equal bins)")
            table[b] = start[r] + (j_low.astype(np.int64) % n)
        return table


def klems_basis(basis: str = "full") -> KlemsBasis:
    """The :class:`KlemsBasis` ``full``, ``half`` or ``quarter``."""

    if basis not in BASES:
        raise ValueError(f"basis must be one of {', '.join(BASES)} (got {basis!r})")
    name, rings = BASES[basis]
    lower = np.array([r[0] for r in rings], dtype=np.float64)
    upper = np.append(lower[1:], 90.0)
    return KlemsBasis(basis, name, lower, upper, np.array([r[1] for r in rings], dtype=np.int64))
