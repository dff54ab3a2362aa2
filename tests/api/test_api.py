"""
Tests of virtspec_mi.api.measure (and, through it, the spectrophotometer kernel).

Statistical checks use fixed seeds and the certified tolerance of the reading: with
N from eq. (23) each assertion |m/N − ρ| < μ fails for a random seed with probability
at most δ (exactly, at most ``miss_probability(N, ρ, μ)`` ≈ 0.001 at the defaults).
"""

from __future__ import annotations

import json
import subprocess
import sys
import warnings

import drjit as dr
import numpy as np
import pytest
from scipy import stats

import virtspec_mi as vm
from virtspec_mi.budgets.bounds import hoeffding_rays, miss_probability
from virtspec_mi.references.quadrature import fresnel_reflectance

MU, DELTA = 0.005, 0.01


def collimated(scene, theta, **kwargs):
    return vm.measure(scene, theta_i=theta, beam="collimated", **kwargs)


@pytest.mark.parametrize("theta", [0, 30, 60, 80, 89])
def test_collimated_diamond_is_fresnel_within_certified_mu(diamond, theta):
    reading = collimated(diamond, theta, seed=0)
    assert reading.rays.tolist() == [hoeffding_rays(MU, DELTA)] == [105_967]
    assert abs(reading.reflectance[0] - fresnel_reflectance(theta, 2.419)) < MU
    assert abs(reading.transmittance[0] - (1 - fresnel_reflectance(theta, 2.419))) < MU


def test_reflects_with_probability_f_not_one_minus_f(diamond):
    # The paper's text ("if F <= xi the ray is reflected") would give 1 - F = 0.83 at 0 deg.
    reading = collimated(diamond, 0, seed=1)
    assert reading.reflectance[0] == pytest.approx(0.172253, abs=MU)
    assert abs(reading.reflectance[0] - (1 - 0.172253)) > 0.5


@pytest.mark.parametrize("beam", ["collimated", "conical"])
def test_counts_add_up_exactly(diamond, beam):
    reading = vm.measure(diamond, theta_i=45, beam=beam, wavelengths="400:700:150")
    assert np.all(reading.reflected + reading.transmitted + reading.absorbed == reading.rays)
    total = reading.reflectance + reading.transmittance + reading.absorptance
    np.testing.assert_allclose(total, 1.0, rtol=0, atol=1e-15)
    assert reading.reflected.dtype == np.int64


@pytest.mark.parametrize("theta", [0, 45, 70, 85])
def test_mitsuba_dielectric_agrees_with_simple_dielectric(mi, theta):
    mitsuba_dielectric = vm.instrument_scene({"type": "dielectric", "int_ior": 2.419, "ext_ior": 1.0})
    for beam in ("collimated", "conical"):
        ours = vm.measure(vm.instrument_scene({"type": "simple_dielectric"}), theta_i=theta, beam=beam, seed=3)
        theirs = vm.measure(mitsuba_dielectric, theta_i=theta, beam=beam, seed=4)
        # each is within mu of the same expectation (certified), so they differ by < 2 mu
        assert abs(ours.reflectance[0] - theirs.reflectance[0]) < 2 * MU
        assert theirs.weight_violations.sum() == 0
    assert abs(theirs.reflectance[0] - fresnel_reflectance(theta, 2.419)) < MU or beam == "conical"


@pytest.fixture(scope="module")
def traced_diamond(mi):
    """Mitsuba's own smooth dielectric (diamond): not flagged wavelength-independent, so
    every wavelength is traced with its own rays."""

    return mi.load_dict(vm.instrument_scene({"type": "dielectric", "int_ior": 2.419, "ext_ior": 1.0}))


def test_same_seed_same_counts_whatever_chunk_size_and_threads(traced_diamond):
    kwargs = dict(theta_i=70, wavelengths=[450, 551, 650], seed=11, sampling="jittered")
    reference = vm.measure(traced_diamond, **kwargs)
    small_chunks = vm.measure(traced_diamond, chunk_size=1024 * 7, **kwargs)
    threads = dr.thread_count()
    try:
        dr.set_thread_count(1)
        one_thread = vm.measure(traced_diamond, chunk_size=50_000, **kwargs)
    finally:
        dr.set_thread_count(threads)
    for other in (small_chunks, one_thread):
        np.testing.assert_array_equal(other.reflected, reference.reflected)
        np.testing.assert_array_equal(other.transmitted, reference.transmitted)


@pytest.mark.parametrize("sampling", ["jittered", "random", "concentric"])
def test_first_reading_of_a_batch_equals_a_single_reading(traced_diamond, sampling):
    # readings are keyed on the global ray index: reading 0 is the same rays either way,
    # whether its chunk holds one reading (scalar path) or several (gathered path).
    scene = traced_diamond
    batch = vm.measure(scene, theta_i=60, wavelengths=[500, 600, 700], rays=5000, sampling=sampling, seed=5)
    single = vm.measure(scene, theta_i=60, wavelengths=[500], rays=5000, sampling=sampling, seed=5)
    assert batch.reflected[0] == single.reflected[0]
    assert len(set(batch.reflected)) > 1  # the other readings have rays of their own
    other_seed = vm.measure(scene, theta_i=60, wavelengths=[500, 600, 700], rays=5000, sampling=sampling, seed=6)
    assert not np.array_equal(other_seed.reflected, batch.reflected)


def test_miss_count_agrees_with_exact_binomial(traced_diamond):
    """
    K independent readings (one per wavelength: each has its own rays) of a specimen
    whose rho is known exactly (Mitsuba's smooth dielectric: traced per wavelength); the number of misses |m/N - rho| >= mu must be
    consistent with Binomial(K, q), q = miss_probability(N, rho, mu) (Hoeffding 1963; the exact binomial law:
    a plain "misses <= delta K" check has no power). Two-sided test at level 1e-4.
    """

    mu, delta, k = 0.05, 0.2, 2000
    n = hoeffding_rays(mu, delta)  # 461
    rho = float(fresnel_reflectance(80.0, 2.419))  # 0.4333
    wavelengths = 400.0 + 0.1 * np.arange(k)
    reading = collimated(traced_diamond, 80.0, wavelengths=wavelengths, mu=mu, delta=delta, seed=2024)
    misses = int(np.sum(np.abs(reading.reflectance - rho) >= mu))
    q = miss_probability(n, rho, mu)
    assert 0.02 < q < 0.05  # the test has something to detect
    assert stats.binomtest(misses, k, q).pvalue > 1e-4, (misses, k * q)
    # unbiased: the pooled estimate is within 4 standard errors of rho
    pooled = reading.reflected.sum() / (n * k)
    assert abs(pooled - rho) < 4 * np.sqrt(rho * (1 - rho) / (n * k))
    # and it has power: half the rays give a miss rate the binomial test rejects
    half = collimated(traced_diamond, 80.0, wavelengths=wavelengths, rays=n // 2, seed=2025)
    half_misses = int(np.sum(np.abs(half.reflectance - rho) >= mu))
    assert stats.binomtest(half_misses, k, q).pvalue < 1e-4


# --- hard cases ------------------------------------------------------------------------


def test_grazing_collimated_90_degrees_reflects_everything(diamond):
    # theta_i = 90 is the limit theta -> 90-: cos(pi/2) = 6.1e-17 > 0 in float64, F -> 1.
    reading = collimated(diamond, 90.0)
    assert reading.reflectance[0] == 1.0 and reading.transmittance[0] == 0.0


def test_grazing_collimated_89_999_degrees(diamond):
    reading = collimated(diamond, 89.999)
    expected = fresnel_reflectance(89.999, 2.419)
    assert 0.999 < expected < 1.0
    assert abs(reading.reflectance[0] - expected) < MU


@pytest.mark.parametrize("theta", [86.0, 89.0, 90.0])
def test_conical_with_emitter_partly_below_specimen_plane(diamond, theta):
    reading = vm.measure(diamond, theta_i=theta, beam="conical")
    assert 0 < reading.backlit_fraction <= 0.5
    assert np.isfinite(reading.reflectance).all()
    assert reading.reflected[0] + reading.transmitted[0] + reading.absorbed[0] == reading.rays


@pytest.mark.parametrize("beam", ["collimated", "conical"])
@pytest.mark.parametrize("theta", [0.0, 45.0, 89.0, 90.0])
def test_index_matched_dielectric_never_reflects(mi, beam, theta):
    scene = vm.instrument_scene({"type": "simple_dielectric", "eta": 1.0})
    reading = vm.measure(scene, theta_i=theta, beam=beam)
    if beam == "conical" and theta > 85.43:
        # back-lit rays pass straight through into the upper hemisphere: R = backlit share
        assert abs(reading.reflectance[0] - reading.backlit_fraction) < MU
    else:
        assert reading.reflected[0] == 0 and reading.transmittance[0] == 1.0


def test_a_single_ray(diamond):
    reading = vm.measure(diamond, theta_i=30, rays=1, wavelengths=[400, 500, 600])
    assert reading.rays.tolist() == [1, 1, 1]
    assert set(reading.reflectance) <= {0.0, 1.0}
    assert np.all(reading.reflected + reading.transmitted == 1)


@pytest.mark.slow
def test_a_billion_rays_exact_counts_in_bounded_memory(tmp_path):
    """N = 10^9 in one reading: exact integer counts and < 1 GiB peak memory (fresh process)."""

    # VmHWM, not ru_maxrss: Linux carries ru_maxrss over from the parent across exec.
    script = (
        "import json, virtspec_mi as vm\n"
        "r = vm.measure(vm.instrument_scene({'type': 'simple_dielectric'}), theta_i=0, "
        "beam='collimated', rays=10**9)\n"
        "print(json.dumps({'r': int(r.reflected[0]), 't': int(r.transmitted[0]), 'a': int(r.absorbed[0]),"
        " 'rss_kib': int(next(l for l in open('/proc/self/status') if l.startswith('VmHWM')).split()[1])}))\n"
    )
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, check=True)
    result = json.loads(out.stdout.strip().splitlines()[-1])
    print(result)
    assert result["r"] + result["t"] + result["a"] == 10**9 and result["a"] == 0
    # well beyond float32 (2^24) and within the certified tolerance of 10^9 rays at delta = 1e-6
    assert abs(result["r"] / 1e9 - 0.172253) < vm.hoeffding_mu(10**9, 1e-6)
    assert result["rss_kib"] < 1024 * 1024


# --- Mitsuba built-in specimens and weights ---------------------------------------------


def test_diffuse_specimen_reads_its_albedo(mi):
    scene = vm.instrument_scene({"type": "diffuse", "reflectance": 0.3})
    for beam in ("collimated", "conical"):
        reading = vm.measure(scene, theta_i=40, beam=beam, wavelengths=[450, 650])
        assert np.all(np.abs(reading.reflectance - 0.3) < MU)
        assert np.all(reading.transmitted == 0)


def test_weights_above_one_are_reported_not_hidden(mi):
    scene = vm.instrument_scene({"type": "diffuse", "reflectance": 1.5})
    with pytest.warns(RuntimeWarning, match="outside \\[0, 1\\]"):
        reading = vm.measure(scene, theta_i=10, rays=1000)
    assert reading.weight_violations[0] == 1000
    assert "WARNING" in reading.summary()


@pytest.mark.parametrize("bsdf", [{"type": "roughconductor"}, {"type": "plastic"}, {"type": "thindielectric"}])
def test_builtin_bsdfs_measure_without_violations(mi, bsdf):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        reading = vm.measure(vm.instrument_scene(bsdf), theta_i=30, rays=20_000)
    assert reading.weight_violations.sum() == 0
    assert 0 <= reading.reflectance[0] + reading.transmittance[0] <= 1


# --- interfaces ------------------------------------------------------------------------


def test_mi_render_returns_the_documented_tensor(mi, scenes_dir):
    scene = mi.load_file(str(scenes_dir / "diamond_collimated.xml"), theta_i="30")
    image = np.array(mi.render(scene, seed=5, spp=2000))
    assert image.shape == (1, 3)
    reading = scene.integrator().last_reading
    assert reading.rays.tolist() == [2000] and reading.settings.seed == 5
    np.testing.assert_allclose(image[0], [reading.reflectance[0], reading.transmittance[0],
                                          reading.absorptance[0]], rtol=1e-6)
    same = vm.measure(scene, seed=5, rays=2000)
    assert same.reflected[0] == reading.reflected[0]


def test_scene_integrator_settings_are_the_defaults_of_measure(mi, scenes_dir):
    scene = mi.load_file(str(scenes_dir / "diamond_conical.xml"))
    reading = vm.measure(scene)
    assert (reading.theta_i, reading.settings.beam) == (70.0, "conical")
    assert vm.measure(scene, theta_i=10, beam="collimated").settings.beam == "collimated"


def test_reading_as_dict_is_json_ready(diamond):
    data = json.loads(json.dumps(vm.measure(diamond, theta_i=5, rays=100).as_dict()))
    assert {"reflectance", "transmittance", "absorptance", "reflected", "transmitted", "rays",
            "seconds", "settings", "geometry"} <= set(data)


def test_wavelength_independent_specimen_is_traced_once_and_says_so(diamond, traced_diamond):
    reading = vm.measure(diamond, theta_i=40, wavelengths="400:700:100", rays=3000)
    assert reading.wavelength_independent and reading.as_dict()["wavelength_independent"]
    assert len(set(reading.reflected)) == 1
    assert "wavelength-independent specimen: traced once" in reading.summary()
    other = vm.measure(traced_diamond, theta_i=40, wavelengths="400:700:100", rays=3000)
    assert not other.wavelength_independent and len(set(other.reflected)) > 1


# --- ray budgets and intervals ---------------------------------------------------------
# False-failure rates for a random seed (the seeds are fixed, so outcomes are deterministic):
# "within mu" at the exact N fails with probability q = miss_probability(66,501, 0.18, 0.005)
# = 6e-4 per wavelength; under two-stage with its exact mixture, <= 0.0059 per wavelength;
# a 0.99 Clopper-Pearson interval misses the truth with probability <= 0.01 per interval.


def test_exact_bound_reading(diamond):
    reading = collimated(diamond, 45, bound="exact", wavelengths=[450, 650], seed=21)
    assert reading.rays.tolist() == [66_501, 66_501] and reading.bound == "exact"
    assert reading.pilot_rays is None and reading.rays_spent.tolist() == [66_501, 66_501]
    assert np.all(np.abs(reading.reflectance - fresnel_reflectance(45, 2.419)) < MU)


def test_two_stage_reading_spends_pilot_and_sized_second_batch(traced_diamond):
    from virtspec_mi.budgets import twostage

    wavelengths = [450, 550, 650]  # traced_diamond: each wavelength has its own rays
    reading = collimated(traced_diamond, 0, bound="two-stage", wavelengths=wavelengths, seed=7)
    assert reading.pilot_rays.tolist() == [2000] * 3
    assert np.all(reading.rays_spent == reading.rays + 2000)
    # R = 0.17: far fewer rays than Hoeffding's 105,967, and within mu
    assert np.all(reading.rays < 50_000) and len(set(reading.rays.tolist())) > 1
    assert np.all(np.abs(reading.reflectance - 0.172253) < MU)
    assert np.all(reading.reflected + reading.transmitted + reading.absorbed == reading.rays)
    # each reading's N2 from its own pilot's counts; the pilot is the ordinary stream of the seed (the
    # first reading's rays start at index 0 whatever the layout), the second batch a fresh stream
    pilot = reading.pilot
    n2 = twostage.stage_two_rays(np.stack([pilot.reflected, pilot.transmitted, pilot.absorbed], axis=1),
                                 2000, MU, DELTA, DELTA / 10)
    assert reading.rays.tolist() == n2.tolist()
    first = collimated(traced_diamond, 0, rays=2000, wavelengths=[450], seed=7)
    assert first.reflected[0] == pilot.reflected[0]
    second = collimated(traced_diamond, 0, rays=int(reading.rays[0]), wavelengths=[450],
                        seed=twostage.stage_two_seed(7))
    assert second.reflected[0] == reading.reflected[0]
    same_seed = collimated(traced_diamond, 0, rays=int(reading.rays[0]), wavelengths=[450], seed=7)
    assert same_seed.reflected[0] != reading.reflected[0]  # not the pilot's rays again


def test_joint_certification_splits_delta(diamond):
    reading = collimated(diamond, 30, joint=True, rays=None, wavelengths=[500])
    assert reading.rays.tolist() == [119_830]  # Hoeffding at delta/2 (eq. 23 at delta/2)
    assert reading.interval_delta == DELTA / 2
    assert "R and T together" in reading.summary()


def test_intervals_on_every_reading(diamond):
    reading = collimated(diamond, 60, wavelengths=[400, 500, 600, 700], seed=31)
    rho = fresnel_reflectance(60, 2.419)
    for name, truth in [("reflectance", rho), ("transmittance", 1 - rho)]:
        interval = getattr(reading, f"{name}_interval")
        assert interval.shape == (4, 2)
        assert np.all(interval[:, 0] <= getattr(reading, name)) and np.all(getattr(reading, name) <= interval[:, 1])
        # each covers the truth with probability >= 0.99 (fixed seed)
        assert np.all((interval[:, 0] <= truth) & (truth <= interval[:, 1]))
        # and it is narrower than the certified +-mu at N = 105,967 (2 sigma ~ 0.0023)
        assert np.all(interval[:, 1] - interval[:, 0] < 2 * MU)
    assert np.all(reading.absorptance_interval[:, 0] == 0.0)
    data = reading.as_dict()
    assert data["bound"] == "hoeffding" and data["interval_delta"] == DELTA
    assert np.allclose(data["reflectance_interval"], reading.reflectance_interval)
    assert "Clopper-Pearson 0.99 intervals" in reading.summary()


def test_integrator_accepts_the_budget_parameters(mi):
    scene_dict = vm.instrument_scene({"type": "simple_dielectric"})
    scene_dict["integrator"] = {"type": "spectrophotometer", "bound": "two-stage", "mu": 0.05, "delta": 0.2,
                                "pilot_rays": 300, "joint": True, "beam": "collimated"}
    reading = vm.measure(mi.load_dict(scene_dict))
    assert reading.bound == "two-stage" and reading.pilot_rays.tolist() == [300]
    assert reading.settings.joint and reading.interval_delta == 0.1
    scene_dict["integrator"] = {"type": "spectrophotometer", "bound": "sloppy"}
    with pytest.raises(Exception, match="bound must be one of hoeffding, chebyshev, exact, two-stage"):
        mi.load_dict(scene_dict)


@pytest.mark.parametrize("bound, joint, rays", [("hoeffding", "false", 105_967), ("chebyshev", "false", 1_000_000),
                                                ("exact", "false", 66_501), ("exact", "true", 78_901),
                                                ("two-stage", "false", None)])
def test_xml_scene_takes_every_bound(mi, scenes_dir, bound, joint, rays):
    scene = mi.load_file(str(scenes_dir / "diamond_collimated.xml"), theta_i="20", bound=bound, joint=joint)
    reading = vm.measure(scene, seed=3)
    assert reading.bound == bound and reading.settings.joint == (joint == "true")
    if rays is not None:
        assert reading.rays.tolist() == [rays]
    else:
        assert reading.pilot_rays.tolist() == [2000] and reading.rays[0] < 60_000
    assert abs(reading.reflectance[0] - fresnel_reflectance(20, 2.419)) < MU


@pytest.mark.parametrize("bound, calls", [("exact", 1), ("two-stage", 2)])
def test_budgets_run_batched(monkeypatch, traced_diamond, bound, calls):
    """A spectrum is one kernel call (fixed N) or two (every pilot, then every second batch)."""

    from virtspec_mi.kernel import tracer

    seen = []
    original = tracer.tally_readings

    def counting(instrument, plans, **options):
        seen.append([plan.rays for plan in plans])
        return original(instrument, plans, **options)

    monkeypatch.setattr(tracer, "tally_readings", counting)
    reading = vm.measure(traced_diamond, theta_i=75, bound=bound, wavelengths="400:700:20", mu=0.02, delta=0.05)
    assert len(seen) == calls and all(len(rays) == 16 for rays in seen)
    assert seen[-1] == reading.rays.tolist()
    if bound == "two-stage":
        assert seen[0] == [500] * 16 and len(set(seen[1])) > 1  # each reading sized on its own


@pytest.mark.parametrize("bound, joint", [("exact", "false"), ("two-stage", "true")])
def test_conical_xml_scene_takes_the_bound(mi, scenes_dir, bound, joint):
    scene = mi.load_file(str(scenes_dir / "diamond_conical.xml"), bound=bound, joint=joint)
    reading = vm.measure(scene)
    assert reading.bound == bound and reading.settings.joint == (joint == "true")
    assert reading.settings.beam == "conical" and reading.theta_i == 70


# --- issue 12: one clear ValueError instead of a traceback ---------------------------------------


@pytest.mark.parametrize("spp", [-5, 2**32, 2**40])
def test_render_refuses_a_bad_spp_naming_it(mi, scenes_dir, spp):
    scene = mi.load_file(str(scenes_dir / "diamond_conical.xml"))
    # before: Dr.Jit's RuntimeError "error while performing a custom differentiable operation"
    with pytest.raises(ValueError, match=r"spectrophotometer: spp must be a whole number with 0 <= spp <= "
                                         rf"4294967295 .*\(got {spp}\)"):
        mi.render(scene, spp=spp)
    with pytest.raises(ValueError, match="spp must be a whole number"):
        scene.integrator().render(scene, spp=spp)
    assert np.array(mi.render(scene, spp=1000)).shape == (1, 3)  # and the same scene still renders


def test_render_leaves_other_integrators_errors_alone(mi):
    scene = mi.load_dict({"type": "scene", "integrator": {"type": "path"},
                          "sensor": {"type": "perspective", "film": {"type": "hdrfilm", "width": 2, "height": 2}}})
    assert np.array(mi.render(scene, spp=1)).shape[:2] == (2, 2)


def test_specimens_needing_uv_partials_are_refused_with_the_reason(mi):
    bump = {"type": "bumpmap", "arbitrary": {"type": "checkerboard"}, "bsdf": {"type": "diffuse"}}
    # before: RuntimeError "[Texture] Texture::eval_1_grad(): not implemented!" from the kernel
    with pytest.raises(ValueError, match=r"BumpMap cannot be sampled by the instrument .*eval_1_grad.*no uv "
                                         r"partials .*bumpmap.* not supported"):
        vm.measure(vm.instrument_scene(bump), rays=100)


def test_a_scene_dict_with_a_none_value_is_refused_not_a_crash(mi):
    # Mitsuba 3.9.1's load_dict ends the process with a segmentation fault on a None value
    from virtspec_mi.engine.bench import SceneError

    with pytest.raises(SceneError, match=r"\[specimen.bsdf.eta\] has no value \(None\)"):
        vm.measure(vm.instrument_scene({"type": "simple_dielectric", "eta": None}), rays=10)


def test_a_long_measurement_shows_progress_in_a_terminal(traced_diamond, capsys, monkeypatch):
    import sys

    import virtspec_mi.engine.progress as progress

    monkeypatch.setattr(sys.stderr, "isatty", lambda: True)
    kwargs = dict(theta_i=30, wavelengths="400:700:10", rays=20_000, chunk_size=65_536)
    quiet = vm.measure(traced_diamond, **kwargs)  # ~ms: under the 2 s threshold
    assert capsys.readouterr().err == ""
    monkeypatch.setattr(progress, "_PROGRESS_AFTER_S", 0.0)  # now every measurement counts as slow
    shown = vm.measure(traced_diamond, **kwargs)
    assert "readings" in capsys.readouterr().err
    np.testing.assert_array_equal(shown.reflected, quiet.reflected)  # the bar changes no count
    vm.measure(traced_diamond, progress=False, **kwargs)
    assert capsys.readouterr().err == ""
