"""
Ray budgets as objects: one table of rules, dispatched one way
==============================================================

Every rule the package sizes a reading by is one object here, and everything the rest
of the package asks of a rule is asked of that object — colour-science's ``method=``
dispatch is the model, so no module compares rule names.

:data:`BUDGETS` — the ``bound`` setting: how many rays certify one proportion (a
reflectance, a transmittance, a detector fraction) within μ at δ.

- :meth:`RayBudget.rays` — rays per reading for (μ, δ) (fixed rules);
- :meth:`RayBudget.tolerance` — the μ that N rays guarantee at δ under this rule;
- :meth:`RayBudget.certified` — the μ a reading of N rays may state when μ was asked;
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

:data:`GUARANTEES` — the goniophotometer's ``guarantee`` setting: what a binned reading
of K bins is sized to certify (:mod:`virtspec_mi.budgets.bins` derives each).

- :meth:`Guarantee.rays` — rays per reading for (μ, δ, K) (or ε above a floor);
- :meth:`Guarantee.certified` — the μ every bin fraction carries at once for N rays;
- :meth:`Guarantee.stage_two` — the columns a two-stage pilot sizes the reading from,
  or ``ValueError`` with the reason a pilot cannot (:attr:`Guarantee.refusal`).

===============  =====================================  ====================================
name             rays for (μ, δ, K)                     two-stage pilot
===============  =====================================  ====================================
``union``        Hoeffding at δ/K, ⌈ln(2K/δ)/(2μ²)⌉     every bin fraction at δ/K
``union-exact``  the exact rule at δ/K                  every bin fraction at δ/K
``dkw``          DKW–Massart, ⌈ln(2/δ)/(2μ²)⌉           refused: a CDF is not a count
``relative``     ⌈3 ln(2K/δ)/(ε² f_floor Ω_min)⌉        refused: sized by the floor
===============  =====================================  ====================================

A reading whose rays were given carries :data:`RAYS_GIVEN` (``guarantee_of("rays")``).
What a hemispherical and a sphere reading certify, for the two-stage pilot, is
:func:`quantity_columns` and :data:`DETECTOR_COLUMNS`.

The rule objects trust their arguments: values are checked once where they enter (the
settings and options dataclasses; the public functions of
:mod:`virtspec_mi.budgets.bounds`; :func:`gonio_rays` and :func:`check_gonio_options`).

References
----------
Baranoski et al. (2001), eqs. (14), (15), (19), (23). Hoeffding, W. (1963), J. Amer.
Statist. Assoc. 58, 13–30. Clopper, C.J., Pearson, E.S. (1934), Biometrika 26, 404–413
(the two-stage pilot's interval). The exact rule and the two-stage sizing are computed
by :mod:`virtspec_mi.budgets.bounds` and :mod:`virtspec_mi.budgets.twostage` (tables:
``tools/budget_tables.py``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

from virtspec_mi.budgets import bins as histogram_bounds
from virtspec_mi.budgets import twostage
from virtspec_mi.budgets.bounds import (
    chebyshev_mu,
    chebyshev_rays,
    exact_certified,
    exact_mu,
    exact_rays,
    hoeffding_mu,
    hoeffding_rays,
    stated_mu,
)
from virtspec_mi.base.checks import (
    check_bins,
    check_brdf_floor,
    check_delta,
    check_mu,
    check_rays_needed,
    check_relative_tolerance,
    shown_value,
    validated,
)

__all__ = [
    "RayBudget",
    "Hoeffding",
    "Chebyshev",
    "Exact",
    "TwoStage",
    "BUDGETS",
    "format_budgets",
    "Columns",
    "quantity_columns",
    "DETECTOR_COLUMNS",
    "Guarantee",
    "Union",
    "UnionExact",
    "DKW",
    "Relative",
    "RaysGiven",
    "GUARANTEES",
    "RAYS_GIVEN",
    "guarantee_of",
    "check_gonio_options",
    "gonio_rays",
]


# -- bound=: the rules of one proportion -------------------------------------------------


class RayBudget:
    """A fixed ray-budget rule: every reading gets :meth:`rays` rays."""

    name: str = ""
    description: str = ""
    """One line: the rule and its equation (CLI help, summaries)."""
    adaptive: bool = False
    """True when each reading is sized by its own pilot batch."""
    note: str = ""
    """What :func:`format_budgets` adds below its table about this rule ("" for nothing)."""

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
        than :meth:`tolerance` (:func:`virtspec_mi.budgets.bounds.stated_mu`).
        """

        return stated_mu(rays, mu, self.tolerance(rays, delta), lambda: self.rays(mu, delta))

    def most_rays(self, settings: Any) -> int:
        """The most rays one reading of ``settings`` may trace in one batch."""

        return self.rays(settings.mu, settings.quantity_delta)

    def spend(self, mu: float, delta: float) -> str:
        """Rays per reading at (μ, δ), as :func:`format_budgets` shows them."""

        return f"{self.rays(mu, delta):,}"

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
        return hoeffding_rays.unchecked(mu, delta)

    def tolerance(self, rays: int, delta: float) -> float:
        return hoeffding_mu.unchecked(rays, delta)


class Chebyshev(RayBudget):
    """The ordinary Chebyshev bound, eq. (15)."""

    name = "chebyshev"
    description = "N = ceil(1/(4 mu^2 delta)), eq. (15)"

    def rays(self, mu: float, delta: float) -> int:
        return chebyshev_rays.unchecked(mu, delta)

    def tolerance(self, rays: int, delta: float) -> float:
        return chebyshev_mu.unchecked(rays, delta)


class Exact(RayBudget):
    """The smallest N certified by the exact binomial law (:func:`virtspec_mi.budgets.bounds.exact_rays`)."""

    name = "exact"
    description = "the smallest N the exact binomial law certifies"

    def rays(self, mu: float, delta: float) -> int:
        return exact_rays.unchecked(mu, delta)

    def tolerance(self, rays: int, delta: float) -> float:
        return exact_mu.unchecked(int(rays), delta)

    def certified(self, rays: int, delta: float, mu: float) -> float:
        return exact_certified(rays, delta, mu)


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
    note = ("two-stage: a pilot, then a second batch sized per reading from the pilot's interval "
            "(on average far fewer rays than the most, e.g. 19,442 at rho = 0.05 for mu = 0.005, delta = 0.01)")
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

    def spend(self, mu: float, delta: float) -> str:
        """The default pilot n₁ and the most rays its second batch can take (Hoeffding's N at δ − δ₁)."""

        pilot = self.default_pilot_rays(mu)
        return f"{pilot:,} + at most {self.most_second_rays(mu, delta, self.default_pilot_delta(delta)):,}"

    @staticmethod
    def most_second_rays(mu: float, delta: float, pilot_delta: float, joint: bool = False) -> int:
        """The most rays a second batch can get: Hoeffding's N at (δ − δ₁), per quantity."""

        return hoeffding_rays.unchecked(mu, (delta - pilot_delta) / (2 if joint else 1))


BUDGETS: dict[str, RayBudget] = {budget.name: budget for budget in (Hoeffding(), Chebyshev(), Exact(), TwoStage())}
"""Every ray-budget rule by name; ``"hoeffding"`` (eq. 23) is the default."""


@validated(mu=check_mu)
def format_budgets(mu: float, deltas: Sequence[float]) -> str:
    """
    Rays per reading under every rule of :data:`BUDGETS` at μ for each δ, as text
    (``virtspec bounds``): each rule's :meth:`RayBudget.spend` — the fixed rules' N, and
    for ``two-stage`` its pilot n₁ plus the most rays its second batch can take; what it
    spends on average depends on ρ (:func:`virtspec_mi.budgets.twostage.two_stage_law`;
    notebook 01 tabulates it) — then each rule's note.
    """

    deltas = [check_delta(delta) for delta in deltas]
    rules = list(BUDGETS.values())
    columns = [[rule.spend(mu, delta) for delta in deltas] for rule in rules]
    widths = [max(len(rule.name), *(len(cell) for cell in cells)) for rule, cells in zip(rules, columns)]
    lines = [f"Rays per reading under each rule (bound=...), mu = {mu:g}",
             f"{'delta':>8}" + "".join(f"  {rule.name:>{width}}" for rule, width in zip(rules, widths))]
    for i, delta in enumerate(deltas):
        lines.append(f"{delta:>8g}" + "".join(f"  {cells[i]:>{width}}" for cells, width in zip(columns, widths)))
    lines += [rule.note for rule in rules if rule.note]
    return "\n".join(lines)


# -- the two-stage pilot's columns ---------------------------------------------------------


@dataclass(frozen=True)
class Columns:
    """
    The certified columns of a reading, from which a two-stage pilot sizes its second
    batch: each column's pilot count gives a Clopper–Pearson interval at δ₁/``share``, its
    N₂ is the exact rule at (δ − δ₁)/``share`` over that interval, and the reading takes the
    largest N₂ (:func:`virtspec_mi.budgets.twostage.stage_two_rays`; ``share`` 1 is its
    marginal sizing, ``share`` equal to the number of columns its ``joint`` one).
    """

    what: str
    """The columns, in words (e.g. ``"every bin fraction"``)."""
    share: int
    """δ is split over this many statements made together (Bonferroni): 1 is each column at δ."""


def quantity_columns(joint: bool) -> Columns:
    """
    A hemispherical reading's columns: reflected, transmitted and absorbed each at δ, or
    with ``joint`` reflected and transmitted together, each at δ/2.
    """

    if joint:
        return Columns("reflected and transmitted, together", 2)
    return Columns("reflected, transmitted and absorbed, each", 1)


DETECTOR_COLUMNS: Columns = Columns("the detector fraction of each configuration (sample, standard)", 2)
"""A sphere reading's columns: the detector fraction of each of its two configurations, each at δ/2."""


# -- guarantee=: what a binned (goniophotometer) reading certifies ---------------------------


class Guarantee:
    """What the N of a goniophotometer reading of K bins is sized to certify (``guarantee``)."""

    name: str = ""
    description: str = ""
    """One line: what it certifies and its N (CLI help, summaries)."""
    bound_words: str = ""
    """The bound in messages: "the union bound" (… for mu = 0.01 needs N = …)."""
    union_words: str = "union bound over K"
    """How the certificate names the bound behind its every-bin-fraction line."""
    needs: str = ""
    """The options it needs beyond μ, δ and K, in words ("" for none)."""
    refusal: str = ""
    """Why a two-stage pilot cannot size it ("": it can, from :meth:`stage_two`)."""

    def rays(self, mu: float, delta: float, bins: int, *, relative: float | None = None, floor: float | None = None,
             smallest_solid_angle: float | None = None) -> int:
        """Rays per reading for (μ, δ) over K bins (or ε above the floor: :class:`Relative`), ≤ 2³² − 1."""

        return check_rays_needed(self._rays(mu, delta, bins), f"{self.bound_words} for mu = {shown_value(mu)}")

    def _rays(self, mu: float, delta: float, bins: int) -> int:
        raise NotImplementedError

    def certified(self, rays: Any, delta: float, mu: float, bins: int) -> Any:
        """
        The μ with |m_k/N − p_k| < μ for every bin at once at δ that ``rays`` rays certify
        (per reading; before the rounding bias and the reading's own certification): the
        smaller of the union μ and twice the DKW μ (:func:`virtspec_mi.budgets.bins.bins_mu`).
        """

        return histogram_bounds.bins_mu(rays, delta, bins)

    def target(self, mu: float, bins: int, relative: float | None, floor: float | None) -> str | None:
        """What N was sized for, in words (``None`` when the rays were given)."""

        raise NotImplementedError

    @property
    def sized(self) -> str:
        """How N came about, in words: "sized by guarantee=union"."""

        return f"sized by guarantee={self.name}"

    def stage_two(self, bins: int) -> Columns:
        """The columns a two-stage pilot sizes a reading of K bins from; ``ValueError`` saying why not."""

        if self.refusal:
            raise ValueError(self.refusal)
        return Columns("every bin fraction", bins)

    def __repr__(self) -> str:
        return f"{type(self).__name__}()"


class Union(Guarantee):
    """Every bin fraction within μ at once: Hoeffding + the union over K (:func:`~virtspec_mi.budgets.bins.union_rays`)."""

    name = "union"
    description = ("every bin fraction |m_k/N - p_k| < mu at once: N = ceil(ln(2K/delta)/(2 mu^2)) "
                   "(Hoeffding + union)")
    bound_words = "the union bound"
    rule_words = "Hoeffding + union"
    """The rule behind each bin's share δ/K, as :meth:`target` names it."""

    def _rays(self, mu: float, delta: float, bins: int) -> int:
        return histogram_bounds.union_rays(mu, delta, bins)

    def target(self, mu: float, bins: int, relative: float | None, floor: float | None) -> str:
        return f"every bin fraction within mu = {mu:g} at once ({self.rule_words} over K = {bins})"


class UnionExact(Union):
    """Every bin fraction within μ at once: the exact rule at δ/K (:func:`~virtspec_mi.budgets.bins.union_exact_rays`)."""

    name = "union-exact"
    description = "every bin fraction at once, exact binomial rule at delta/K per bin (fewer rays)"
    bound_words = "the exact union"
    union_words = "exact-binomial union bound over K"
    rule_words = "exact binomial at delta/K"

    def _rays(self, mu: float, delta: float, bins: int) -> int:
        return histogram_bounds.union_exact_rays(mu, delta, bins)

    def certified(self, rays: Any, delta: float, mu: float, bins: int) -> Any:
        """The exact rule's μ at δ/K (μ itself where N is its N for μ), or the union/DKW μ where smaller."""

        return np.minimum(histogram_bounds.union_exact_mu(rays, delta, bins, mu),
                          histogram_bounds.bins_mu(rays, delta, bins))


class DKW(Guarantee):
    """The CDFs of θo and φo within μ everywhere: DKW–Massart (:func:`~virtspec_mi.budgets.bins.dkw_rays`)."""

    name = "dkw"
    description = "the CDFs of theta_o and phi_o within mu everywhere (DKW-Massart): N = ceil(ln(2/delta)/(2 mu^2))"
    bound_words = "the DKW bound"
    refusal = ("bound 'two-stage' cannot size guarantee 'dkw': it certifies the CDFs of theta_o and phi_o at every "
               "threshold at once, which no pilot interval of bin counts bounds; use guarantee 'union' or "
               "'union-exact', or a fixed bound")

    def _rays(self, mu: float, delta: float, bins: int) -> int:
        return histogram_bounds.dkw_rays(mu, delta)

    def target(self, mu: float, bins: int, relative: float | None, floor: float | None) -> str:
        return f"the CDFs of theta_o and phi_o within mu = {mu:g} (DKW-Massart)"


class Relative(Guarantee):
    """f_k within a relative ε in every bin above a floor (:func:`~virtspec_mi.budgets.bins.relative_rays`)."""

    name = "relative"
    description = "f_k within relative_tolerance for every bin with f_k >= brdf_floor (Chernoff + union)"
    needs = "relative_tolerance (0 < relative_tolerance <= 1) and brdf_floor (> 0, in 1/sr)"
    refusal = ("bound 'two-stage' cannot size guarantee 'relative': its N follows from brdf_floor and the smallest "
               "bin's solid angle, not from counts a pilot could bound; use a fixed bound")

    def rays(self, mu: float, delta: float, bins: int, *, relative: float | None = None, floor: float | None = None,
             smallest_solid_angle: float | None = None) -> int:
        return histogram_bounds.relative_rays(relative, floor, delta, bins, smallest_solid_angle)

    def target(self, mu: float, bins: int, relative: float | None, floor: float | None) -> str:
        return (f"f_k within relative {relative:g} for every bin with f_k >= {floor:g}/sr "
                f"(Chernoff + union over K = {bins})")


class RaysGiven(Guarantee):
    """The rays were given (``rays=``): N was sized for nothing; the spent rays certify what they do."""

    name = "rays"
    description = "rays given"
    refusal = "rays were given: a two-stage pilot sizes nothing (leave rays unset)"

    def rays(self, mu: float, delta: float, bins: int, *, relative: float | None = None, floor: float | None = None,
             smallest_solid_angle: float | None = None) -> int:
        raise ValueError("the rays of this reading were given, not sized by a guarantee")

    def target(self, mu: float, bins: int, relative: float | None, floor: float | None) -> None:
        return None

    @property
    def sized(self) -> str:
        return "rays given"


GUARANTEES: dict[str, Guarantee] = {rule.name: rule for rule in (Union(), UnionExact(), DKW(), Relative())}
"""How a goniophotometer reading may be sized (``guarantee``); ``"union"`` is the default."""

RAYS_GIVEN: Guarantee = RaysGiven()
"""What a goniophotometer reading whose rays were given carries (its ``guarantee`` is ``"rays"``)."""


def guarantee_of(name: str) -> Guarantee:
    """The rule a goniophotometer reading names as its ``guarantee``: a row of :data:`GUARANTEES`, or ``"rays"``."""

    return RAYS_GIVEN if name == RAYS_GIVEN.name else GUARANTEES[name]


def check_gonio_options(guarantee: Any, delta: float, bins: int, relative: Any = None,
                        floor: Any = None) -> tuple[Guarantee, float | None, float | None]:
    """
    The goniophotometer's sizing options, checked once where they enter: ``guarantee``
    (a name of :data:`GUARANTEES`), δ/K (a normal float, as δ), and ``relative`` (ε) and
    ``floor`` where given — both required where the guarantee needs them. ``delta`` and
    ``bins`` are validated already (the settings; the bins). Returns the rule and ε and the
    floor as floats (or ``None``).
    """

    if not isinstance(guarantee, str) or guarantee not in GUARANTEES:
        raise ValueError(f"guarantee must be one of {', '.join(GUARANTEES)} (got {guarantee!r})")
    rule = GUARANTEES[guarantee]
    check_delta(delta / bins, name="delta/K")
    if rule.needs and (relative is None or floor is None):
        raise ValueError(f"guarantee {rule.name!r} needs {rule.needs}")
    given = [name for name, value in (("relative_tolerance", relative), ("brdf_floor", floor)) if value is not None]
    if given and not rule.needs:
        relative_rules = [name for name, row in GUARANTEES.items() if row.needs]
        raise ValueError(f"{given[0]} applies only with guarantee={relative_rules[0]!r} (got guarantee={rule.name!r}); "
                         f"drop {' and '.join(given)}, or set guarantee={relative_rules[0]!r}")
    relative = None if relative is None else check_relative_tolerance(relative)
    floor = None if floor is None else check_brdf_floor(floor)
    return rule, relative, floor


@validated(mu=check_mu, delta=check_delta, bins=check_bins)
def gonio_rays(guarantee: str, mu: float, delta: float, bins: int, relative: float | None = None,
               floor: float | None = None, smallest_solid_angle: float | None = None) -> int:
    """
    Rays per reading for ``guarantee`` (:data:`GUARANTEES`) at μ (or ε and floor) and δ over
    K bins: the checked entry (:func:`check_gonio_options`), then the rule's
    :meth:`Guarantee.rays`.
    """

    rule, relative, floor = check_gonio_options(guarantee, delta, bins, relative, floor)
    return rule.rays(mu, delta, bins, relative=relative, floor=floor, smallest_solid_angle=smallest_solid_angle)
