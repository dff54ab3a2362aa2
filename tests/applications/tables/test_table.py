"""
Tests of :mod:`virtspec_mi.applications.tables.table`: the certified albedo table as a record.

A tiny table is measured once (4 conductor cells and 2 E_avg values at ε = 0.05, about half a
second); its counts are then replaced by exact numbers, so every value, tolerance and
interval below is checked against arithmetic on those counts: Ê = c·hits/N, the certified
tolerance ε + rounded·10⁻⁴/N (NaN where a cell had a violation, and the statement says NOT
CERTIFIED), the Clopper–Pearson interval of :mod:`virtspec_mi.budgets.intervals` at each
cell's δ, the engine's memory order, linear interpolation (exact at nodes and midpoints), and
the files read back. The measured cells against the quadrature are in ``test_albedo.py``.

References
----------
Clopper, C.J., Pearson, E.S. (1934). Biometrika 26, 404–413.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from virtspec_mi.applications.tables.table import AlbedoTable, read_albedo_table
from virtspec_mi.budgets.intervals import clopper_pearson


@pytest.fixture(scope="module")
def measured(mi):
    from virtspec_mi.applications.tables.albedo import albedo_table

    return albedo_table("conductor", engine=None, mu=[1.0, 0.5], alpha=[0.3, 0.8], epsilon=0.05, delta=0.01, seed=3,
                        progress=False)


def counts(reflected, rays=1000, **changes) -> dict[str, np.ndarray]:
    reflected = np.asarray(reflected, dtype=np.int64)
    made = {name: np.zeros(reflected.shape, dtype=np.int64) for name in
            ("transmitted", "rounded_weights", "weight_violations", "invalid_directions", "capped", "pilot_rays",
             "pilot_violations")}
    made.update(rays=np.full(reflected.shape, rays, dtype=np.int64), reflected=reflected,
                interval_delta=np.full(reflected.shape, 0.001))
    made.update({name: np.asarray(value) for name, value in changes.items()})
    return made


@pytest.fixture
def exact(measured):
    """The measured table with exact counts: E = [[0.9, 0.4], [0.8, 0.5]], E_avg = [0.85, 0.45]."""

    return replace(measured, counts=counts([[900, 400], [800, 500]]), average_counts=counts([850, 450]))


def test_dims_cells_and_rays(exact):
    assert exact.dims == ("mu", "alpha") and exact.average_dims == ("alpha",)
    assert exact.cells == 6 and exact.rays == 6000
    assert exact.quantities == ("E",) and exact.order == ("mu", "alpha")


def test_values_are_the_counts_fractions(exact):
    np.testing.assert_allclose(exact.E, [[0.9, 0.4], [0.8, 0.5]])
    np.testing.assert_allclose(exact.E_avg, [0.85, 0.45])
    np.testing.assert_allclose(exact.quantity("E_R"), exact.E)
    np.testing.assert_array_equal(exact.E_T, 0.0)
    scaled = replace(exact, count_scale=1.0032)
    np.testing.assert_allclose(scaled.E, 1.0032 * exact.E)
    with pytest.raises(ValueError, match=r"quantity must be one of E, E_R, E_T \(got 'E_X'\)"):
        exact.quantity("E_X")
    without = replace(exact, average_counts=None)
    assert without.E_avg is None and without.cells == 4
    for call in (lambda: without.quantity("E", average=True), lambda: without.certified_epsilon(average=True),
                 lambda: without.interval_delta(average=True)):
        with pytest.raises(ValueError, match=r"this table has no E_avg \(made with average=False\)"):
            call()


def test_the_certified_tolerance_and_the_statement(exact):
    np.testing.assert_allclose(exact.certified_epsilon(), 0.05)
    rounded = replace(exact, counts=counts([[900, 400], [800, 500]], rounded_weights=[[10, 0], [0, 0]]))
    assert rounded.certified_epsilon()[0, 0] == pytest.approx(0.05 + 10 * 1e-4 / 1000)
    assert exact.certified
    assert exact.statement().startswith("every value (E and E_avg; 6 cells) within 0.05 of the model's true value at "
                                        "once with probability >= 0.99 (bound two-stage:")
    broken = replace(exact, counts=counts([[900, 400], [800, 500]], capped=[[0, 3], [0, 0]]))
    assert not broken.certified and np.isnan(broken.certified_epsilon()[0, 1])
    assert broken.statement().startswith("NOT CERTIFIED: 1 of 6 values had weight violations, invalid directions or "
                                         "capped walks")


def test_intervals_are_clopper_pearson_at_each_cells_delta(exact):
    lower, upper = exact.interval()
    for index in np.ndindex(2, 2):
        lo, hi = (float(v) for v in clopper_pearson(int(round(exact.E[index] * 1000)), 1000, 0.001))
        assert (float(lower[index]), float(upper[index])) == pytest.approx((lo, hi), rel=1e-12)
        assert lower[index] < exact.E[index] < upper[index]
    np.testing.assert_array_equal(exact.interval_delta(), 0.001)


def test_layout_is_the_engines_memory_order(exact):
    np.testing.assert_array_equal(exact.layout(), exact.E)
    swapped = replace(exact, order=("alpha", "mu"))
    np.testing.assert_array_equal(swapped.layout(), exact.E.T)
    np.testing.assert_array_equal(swapped.layout(average=True), exact.E_avg)


def test_interpolation_is_exact_at_nodes_and_linear_between(exact):
    np.testing.assert_allclose(exact.interpolate(exact.mu[:, None], exact.alpha[None, :]), exact.E)
    assert exact.interpolate(0.75, 0.3) == pytest.approx((0.9 + 0.8) / 2)
    assert exact.interpolate(0.75, 0.55) == pytest.approx((0.9 + 0.4 + 0.8 + 0.5) / 4)
    with pytest.raises(ValueError):
        exact.interpolate(0.2, 0.3)  # outside the grid
    estimate = exact.interpolation_estimate()  # two nodes per axis: no triple, nothing estimated
    assert estimate["mu"].shape == (2, 1) and np.all(np.isnan(estimate["mu"]))


def test_files_round_trip_and_other_suffixes_are_refused(measured, tmp_path):
    for suffix in (".nc", ".json"):
        path = measured.write(tmp_path / f"table{suffix}")
        back = read_albedo_table(path)
        assert isinstance(back, AlbedoTable)
        for name in measured.counts:
            np.testing.assert_array_equal(back.counts[name], measured.counts[name], err_msg=name)
        np.testing.assert_array_equal(back.E_avg, measured.E_avg)
        assert back.statement() == measured.statement()
    with pytest.raises(ValueError, match=r"path must end in .nc, .json, .npy, .h or .hpp \(got 'table.csv'\)"):
        measured.write(tmp_path / "table.csv")


def test_the_description_states_layout_and_certificate(exact):
    description = exact.description()
    assert description["order"] == ["mu", "alpha"] and description["shape"] == [2, 2]
    assert description["certificate"] == exact.statement() and description["rays_total"] == 6000
    assert description["worst_certified_epsilon"] == pytest.approx(0.05)
