"""
Certified albedo tables (virtspec_mi.applications.tables.albedo): cells against the independent
quadrature, the certificate, files, the comparison mode, resume and the CLI.

Cells are held to their own certificate: |Ê − E| < certified_epsilon (every cell of a
table at once with probability ≥ 1 − δ = 0.99 for a random seed; the seeds are fixed)
plus the quadrature's own error (the change when its nodes double, ×4).
"""

from __future__ import annotations

import json

import numpy as np
import pytest

import virtspec_mi as vm
from virtspec_mi.applications.tables.albedo import albedo_table
from virtspec_mi.applications.tables.table import read_albedo_table
from virtspec_mi.exchange.conventions import convention, cycles_ior
from virtspec_mi.references.microfacet import average_albedo, directional_albedo


def _reference(mu: float, alpha: float, distribution: str, eta: float | None = None, part: str = "total") -> tuple:
    masking = "exact"  # the tables measure the microfacet plugin, whose Beckmann G1 is exact by default
    coarse = directional_albedo(mu, alpha, distribution, eta, masking, nodes=160)
    fine = directional_albedo(mu, alpha, distribution, eta, masking, nodes=320)
    return getattr(fine, part), 4 * abs(getattr(fine, part) - getattr(coarse, part)) + 1e-7


@pytest.fixture(scope="module")
def ggx(mi):
    return albedo_table("conductor", engine=None, mu=[1.0, 0.5, 0.15], alpha=[0.1, 0.5, 1.0], epsilon=4e-3,
                        delta=0.01, seed=11, progress=False)


@pytest.fixture(scope="module")
def beckmann(mi):
    return albedo_table("conductor", distribution="beckmann", engine=None, mu=[1.0, 0.5], alpha=[0.3, 1.0],
                        epsilon=4e-3, seed=12, progress=False)


@pytest.fixture(scope="module")
def glass(mi):
    return albedo_table("glass", engine=None, mu=[1.0, 0.7], alpha=[0.5], eta=[1.5], epsilon=5e-3, parts=True,
                        seed=13, progress=False)


def test_ggx_cells_match_the_quadrature(ggx):
    assert ggx.certified
    for i, mu in enumerate(ggx.mu):
        for j, alpha in enumerate(ggx.alpha):
            expected, quad = _reference(mu, alpha, "ggx")
            assert abs(ggx.E[i, j] - expected) < ggx.certified_epsilon()[i, j] + quad, (mu, alpha)
    # the anchor cell: GGX, alpha = 1, mu = 1
    assert ggx.E[0, 2] == pytest.approx(directional_albedo(1.0, 1.0, nodes=320).total, abs=ggx.epsilon)


def test_ggx_average_is_the_cosine_weighted_albedo(ggx):
    expected = average_albedo(0.5, "ggx", nodes=128, mu_nodes=24).total
    assert abs(ggx.E_avg[1] - expected) < ggx.certified_epsilon(average=True)[1] + 2e-4


def test_beckmann_cells_match_the_quadrature(beckmann):
    for i, mu in enumerate(beckmann.mu):
        for j, alpha in enumerate(beckmann.alpha):
            expected, quad = _reference(mu, alpha, "beckmann")
            assert beckmann.certified_epsilon()[i, j] >= beckmann.epsilon
            assert abs(beckmann.E[i, j] - expected) < beckmann.certified_epsilon()[i, j] + quad, (mu, alpha)


def test_glass_cells_match_the_quadrature_from_both_sides(glass):
    assert glass.dims == ("side", "eta", "mu", "alpha") and glass.quantities == ("E", "E_R", "E_T")
    for s, eta in enumerate((1.5, 1 / 1.5)):
        for i, mu in enumerate(glass.mu):
            tol = glass.certified_epsilon()[s, 0, i, 0]
            for name, part in (("E", "total"), ("E_R", "reflected"), ("E_T", "transmitted")):
                expected, quad = _reference(mu, 0.5, "ggx", eta, part)
                assert abs(glass.quantity(name)[s, 0, i, 0] - expected) < tol + quad, (eta, mu, name)
    assert np.all(glass.E < 1.0)  # a rough dielectric loses energy to masking (E = 1 only when smooth)


def test_the_certificate_says_what_was_spent(ggx):
    text = ggx.statement()
    assert "within 0.004" in text and "0.99" in text and "12 cells" in text
    deltas = np.concatenate([ggx.interval_delta().ravel(), ggx.interval_delta(average=True).ravel()])
    assert deltas.sum() <= 0.9 * ggx.delta * (1 + 1e-9)  # second batches: 9/10 of delta, pilots the rest
    lower, upper = ggx.interval()
    assert np.all((lower <= ggx.E) & (ggx.E <= upper))
    assert ggx.rays == int(ggx.counts["rays"].sum() + ggx.counts["pilot_rays"].sum()
                           + ggx.average_counts["rays"].sum() + ggx.average_counts["pilot_rays"].sum())


def test_interpolation_between_the_cells(ggx):
    """At the nodes the interpolation is the table; between them the estimate is labelled, not certified."""

    mu, alpha = np.meshgrid(ggx.mu, ggx.alpha, indexing="ij")
    assert np.allclose(ggx.interpolate(mu, alpha), ggx.E, atol=1e-12)
    halfway = ggx.interpolate(0.75, 0.3)
    assert min(ggx.E[:2, :2].min(), 1) <= halfway <= ggx.E[:2, :2].max()
    estimate = ggx.interpolation_estimate()
    assert estimate["mu"].shape == (3, 2) and estimate["alpha"].shape == (3, 2)  # (other axis, intervals)
    assert np.all(estimate["mu"][np.isfinite(estimate["mu"])] > 0)


def test_two_stage_spends_fewer_rays_than_hoeffding_near_one(mi):
    smooth = dict(engine=None, mu=[1.0, 0.8], alpha=[0.02, 0.05], epsilon=5e-3, average=False, seed=3,
                  progress=False)
    two = albedo_table(**smooth)
    fixed = albedo_table(bound="hoeffding", **smooth)
    assert two.rays < 0.3 * fixed.rays
    assert np.all(np.abs(two.E - fixed.E) < two.certified_epsilon() + fixed.certified_epsilon())


def test_files_round_trip(ggx, tmp_path):
    ggx.write(tmp_path / "t.nc")
    back = read_albedo_table(tmp_path / "t.nc")
    assert np.array_equal(back.E, ggx.E) and np.array_equal(back.E_avg, ggx.E_avg)
    assert back.statement() == ggx.statement() and back.provenance == ggx.provenance
    ggx.write(tmp_path / "t.npy")
    assert np.array_equal(np.load(tmp_path / "t.npy"), ggx.layout().astype(np.float32))
    assert np.array_equal(np.load(tmp_path / "t_avg.npy"), ggx.E_avg.astype(np.float32))
    meta = json.loads((tmp_path / "t.json").read_text())
    assert meta["epsilon"] == ggx.epsilon and meta["provenance"]["mitsuba"] and meta["order"] == ["mu", "alpha"]
    with pytest.raises(ValueError, match="path"):
        ggx.write(tmp_path / "t.txt")


def test_compare_flags_exactly_the_cells_outside(ggx, tmp_path):
    published = ggx.E.copy()
    published[0, 1] += 3 * ggx.epsilon
    published[2, 0] -= 1.5 * ggx.epsilon
    published[1, 2] += 0.5 * ggx.epsilon  # inside: not flagged
    comparison = ggx.compare(published)
    assert [(c["mu"], c["alpha"]) for c in comparison.outside] == [(1.0, 0.5), (0.15, 0.1)]
    assert "2 of 9 published cells outside" in comparison.summary()
    ggx.write(tmp_path / "t.h")
    assert ggx.compare(tmp_path / "t.h").outside == []  # our own header, read back: nothing outside
    assert ggx.compare(tmp_path / "t.h", average=True).outside == []
    with pytest.raises(ValueError, match="9 cells"):
        ggx.compare(np.zeros(8))


def test_a_published_table_of_another_model_is_flagged(ggx):
    """Exact (erf) Beckmann values are not the table's GGX: most cells are flagged."""

    other = np.array([[directional_albedo(mu, a, "beckmann", nodes=128).total for a in ggx.alpha] for mu in ggx.mu])
    assert len(ggx.compare(other).outside) >= 5


def test_resume_reuses_finished_groups(mi, tmp_path, monkeypatch):
    import virtspec_mi.runtime.reading as reading

    kwargs = dict(engine=None, mu=[1.0, 0.4], alpha=[0.2, 0.8], epsilon=0.01, seed=5, progress=False)
    whole = albedo_table(**kwargs)
    calls = {"n": 0}
    real = reading.take

    def failing(*args, **options):
        calls["n"] += 1
        if calls["n"] == 4:
            raise KeyboardInterrupt
        return real(*args, **options)

    monkeypatch.setattr(reading, "take", failing)
    with pytest.raises(KeyboardInterrupt):
        albedo_table(checkpoint=tmp_path / "parts", **kwargs)
    monkeypatch.setattr(reading, "take", real)
    assert len(list((tmp_path / "parts").glob("*.nc"))) == 3
    resumed = albedo_table(checkpoint=tmp_path / "parts", **kwargs)
    for key in whole.counts:
        assert np.array_equal(resumed.counts[key], whole.counts[key]), key
    assert not (tmp_path / "parts").exists()  # removed once the table is complete
    (tmp_path / "other").mkdir()
    albedo_table(checkpoint=tmp_path / "other", **{**kwargs, "seed": 6, "average": False, "epsilon": 0.05})
    with pytest.raises(ValueError, match="different table"):  # a foreign checkpoint is refused
        stamp = tmp_path / "foreign"
        stamp.mkdir()
        (stamp / "identity.json").write_text(json.dumps({"seed": 99}))
        albedo_table(checkpoint=stamp, **kwargs)


def test_engine_conventions():
    cycles = convention("cycles")
    assert cycles.mu[0] == 1e-4 and cycles.mu[-1] == 1.0 and len(cycles.alpha) == 32
    assert cycles.alpha[-1] == 1.0 and cycles.alpha[1] == pytest.approx((1 / 31) ** 2)
    assert cycles_ior(16)[0] == pytest.approx(1.0, abs=1e-7) and cycles_ior(16)[-1] == pytest.approx(99.50, abs=0.01)
    filament = convention("filament")
    assert filament.order == ("alpha", "mu") and filament.alpha[0] == 1.0 and filament.mu[0] == 0.5 / 128
    unreal = convention("unreal")
    assert unreal.alpha[0] == pytest.approx((0.5 / 32) ** 2) and len(unreal.mu) == 128
    with pytest.raises(ValueError, match="engine"):
        convention("arnold")
    with pytest.raises(ValueError, match="glass"):
        convention("filament", "glass")


def test_bad_input_names_the_parameter(mi):
    with pytest.raises(ValueError, match="epsilon"):
        albedo_table(epsilon=0.7)
    with pytest.raises(ValueError, match="delta"):
        albedo_table(delta=0.0)
    with pytest.raises(ValueError, match="mu"):
        albedo_table(engine=None, mu=[1.2], alpha=[0.5])
    with pytest.raises(ValueError, match="alpha"):
        albedo_table(engine=None, mu=[1.0], alpha=[0.0])
    with pytest.raises(ValueError, match="eta"):
        albedo_table("glass", engine=None, mu=[1.0], alpha=[0.5], eta=[0.5])
    with pytest.raises(ValueError, match="engine"):
        albedo_table(engine="cycles", mu=[1.0])
    with pytest.raises(ValueError, match="model"):
        albedo_table("plastic")
    with pytest.raises(ValueError, match="bound"):
        albedo_table(bound="exact")
    assert vm.albedo_table is albedo_table


def test_cli_albedo_table(mi, tmp_path, capsys):
    from virtspec_mi.cli import main

    out = tmp_path / "t.nc"
    assert main(["albedo-table", "--engine", "none", "--cosines", "1,0.5", "--alpha", "0.3", "--epsilon", "0.02",
                 "--out", str(out), str(tmp_path / "t.h"), "--quiet"]) == 0
    text = capsys.readouterr().out
    assert "within 0.02" in text and f"written: {out}" in text
    np.save(tmp_path / "pub.npy", read_albedo_table(out).E + 0.5)
    assert main(["albedo-table", "--from", str(out), "--compare", str(tmp_path / "pub.npy")]) == 0
    assert "2 of 2 published cells outside" in capsys.readouterr().out
    assert main(["albedo-table", "--epsilon", "0.9"]) == 1
    assert "epsilon must satisfy" in capsys.readouterr().err


@pytest.mark.slow
def test_cycles_glass_grid_cells_match_the_quadrature(mi):
    """A few Cycles-grid glass cells (rough, both sides) on the 16-node index axis, against the quadrature."""

    etas = cycles_ior(16)[[5, 10]]
    table = albedo_table("glass", engine=None, mu=[1.0, 0.4], alpha=[0.25, 1.0], eta=etas, epsilon=5e-3, seed=21,
                         progress=False)
    for s in range(2):
        for e, eta in enumerate(etas):
            for i, mu in enumerate(table.mu):
                for j, alpha in enumerate(table.alpha):
                    expected, quad = _reference(mu, alpha, "ggx", eta if s == 0 else 1 / eta)
                    assert abs(table.E[s, e, i, j] - expected) < table.certified_epsilon()[s, e, i, j] + quad


def test_a_cell_with_invalid_directions_is_not_certified(ggx):
    from dataclasses import replace

    counts = {k: v.copy() for k, v in ggx.counts.items()}
    counts["invalid_directions"][1, 1] = 1
    broken = replace(ggx, counts=counts)
    assert not broken.certified and np.isnan(broken.certified_epsilon()[1, 1])
    assert np.isfinite(np.delete(broken.certified_epsilon().ravel(), 4)).all()  # (1, 1) of a 3 x 3 grid
    assert broken.statement().startswith("NOT CERTIFIED: 1 of 12 values")
    assert broken.compare(broken.E).outside[0]["index"] == (1, 1)  # no tolerance: reported as outside


def test_the_cosines_are_cosines_and_mu_keeps_one_meaning(capsys):
    from virtspec_mi.cli import main

    assert main(["albedo-table", "--engine", "none", "--mu", "1,0.5", "--alpha", "0.3"]) == 1
    err = capsys.readouterr().err
    assert "--mu: the cosines of incidence are --cosines" in err and "a table's is --epsilon" in err


def test_an_engine_order_table_compared_with_its_own_file_is_flagged_nowhere(mi, tmp_path):
    """Unreal's memory order is [roughness][mu]: the file's canonical (mu, alpha) array is put in it, by any name."""

    table = albedo_table("conductor", engine="unreal", fresnel="split", parts=True, epsilon=0.2, average=False,
                         progress=False)
    assert table.order == ("alpha", "mu")
    table.write(tmp_path / "t.nc")
    for array in (None, "E"):
        assert table.compare(tmp_path / "t.nc", array=array).outside == []
    assert table.compare(tmp_path / "t.nc", array="E_R").outside  # E against E_R: different quantities, flagged
    with pytest.raises(ValueError, match="array 'rays' is not a quantity of the albedo table"):
        table.compare(tmp_path / "t.nc", array="rays")


def test_numbers_given_as_text_are_refused_by_name(mi):
    for name in ("epsilon", "delta", "wavelength"):
        with pytest.raises(ValueError, match=f"{name} must be a number, not text"):
            albedo_table(engine=None, mu=[1.0], alpha=[0.5], **{name: "0.1"})


def test_two_outputs_of_one_name_are_refused_before_any_ray(mi, tmp_path):
    with pytest.raises(ValueError, match="one output would replace the other"):
        albedo_table(engine=None, mu=[1.0], alpha=[0.5], out=[tmp_path / "t.nc", tmp_path / "t.nc"])


def test_a_full_disk_mid_table_says_the_table_resumes_from_its_parts(mi, tmp_path, monkeypatch):
    """It offered an internal group, rescued to a temporary file, as "the result"; the table resumes from its parts."""

    import errno

    from virtspec_mi.base.files import WriteError
    from virtspec_mi.engine.checkpoint import ResultStore

    real, saved = ResultStore.save, []

    def full_after_one(self, label, result):
        if saved:
            raise WriteError(self.directory / "part.nc", "No space left on device", code=errno.ENOSPC, result=result)
        saved.append(label)
        return real(self, label, result)

    monkeypatch.setattr(ResultStore, "save", full_after_one)
    kwargs = dict(engine=None, mu=[1.0, 0.5], alpha=[0.5], epsilon=0.05, progress=False)
    with pytest.raises(WriteError) as caught:
        albedo_table(checkpoint=tmp_path / "parts", **kwargs)
    message = str(caught.value)
    assert "No space left on device" in message and f"the groups finished before it are kept in {tmp_path / 'parts'}" \
        in message and "resumes from them" in message and "error.result" not in message
    monkeypatch.setattr(ResultStore, "save", real)
    assert albedo_table(checkpoint=tmp_path / "parts", **kwargs).rays > 0  # resumed
