"""
Linear spectral functionals and their Hoeffding certificate
===========================================================

A derived quantity that is linear in the spectrum — a tristimulus value, a band's
reflectance, fAPAR, a weighted albedo — is a **functional** L = Σₖ wₖ q(λₖ) of one
per-reading quantity q (reflectance, transmittance or absorptance), each q(λₖ) the
probability that a ray of reading k ends in that fate. Its estimate L̂ = Σₖ wₖ mₖ/Nₖ is a
sum of independent bounded terms — ray j of reading k adds wₖ/Nₖ·{0, 1}, a range of
|wₖ|/Nₖ — so Hoeffding (1963, Theorem 2) bounds it directly:

    P(|L̂ − L| ≥ t) ≤ 2 exp(−2t² / Σₖ wₖ²/Nₖ)                                   (1)

(:func:`hoeffding_tolerance` solves (1) for t at δ). At a fixed total N, Σₖ wₖ²/Nₖ is
least for Nₖ ∝ |wₖ| (Cauchy–Schwarz), where it is (Σₖ|wₖ|)²/N: the whole functional
costs the rays of ONE reading at tolerance t/Σ|wₖ|, and a wavelength of zero weight
costs none (:func:`allocate`). Several functionals stated together share δ by a union
bound (δ/m each, :func:`union_delta`); when they share readings each reading takes the
most rays any of them asks for, which only shrinks every Σₖ wₖ²/Nₖ.

When the readings of different wavelengths are one set of rays (a wavelength-independent
specimen: :attr:`~virtspec_mi.results.readings.Result.wavelength_independent`), ray j
adds (Σₖ wₖ)/N·{0, 1} and (1) holds with Σₖ wₖ²/Nₖ replaced by (Σₖ wₖ)²/N.

References
----------
Hoeffding, W. (1963). Probability inequalities for sums of bounded random variables.
*J. Amer. Statist. Assoc.* 58(301), 13–30, Theorem 2 (eq. 2.3).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

__all__ = ["QUANTITIES", "Functional", "hoeffding_tolerance", "allocate", "allocate_jointly", "union_delta",
           "certified_tolerance"]

QUANTITIES: tuple[str, ...] = ("reflectance", "transmittance", "absorptance")
"""The per-reading quantities a functional may weigh: each a fate's share of the rays."""


@dataclass(frozen=True)
class Functional:
    """
    L = Σₖ wₖ q(λₖ): ``weights`` wₖ at ``wavelengths`` λₖ (nm) of ``quantity`` q.

    Attributes
    ----------
    name : str
        Short name (a variable name of the result: ``X``, ``band_B04``, ``fapar``).
    wavelengths : ndarray
        λₖ in nm, increasing.
    weights : ndarray
        wₖ (any sign); L is in the units of Σₖ wₖ·q.
    quantity : str
        One of :data:`QUANTITIES`.
    units : str
        Units of L (``"1"`` for a share, ``""`` for CIE tristimulus values).
    long_name : str
        What L is, in words.
    """

    name: str
    wavelengths: np.ndarray
    weights: np.ndarray
    quantity: str = "reflectance"
    units: str = "1"
    long_name: str = ""
    notes: tuple[str, ...] = field(default=())

    def __post_init__(self) -> None:
        wavelengths = np.asarray(self.wavelengths, dtype=np.float64)
        weights = np.asarray(self.weights, dtype=np.float64)
        if wavelengths.ndim != 1 or wavelengths.shape != weights.shape or not len(wavelengths):
            raise ValueError(f"functional {self.name}: wavelengths and weights must be 1-d of one length "
                             f"(got {wavelengths.shape} and {weights.shape})")
        if not np.all(np.isfinite(weights)) or not np.all(np.isfinite(wavelengths)):
            raise ValueError(f"functional {self.name}: wavelengths and weights must be finite")
        if self.quantity not in QUANTITIES:
            raise ValueError(f"quantity must be one of {', '.join(QUANTITIES)} (got {self.quantity!r})")
        object.__setattr__(self, "wavelengths", wavelengths)
        object.__setattr__(self, "weights", weights)

    @property
    def total_weight(self) -> float:
        """Σₖ |wₖ|: the functional's range, and the scale of its cost."""

        return float(np.abs(self.weights).sum())

    def value(self, values: np.ndarray) -> float:
        """L of per-wavelength values (one per :attr:`wavelengths`)."""

        return float(np.dot(self.weights, np.asarray(values, dtype=np.float64)))

    def at(self, wavelengths: np.ndarray) -> np.ndarray:
        """The weights laid out on ``wavelengths`` (a superset of :attr:`wavelengths`; zero elsewhere)."""

        grid = np.asarray(wavelengths, dtype=np.float64)
        index = np.searchsorted(grid, self.wavelengths)
        if np.any(index >= len(grid)) or not np.allclose(grid[np.minimum(index, len(grid) - 1)], self.wavelengths):
            raise ValueError(f"functional {self.name}: its wavelengths are not all on the grid")
        out = np.zeros(len(grid))
        np.add.at(out, index, self.weights)
        return out


def hoeffding_tolerance(weights: np.ndarray, rays: np.ndarray, delta: float, shared: bool = False) -> float:
    """
    The t of eq. (1) at ``delta``: |L̂ − L| < t with probability ≥ 1 − δ for readings of
    ``rays`` Nₖ (independent), or one shared set of N rays (``shared``). A weight on a
    reading of no rays gives ``inf``.
    """

    weights, rays = np.asarray(weights, dtype=np.float64), np.asarray(rays, dtype=np.float64)
    if not 0 < delta < 1:
        raise ValueError(f"delta must lie in (0, 1) (got {delta!r})")
    used = weights != 0
    if np.any(rays[used] <= 0):
        return math.inf
    if shared:
        spread = float(weights.sum()) ** 2 / float(rays[used].min()) if used.any() else 0.0
    else:
        spread = float(np.sum(weights[used] ** 2 / rays[used]))
    return math.sqrt(spread * math.log(2.0 / delta) / 2.0)


def allocate(weights: np.ndarray, tolerance: float, delta: float) -> np.ndarray:
    """
    Rays per reading Nₖ = ⌈c·|wₖ|⌉ with c = Σ|w|·ln(2/δ)/(2t²): the fewest rays in all for
    which eq. (1) gives |L̂ − L| < ``tolerance`` at ``delta`` (zero rays where wₖ = 0).
    """

    weights = np.abs(np.asarray(weights, dtype=np.float64))
    if not tolerance > 0 or not math.isfinite(tolerance):
        raise ValueError(f"tolerance must be a positive number (got {tolerance!r})")
    if not 0 < delta < 1:
        raise ValueError(f"delta must lie in (0, 1) (got {delta!r})")
    scale = weights.sum() * math.log(2.0 / delta) / (2.0 * tolerance ** 2)
    return np.ceil(scale * weights).astype(np.int64)


def union_delta(delta: float, statements: int) -> float:
    """δ of each of ``statements`` statements made together at ``delta`` (Bonferroni: δ/m)."""

    if statements < 1:
        raise ValueError(f"statements must be at least 1 (got {statements})")
    return delta / statements


def certified_tolerance(functional: Functional, rays: np.ndarray, delta: float, rounding: np.ndarray | None = None,
                        shared: bool = False) -> float:
    """
    The tolerance of ``functional`` from the rays spent (``rays`` per wavelength of the
    functional) at ``delta``: eq. (1), plus Σₖ |wₖ|·(rounding bias)ₖ when given.
    """

    t = hoeffding_tolerance(functional.weights, rays, delta, shared=shared)
    if rounding is not None:
        t += float(np.sum(np.abs(functional.weights) * np.asarray(rounding, dtype=np.float64)))
    return t


def allocate_jointly(weights: np.ndarray, tolerances: np.ndarray, delta: float, iterations: int = 200) -> np.ndarray:
    """
    Rays per reading for several functionals on one grid (``weights`` shape (m, n)), each
    j within ``tolerances[j]`` at ``delta`` by eq. (1): the fewest rays in all, found as
    the minimum of Σₖ Nₖ under Σₖ wⱼₖ²/Nₖ ≤ vⱼ = 2tⱼ²/ln(2/δ) (convex; its optimum has
    Nₖ = √(Σⱼ λⱼ wⱼₖ²), the λⱼ found by a multiplicative fixed-point iteration) and then
    scaled up until every constraint holds — so the result is feasible whatever the
    iteration reached. One functional: :func:`allocate`'s Nₖ ∝ |wₖ|.
    """

    weights = np.atleast_2d(np.asarray(weights, dtype=np.float64))
    tolerances = np.asarray(tolerances, dtype=np.float64)
    if np.any(~(tolerances > 0)) or not np.all(np.isfinite(tolerances)):
        raise ValueError(f"tolerances must be positive numbers (got {tolerances.tolist()})")
    if len(weights) == 1:
        return allocate(weights[0], float(tolerances[0]), delta)
    limits = 2 * tolerances ** 2 / math.log(2.0 / delta)
    squares = weights ** 2
    used = squares.sum(axis=0) > 0
    lam = 1.0 / limits

    def rays_of(lam: np.ndarray) -> np.ndarray:
        return np.sqrt(lam @ squares)

    for _ in range(iterations):
        rays = rays_of(lam)
        spread = (squares[:, used] / rays[used]).sum(axis=1)
        lam = lam * (spread / limits) ** 2
        lam = lam / lam.max()
    rays = rays_of(lam)
    spread = (squares[:, used] / rays[used]).sum(axis=1)
    rays = rays * float(np.max(spread / limits))  # every constraint holds (the tightest exactly)
    return np.where(used, np.ceil(rays), 0).astype(np.int64)
