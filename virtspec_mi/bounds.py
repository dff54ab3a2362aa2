"""
Ray budgets: how many rays certify a reading
============================================

A reading counts m of N rays; each ray is a Bernoulli trial with success probability
ρ (the reflectance, or transmittance). The paper certifies ``|m/N − ρ| < μ`` with
probability at least ``1 − δ`` by choosing N from a tail bound that needs no
knowledge of ρ:

- :func:`chebyshev_rays`: the ordinary Chebyshev bound, ``N = ⌈1/(4μ²δ)⌉``, eq. (15);
- :func:`hoeffding_rays`: the exponential Chebyshev (Hoeffding) bound,
  ``N = ⌈ln(2/δ)/(2μ²)⌉``, eq. (20)/(23) — the default of virtspec-mi.

The inverses (:func:`chebyshev_mu`, :func:`hoeffding_mu`) give the tolerance that N
rays guarantee at δ, and :func:`miss_probability` is the *exact* probability that a
reading of N rays misses ρ by μ or more (used to test the instrument's statistics).

References
----------
Baranoski, G.V.G., Rokne, J.G., Xu, G. (2001). Virtual spectrophotometric
measurements for biologically and physically based rendering. The Visual Computer
17, 506–518: eqs. (10)–(23) and Table 1.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable, Sequence

import numpy as np

from virtspec_mi.settings import check_delta, check_mu, check_rays

__all__ = [
    "BOUNDS",
    "chebyshev_rays",
    "hoeffding_rays",
    "chebyshev_mu",
    "hoeffding_mu",
    "rays_for_bound",
    "miss_probability",
    "Table1Row",
    "table_1",
    "format_table_1",
]


def chebyshev_rays(mu: float, delta: float) -> int:
    """
    Rays the ordinary Chebyshev inequality needs: ``⌈1/(4μ²δ)⌉``.

    References
    ----------
    Baranoski et al. (2001), eq. (15).
    """

    check_mu(mu)
    check_delta(delta)
    return _ceil(1.0 / (4.0 * mu * mu * delta))


def hoeffding_rays(mu: float, delta: float) -> int:
    """
    Rays the exponential Chebyshev (Hoeffding) inequality needs: ``⌈ln(2/δ)/(2μ²)⌉``.

    References
    ----------
    Baranoski et al. (2001), eqs. (20) and (23); μ = 0.005, δ = 0.01 gives 105,967.
    """

    check_mu(mu)
    check_delta(delta)
    return _ceil(math.log(2.0 / delta) / (2.0 * mu * mu))


def chebyshev_mu(rays: int, delta: float) -> float:
    """Tolerance μ that ``rays`` rays guarantee at δ under eq. (14): ``μ = 1/(2√(Nδ))``."""

    check_rays(rays, math.inf)
    check_delta(delta)
    return 1.0 / (2.0 * math.sqrt(rays * delta))


def hoeffding_mu(rays: int, delta: float) -> float:
    """Tolerance μ that ``rays`` rays guarantee at δ under eq. (19): ``μ = √(ln(2/δ)/(2N))``."""

    check_rays(rays, math.inf)
    check_delta(delta)
    return math.sqrt(math.log(2.0 / delta) / (2.0 * rays))


BOUNDS: dict[str, Callable[[float, float], int]] = {
    "hoeffding": hoeffding_rays,
    "chebyshev": chebyshev_rays,
}
"""Ray-budget rules by name; ``"hoeffding"`` (eq. 23) is the default."""


def rays_for_bound(bound: str, mu: float, delta: float) -> int:
    """Rays per reading under the named rule of :data:`BOUNDS`."""

    if bound not in BOUNDS:
        raise ValueError(f"bound must be one of {sorted(BOUNDS)} (got {bound!r})")
    return BOUNDS[bound](mu, delta)


def miss_probability(rays: int, rho: float, mu: float) -> float:
    """
    Exact probability that a reading of ``rays`` rays misses ρ by μ or more.

    ``P(|m/N − ρ| ≥ μ)`` with ``m ~ Binomial(N, ρ)``: the quantity the bounds of
    eqs. (10) and (17) majorise. The statistical tests compare observed miss counts
    with this number instead of with δ (a "≤ δ" check has almost no power).
    """

    from scipy import stats

    check_rays(rays, math.inf)
    check_mu(mu)
    n = int(rays)
    # m ≤ N(ρ − μ) or m ≥ N(ρ + μ); the 1e-9 guards the lattice points against rounding.
    low = math.floor(n * (rho - mu) + 1e-9)
    high = math.ceil(n * (rho + mu) - 1e-9)
    lower = stats.binom.cdf(low, n, rho) if low >= 0 else 0.0
    upper = stats.binom.sf(high - 1, n, rho) if high <= n else 0.0
    return float(lower + upper)


@dataclass(frozen=True)
class Table1Row:
    """One row of the paper's Table 1: rays under both bounds at one δ."""

    delta: float
    chebyshev_rays: int
    hoeffding_rays: int

    @property
    def chebyshev_log10(self) -> float:
        return math.log10(self.chebyshev_rays)

    @property
    def hoeffding_log10(self) -> float:
        return math.log10(self.hoeffding_rays)


def table_1(mu: float = 0.005, deltas: Sequence[float] = (0.001, 0.01, 0.1)) -> list[Table1Row]:
    """
    The paper's Table 1: rays under eq. (15) and eq. (23) for each δ at μ.

    References
    ----------
    Baranoski et al. (2001), Table 1.
    """

    return [Table1Row(d, chebyshev_rays(mu, d), hoeffding_rays(mu, d)) for d in deltas]


# Table 1 as printed in the paper (δ → ordinary, exponential log10 N), to flag differences.
_PAPER_TABLE_1 = {0.001: (7.0, 5.18), 0.01: (6.0, 5.02), 0.1: (5.0, 4.77)}


def format_table_1(mu: float = 0.005, deltas: Sequence[float] = (0.001, 0.01, 0.1)) -> str:
    """Table 1 as text: N and log10 N to two decimals, with the paper's value where it differs."""

    lines = [
        f"Rays per reading for |m/N - rho| < mu = {mu:g} with probability >= 1 - delta",
        f"{'delta':>8}  {'Chebyshev N (15)':>17} {'log10':>6}  {'Hoeffding N (23)':>17} {'log10':>6}  note",
    ]
    notes = []
    for row in table_1(mu, deltas):
        paper = _PAPER_TABLE_1.get(row.delta) if mu == 0.005 else None
        note = ""
        if paper is not None:
            diffs = [
                f"paper {p:.2f}"
                for p, v in zip(paper, (row.chebyshev_log10, row.hoeffding_log10))
                if f"{p:.2f}" != f"{v:.2f}"
            ]
            if diffs:
                note = "; ".join(diffs) + " (truncated, not rounded)"
                notes.append(row.delta)
        lines.append(
            f"{row.delta:>8g}  {row.chebyshev_rays:>17,d} {row.chebyshev_log10:>6.2f}  "
            f"{row.hoeffding_rays:>17,d} {row.hoeffding_log10:>6.2f}  {note}"
        )
    if notes:
        lines.append(
            "The paper prints log10 N truncated to two decimals; the values here are rounded."
        )
    return "\n".join(lines)


def _ceil(x: float) -> int:
    """⌈x⌉ that forgives floating-point noise just above an integer (e.g. 1e6 + 1e-10)."""

    nearest = round(x)
    return int(nearest) if abs(x - nearest) <= 1e-9 * max(1.0, abs(x)) else int(np.ceil(x))
