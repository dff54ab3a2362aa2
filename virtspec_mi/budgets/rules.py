"""
Ray budgets as objects: one entry per rule
==========================================

:data:`BUDGETS` maps each rule's name (the ``bound`` setting) to an object that knows
everything the rest of the package asks of a rule — colour-science's ``method=``
dispatch is the model, so no module compares rule names:

- :meth:`RayBudget.rays` — rays per reading for (μ, δ) (fixed rules);
- :meth:`RayBudget.tolerance` — the μ that N rays guarantee at δ under this rule (the
  certificate a reading of N rays may state);
- :attr:`RayBudget.adaptive` — whether each reading is sized by a pilot batch;
- :meth:`RayBudget.most_rays` — the largest number of rays one reading may trace in
  one batch (the key range a sweep reserves per reading).

=============  ==========================================  =====================================
name           rays for (μ, δ)                             tolerance of N rays at δ
=============  ==========================================  =====================================
``hoeffding``  ⌈ln(2/δ)/(2μ²)⌉, eq. (23)                   √(ln(2/δ)/(2N)), eq. (19)
``chebyshev``  ⌈1/(4μ²δ)⌉, eq. (15)                        1/(2√(Nδ)), eq. (14)
``exact``      smallest N certified by the binomial law    its exact inverse (:func:`exact_mu`)
``two-stage``  pilot n₁, then N₂ sized from the pilot      μ for its own N₂; ``exact`` for a given N
=============  ==========================================  =====================================

References
----------
Baranoski et al. (2001), eqs. (14), (15), (19), (23); anchors.md §3 (exact and
two-stage rules).
"""

from __future__ import annotations

from typing import Any, Sequence

from virtspec_mi.budgets import twostage
from virtspec_mi.budgets.bounds import (
    EXACT_MU_MAX_RAYS,
    chebyshev_mu,
    chebyshev_rays,
    exact_mu,
    exact_rays,
    hoeffding_mu,
    hoeffding_rays,
)

__all__ = ["RayBudget", "Hoeffding", "Chebyshev", "Exact", "TwoStage", "BUDGETS", "format_budgets"]


class RayBudget:
    """A fixed ray-budget rule: every reading gets :meth:`rays` rays."""

    name: str = ""
    description: str = ""
    """One line: the rule and its equation (CLI help, summaries)."""
    adaptive: bool = False
    """True when each reading is sized by its own pilot batch."""

    def rays(self, mu: float, delta: float) -> int:
        """Rays per reading that certify |m/N − ρ| < μ with probability ≥ 1 − δ."""

        raise NotImplementedError

    def tolerance(self, rays: int, delta: float) -> float:
        """The μ that ``rays`` rays guarantee at δ under this rule."""

        raise NotImplementedError

    def certified(self, rays: int, delta: float, mu: float) -> float:
        """
        The tolerance a reading of ``rays`` rays may state at δ when μ was asked for: μ
        itself where the rule certifies μ for ``rays`` (N ≥ the rule's N for (μ, δ); every
        rule here certifies N and all larger N), else :meth:`tolerance` — and never more
        than :meth:`tolerance`.
        """

        tolerance = self.tolerance(rays, delta)
        if tolerance <= mu:
            return tolerance
        try:
            needed = self.rays(mu, delta)
        except ValueError:  # the rule's N is beyond any float (mu ~ 1e-300): these rays are fewer
            return tolerance
        return mu if rays >= needed else tolerance

    def most_rays(self, settings: Any) -> int:
        """The most rays one reading of ``settings`` may trace in one batch."""

        return self.rays(settings.mu, settings.quantity_delta)

    @staticmethod
    def default_pilot_rays(mu: float) -> int:
        """Two-stage pilot size n₁ when none is given: ⌈10/μ⌉ (:mod:`virtspec_mi.budgets.twostage`)."""

        return twostage.default_pilot_rays(mu)

    @staticmethod
    def default_pilot_delta(delta: float) -> float:
        """Two-stage pilot failure probability δ₁ when none is given: δ/10."""

        return twostage.default_pilot_delta(delta)

    def __repr__(self) -> str:
        return f"{type(self).__name__}()"


class Hoeffding(RayBudget):
    """The exponential Chebyshev (Hoeffding) bound, eq. (23): the default."""

    name = "hoeffding"
    description = "N = ceil(ln(2/delta)/(2 mu^2)), eq. (23)"

    def rays(self, mu: float, delta: float) -> int:
        return hoeffding_rays(mu, delta)

    def tolerance(self, rays: int, delta: float) -> float:
        return hoeffding_mu(rays, delta)


class Chebyshev(RayBudget):
    """The ordinary Chebyshev bound, eq. (15)."""

    name = "chebyshev"
    description = "N = ceil(1/(4 mu^2 delta)), eq. (15)"

    def rays(self, mu: float, delta: float) -> int:
        return chebyshev_rays(mu, delta)

    def tolerance(self, rays: int, delta: float) -> float:
        return chebyshev_mu(rays, delta)


class Exact(RayBudget):
    """The smallest N certified by the exact binomial law (:func:`virtspec_mi.budgets.bounds.exact_rays`)."""

    name = "exact"
    description = "the smallest N the exact binomial law certifies"

    def rays(self, mu: float, delta: float) -> int:
        return exact_rays(mu, delta)

    def tolerance(self, rays: int, delta: float) -> float:
        return exact_mu(int(rays), delta)

    def certified(self, rays: int, delta: float, mu: float) -> float:
        # Below EXACT_MU_MAX_RAYS the tolerance is the exact inverse already: no search for N.
        if rays <= EXACT_MU_MAX_RAYS:
            return self.tolerance(rays, delta)
        return super().certified(rays, delta, mu)


class TwoStage(RayBudget):
    """
    A pilot of n₁ rays, then a fresh batch of N₂ rays sized by the exact rule over the
    pilot's interval (:mod:`virtspec_mi.budgets.twostage`): each reading sized so is certified
    at μ. Given a fixed N (``rays=``) it states the exact rule's tolerance, on which its
    sizing is built.
    """

    name = "two-stage"
    description = "a pilot of pilot_rays, then a fresh batch sized per reading by the exact rule"
    adaptive = True
    fixed = Exact()

    def tolerance(self, rays: int, delta: float) -> float:
        return self.fixed.tolerance(rays, delta)

    def certified(self, rays: int, delta: float, mu: float) -> float:
        return self.fixed.certified(rays, delta, mu)

    def rays(self, mu: float, delta: float) -> int:
        raise ValueError("bound 'two-stage' sizes each reading from a pilot batch (virtspec_mi.budgets.twostage); "
                         "give rays= or use a fixed rule: hoeffding, chebyshev or exact")

    def most_rays(self, settings: Any) -> int:
        """
        The larger of the pilot n₁ and Hoeffding's N at the second stage's δ − δ₁ (per
        quantity): the exact rule over any interval of ρ never needs more.
        """

        stage_two = self.most_second_rays(settings.mu, settings.delta, settings.pilot_delta_value, settings.joint)
        return max(settings.pilot_rays_per_reading, stage_two)

    @staticmethod
    def most_second_rays(mu: float, delta: float, pilot_delta: float, joint: bool = False) -> int:
        """The most rays a second batch can get: Hoeffding's N at (δ − δ₁), per quantity."""

        return hoeffding_rays(mu, (delta - pilot_delta) / (2 if joint else 1))

BUDGETS: dict[str, RayBudget] = {budget.name: budget for budget in (Hoeffding(), Chebyshev(), Exact(), TwoStage())}
"""Every ray-budget rule by name; ``"hoeffding"`` (eq. 23) is the default."""


def format_budgets(mu: float, deltas: Sequence[float]) -> str:
    """
    Rays per reading under every rule of :data:`BUDGETS` at μ for each δ, as text: the
    fixed rules' N, and for ``two-stage`` its pilot n₁ plus the most rays its second
    batch can take (Hoeffding's N at δ − δ₁); what it spends on average depends on ρ
    (:func:`virtspec_mi.budgets.twostage.two_stage_law`; notebook 01 tabulates it).
    """

    two_stage = BUDGETS["two-stage"]
    header = f"{'delta':>8}" + "".join(f"  {name:>{width}}" for name, width in
                                       (("hoeffding", 10), ("chebyshev", 12), ("exact", 10), ("two-stage", 22)))
    lines = [f"Rays per reading under each rule (bound=...), mu = {mu:g}", header]
    for delta in deltas:
        pilot = two_stage.default_pilot_rays(mu)
        most = two_stage.most_second_rays(mu, delta, two_stage.default_pilot_delta(delta))
        lines.append(f"{delta:>8g}  {hoeffding_rays(mu, delta):>10,}  {chebyshev_rays(mu, delta):>12,}  "
                     f"{exact_rays(mu, delta):>10,}  {f'{pilot:,} + at most {most:,}':>22}")
    lines.append("two-stage: a pilot, then a second batch sized per reading from the pilot's interval "
                 "(on average far fewer rays than the most, e.g. 19,442 at rho = 0.05 for mu = 0.005, "
                 "delta = 0.01)")
    return "\n".join(lines)