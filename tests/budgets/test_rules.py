"""Tests of virtspec_mi.budgets.rules: the ray-budget rules as objects (one table, dispatched one way)."""

from __future__ import annotations

import ast
import math
from pathlib import Path

import numpy as np
import pytest

from virtspec_mi.budgets import bins as gb
from virtspec_mi.budgets import bounds, rules, twostage
from virtspec_mi.budgets.rules import BUDGETS
from virtspec_mi.settings import Settings

from source_trees import parse

MU, DELTA = 0.005, 0.01


def test_every_rule_is_one_entry_and_the_setting_names_them():
    assert list(BUDGETS) == ["hoeffding", "chebyshev", "exact", "two-stage"]
    assert [name for name, budget in BUDGETS.items() if budget.adaptive] == ["two-stage"]
    for name in BUDGETS:
        assert Settings(bound=name).budget is BUDGETS[name]


@pytest.mark.parametrize("name, rays", [("hoeffding", 105_967), ("chebyshev", 1_000_000), ("exact", 66_501)])
def test_a_fixed_rule_certifies_mu_at_its_rays_and_no_less(name, rays):
    budget = BUDGETS[name]
    assert budget.rays(MU, DELTA) == rays
    assert budget.certified(rays, DELTA, MU) <= MU
    fewer = budget.certified(rays // 10, DELTA, MU)
    assert fewer > MU and fewer == budget.tolerance(rays // 10, DELTA)
    assert Settings(bound=name).most_rays_per_reading == rays


def test_closed_form_tolerances_are_the_paper_inverses():
    assert BUDGETS["hoeffding"].tolerance(1000, DELTA) == pytest.approx(math.sqrt(math.log(2 / DELTA) / 2000))
    assert BUDGETS["chebyshev"].tolerance(1000, DELTA) == pytest.approx(1 / (2 * math.sqrt(1000 * DELTA)))


@pytest.mark.parametrize("rays", [1, 50, 1000, 20_000])
def test_exact_tolerance_is_the_smallest_certified_mu(rays):
    mu = bounds.exact_mu(rays, DELTA)
    assert mu <= bounds.hoeffding_mu(rays, DELTA)
    if mu < 0.5:
        assert bounds.max_miss_probability(rays, mu) <= DELTA
        assert bounds.max_miss_probability(rays, mu * (1 - 1e-4)) > DELTA


def test_exact_tolerance_above_the_bisection_size_is_hoeffding_but_mu_when_the_rule_sized_it():
    assert bounds.exact_mu(100_000, DELTA) == bounds.hoeffding_mu(100_000, DELTA)
    assert BUDGETS["exact"].certified(66_501, DELTA, MU) == MU


def test_two_stage_sizes_from_a_pilot_and_reserves_its_largest_spend():
    budget = BUDGETS["two-stage"]
    with pytest.raises(ValueError, match="sizes each reading from a pilot"):
        budget.rays(MU, DELTA)
    settings = Settings(bound="two-stage")
    assert settings.adaptive and settings.pilot_rays_per_reading == 2000
    assert settings.most_rays_per_reading == bounds.hoeffding_rays(MU, DELTA - DELTA / 10)
    assert budget.tolerance(1000, DELTA) == bounds.exact_mu(1000, DELTA)
    assert not Settings(bound="two-stage", rays=1000).adaptive


# --- one table of rules, dispatched one way (issue 21) -------------------------------------------


def test_every_bound_row_has_the_interface_and_gives_its_bounds_number():
    formulas = {"hoeffding": bounds.hoeffding_rays, "chebyshev": bounds.chebyshev_rays, "exact": bounds.exact_rays}
    for name, rule in BUDGETS.items():
        assert isinstance(rule, rules.RayBudget) and rule.name == name and rule.description
        assert isinstance(rule.adaptive, bool)
        assert rule.spend(0.05, 0.2)  # what format_budgets shows
        assert rule.tolerance(461, 0.2) == pytest.approx(rule.certified(461, 0.2, 1e-3))  # too few rays: the tolerance
        if rule.adaptive:
            with pytest.raises(ValueError, match="sizes each reading from a pilot"):
                rule.rays(MU, DELTA)
        else:
            for mu, delta in [(MU, DELTA), (0.05, 0.2), (0.02, 0.001)]:
                assert rule.rays(mu, delta) == formulas[name](mu, delta)


def test_every_guarantee_row_has_the_interface_and_gives_its_bins_number():
    formulas = {"union": lambda mu, delta, k: gb.union_rays(mu, delta, k),
                "union-exact": lambda mu, delta, k: gb.union_exact_rays(mu, delta, k),
                "dkw": lambda mu, delta, k: gb.dkw_rays(mu, delta),
                "relative": lambda mu, delta, k: gb.relative_rays(0.5, 0.05, delta, k, 0.01)}
    assert list(rules.GUARANTEES) == list(formulas)
    rays = np.array([[1000, 53_368], [10**6, 3]])
    for name, rule in rules.GUARANTEES.items():
        assert isinstance(rule, rules.Guarantee) and rule.name == name and rule.description
        assert rules.guarantee_of(name) is rule
        for mu, delta, k in [(0.01, 0.01, 216), (0.02, 0.05, 40), (0.005, 0.01, 1296)]:
            n = rule.rays(mu, delta, k, relative=0.5, floor=0.05, smallest_solid_angle=0.01)
            options = (0.5, 0.05) if rule.needs else (None, None)  # relative_tolerance, brdf_floor: where needed
            assert n == formulas[name](mu, delta, k) and n == rules.gonio_rays(name, mu, delta, k, *options, 0.01)
            certified = rule.certified(rays, delta, mu, k)
            assert certified.shape == rays.shape and np.all(certified <= gb.bins_mu(rays, delta, k))
            target = rule.target(mu, k, 0.5, 0.05)
            assert target and (f"K = {k}" in target or name == "dkw")
        assert rule.sized == f"sized by guarantee={name}" and "union bound over K" in rule.union_words


def test_two_stage_applies_or_is_refused_with_its_reason_by_the_row():
    for name, rule in rules.GUARANTEES.items():
        if rule.refusal:
            with pytest.raises(ValueError, match=f"cannot size guarantee '{name}'"):
                rule.stage_two(216)
        else:  # every bin fraction at delta/K: the union bound
            assert rule.stage_two(216) == rules.Columns("every bin fraction", 216)
    assert [name for name, rule in rules.GUARANTEES.items() if not rule.refusal] == ["union", "union-exact"]
    assert rules.quantity_columns(False).share == 1 and rules.quantity_columns(True).share == 2
    assert rules.DETECTOR_COLUMNS.share == 2  # each sphere configuration at delta/2
    with pytest.raises(ValueError, match="rays were given"):
        rules.RAYS_GIVEN.stage_two(216)


def test_a_reading_with_rays_given_carries_the_rays_given_row():
    given = rules.guarantee_of("rays")
    assert given is rules.RAYS_GIVEN and "rays" not in rules.GUARANTEES  # not a choice of guarantee=
    assert given.target(0.01, 216, None, None) is None and given.sized == "rays given"
    rays = np.array([1000, 10**6])
    assert np.array_equal(given.certified(rays, 0.01, 0.01, 216), gb.bins_mu(rays, 0.01, 216))
    with pytest.raises(ValueError, match="given"):
        given.rays(0.01, 0.01, 216)


def test_the_exact_union_states_mu_where_its_rule_sized_the_reading():
    rule = rules.GUARANTEES["union-exact"]
    n = rule.rays(0.005, 0.01, 1296)
    assert rule.certified(n, 0.01, 0.005, 1296) == 0.005
    assert rules.GUARANTEES["union"].certified(n, 0.01, 0.005, 1296) > 0.005  # the union's mu for fewer rays


def _compared_names(tree: ast.AST, names: set[str]) -> list[int]:
    """Lines of ``tree`` comparing something with a string that names a rule (``x == "union"``, ``in (...)``)."""

    lines = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Compare):
            operands = [node.left, *node.comparators]
            literals = [e for o in operands for e in (o.elts if isinstance(o, (ast.Tuple, ast.List, ast.Set)) else [o])]
            if any(isinstance(e, ast.Constant) and e.value in names for e in literals):
                lines.append(node.lineno)
    return lines


def test_no_module_compares_rule_names():
    """Dispatch is by object: nothing in the package compares a rule's name (the rule table looks rows up by it)."""

    names = set(BUDGETS) | set(rules.GUARANTEES)
    package = Path(rules.__file__).resolve().parents[1]
    found = {}
    for path in sorted(package.rglob("*.py")):
        lines = _compared_names(parse(path.read_text()), names)
        if lines:
            found[str(path.relative_to(package))] = lines
    assert found == {}
    assert _compared_names(parse('if guarantee == "union": pass'), names) == [1]  # the check sees one


def test_format_budgets_shows_every_row_with_its_numbers():
    text = rules.format_budgets(MU, [0.001, 0.01, 0.1])
    header = text.splitlines()[1].split()
    assert header == ["delta", *BUDGETS]
    row = {line.split()[0]: line for line in text.splitlines()[2:5]}
    for delta in (0.001, 0.01, 0.1):
        for rule in BUDGETS.values():
            assert rule.spend(MU, delta) in row[f"{delta:g}"]
    # the numbers themselves: eq. (23)'s 105,967, eq. (15)'s 10^6, the exact rule's 66,501, the two-stage reserve
    assert "105,967" in row["0.01"] and "1,000,000" in row["0.01"] and "66,501" in row["0.01"]
    most = bounds.hoeffding_rays(MU, DELTA - twostage.default_pilot_delta(DELTA))
    assert f"2,000 + at most {most:,}" in row["0.01"]
    assert all(rule.note in text for rule in BUDGETS.values())


def test_format_budgets_loops_over_the_table(monkeypatch):
    class Tenfold(rules.RayBudget):
        name = "tenfold"
        description = "ten times Hoeffding's N"

        def rays(self, mu, delta):
            return 10 * bounds.hoeffding_rays(mu, delta)

    monkeypatch.setitem(BUDGETS, "tenfold", Tenfold())
    text = rules.format_budgets(MU, [DELTA])
    assert "tenfold" in text.splitlines()[1] and "1,059,670" in text.splitlines()[2]


def test_format_budgets_checks_what_a_user_gives():
    with pytest.raises(ValueError, match="mu must satisfy 0 < mu < 0.5"):
        rules.format_budgets(0.7, [DELTA])
    with pytest.raises(ValueError, match="delta must satisfy 0 < delta < 1"):
        rules.format_budgets(MU, [DELTA, 1.5])


# --- validation once, at the boundary -------------------------------------------------------------


@pytest.mark.parametrize("call, message", [
    (lambda: rules.check_gonio_options("maybe", 0.01, 10), "guarantee must be one of union, union-exact, dkw, relative"),
    (lambda: rules.check_gonio_options("relative", 0.01, 10, 0.1), "guarantee 'relative' needs relative_tolerance"),
    (lambda: rules.check_gonio_options("relative", 0.01, 10, 0.5, floor=-1.0),
     "brdf_floor must be a finite BRDF value > 0"),
    (lambda: rules.check_gonio_options("relative", 0.01, 10, relative=2, floor=0.05),
     "relative_tolerance must satisfy 0 < "),
    (lambda: rules.check_gonio_options("union", 0.01, 10, relative=0.5),
     "relative_tolerance applies only with guarantee='relative'"),
    (lambda: rules.check_gonio_options("union", 3e-308, 10), r"delta/K must satisfy 0 < delta/K < 1 and be at least"),
])
def test_the_goniophotometer_options_are_checked_where_they_enter(call, message):
    with pytest.raises(ValueError, match=message):
        call()


def test_checked_options_come_back_as_numbers():
    rule, relative, floor = rules.check_gonio_options("relative", 0.01, 10, "0.5", "0.05")
    assert rule is rules.GUARANTEES["relative"] and (relative, floor) == (0.5, 0.05)
    assert rules.check_gonio_options("dkw", 0.01, 10)[1:] == (None, None)


def test_below_the_boundary_nothing_is_checked_again(monkeypatch):
    """Settings validate once; the rules, the bins' formulas and the two-stage sizing trust their values."""

    from virtspec_mi.base import checks

    settings = {name: Settings(bound=name, mu=0.05, delta=0.2) for name in BUDGETS}
    calls = []
    monkeypatch.setattr(checks, "number", lambda name, value: calls.append(name) or float(value))
    for s in settings.values():
        s.most_rays_per_reading, s.most_rays_spent_per_reading, s.budget.certified(1000, s.delta, s.mu)
        if not s.adaptive:
            s.budget.rays(s.mu, s.quantity_delta), s.budget.tolerance(1000, s.delta)
    for rule in rules.GUARANTEES.values():
        rule.rays(0.05, 0.2, 40, relative=0.5, floor=0.05, smallest_solid_angle=0.01)
        rule.certified(np.array([500, 5000]), 0.2, 0.05, 40)
    gb.brdf_intervals(np.array([0, 3, 40]), 400, np.array([0.1, 0.2, 0.3]), 0.2, 3)
    twostage.stage_two_rays([[30, 170, 0], [0, 0, 200]], 200, 0.05, 0.2, 0.02)
    assert calls == []
    bounds.hoeffding_rays(0.05, 0.2)  # a public entry checks (once per argument)
    assert calls == ["mu", "delta"]
