"""
``turbid_slab`` against MCML's benchmarks, adding-doubling (iadpython) and exact cases.

Tolerances: a reading's fraction m/N is Binomial(N, p)/N; each comparison allows
K = 5 standard deviations sqrt(p(1 − p)/N) of the Monte Carlo (two-sided normal
false-failure probability 5.7·10⁻⁷ per comparison, < 10⁻³ over the whole file) plus
the stated accuracy of the reference (adding-doubling at 24 quadrature points:
5·10⁻⁴; published MCML values: their last digit). Seeds are fixed.
"""

from __future__ import annotations

import math
import subprocess
import sys

import numpy as np
import pytest

import virtspec_mi as vm
from virtspec_mi.references.slab import clear_slab_diffuse_reflectance, clear_slab_reflectance, walk_slab

K = 5.0
AD_ACCURACY = 5e-4  # iadpython 0.5.3 at quad_pts = 24 (≤ 24: it diverges from 32 on, anchors §1.1)
QUAD_PTS = 24


def slab(**params) -> dict:
    return {"type": "turbid_slab", **params}


def read(bsdf: dict, *, rays: int, beam: str = "collimated", seed: int = 1, **kwargs):
    return vm.measure(vm.instrument_scene(bsdf), beam=beam, rays=rays, seed=seed, **kwargs)


def within(measured: float, expected: float, rays: int, extra: float = 0.0) -> bool:
    sigma = math.sqrt(max(expected * (1.0 - expected), 1.0 / rays) / rays)
    return abs(measured - expected) <= K * sigma + extra


def optical(albedo: float, tau: float, g: float, n: float = 1.0) -> dict:
    """Slab of unit thickness with the given albedo and optical thickness."""

    return slab(mu_a=(1.0 - albedo) * tau, mu_s=albedo * tau, g=g, thickness=1.0, eta=n)


def adding_doubling(albedo: float, tau: float, g: float, n: float = 1.0) -> tuple[float, ...]:
    iad = pytest.importorskip("iadpython")
    return tuple(float(v) for v in iad.Sample(a=albedo, b=tau, g=g, n=n, quad_pts=QUAD_PTS).rt())


# --- MCML benchmarks (MCML manual, Tables 6.1 and 6.2) ------------------------------------


MCML_SLAB = slab(mu_a=10.0, mu_s=90.0, g=0.75, thickness=0.02)  # 1/cm, cm; n = 1


def test_mcml_slab_rd_and_tt(mi):
    n = 1_000_000
    r = read(MCML_SLAB, rays=n)
    # van de Hulst (1980): Rd = 0.09739, Tt = 0.66096 (5 digits: ±5e-6).
    assert within(r.diffuse_reflectance[0], 0.09739, n, 5e-6)
    assert within(r.transmittance[0], 0.66096, n, 5e-6)
    # Index-matched: no specular reflection at all; unscattered transmission e^-2.
    assert r.specular_reflected[0] == 0
    assert within(r.regular_transmittance[0], math.exp(-2.0), n)
    assert r.capped[0] == 0 and r.weight_violations[0] == 0
    assert r.reflected[0] + r.transmitted[0] + r.absorbed[0] == n


def test_mcml_semi_infinite_total_is_specular_plus_diffuse(mi):
    """n = 1.5, mu_a = 10, mu_s = 90 /cm, g = 0: Giovanelli's "Rd = 0.2600" is Rsp + Rd (anchors §2c)."""

    n = 1_000_000
    r = read(slab(mu_a=10.0, mu_s=90.0, g=0.0, thickness=float("inf"), eta=1.5), rays=n)
    assert r.transmitted[0] == 0
    # Rsp: a Fresnel coin flip at normal incidence, R0 = (0.5/2.5)^2 = 0.04 exactly.
    assert within(r.specular_reflectance[0], 0.04, n)
    # Total: adding-doubling UR1 = 0.25991 (iadpython, 64 points, anchors §2b); diffuse 0.21991.
    assert within(r.reflectance[0], 0.25991, n, 2e-4)
    assert within(r.diffuse_reflectance[0], 0.25991 - 0.04, n, 2e-4)
    assert not within(r.diffuse_reflectance[0], 0.2600, n)  # the misreading is detectable


def test_mcml_slab_diffuse_illumination_matches_adding_doubling(mi):
    n = 1_000_000
    _, _, uru, utu = adding_doubling(0.9, 2.0, 0.75)
    r = read(MCML_SLAB, rays=n, beam="diffuse")
    assert within(r.reflectance[0], uru, n, AD_ACCURACY)
    assert within(r.transmittance[0], utu, n, AD_ACCURACY)


@pytest.mark.parametrize("n_slab", [1.4, 2.4])
def test_unscattered_parts_match_adding_doubling(mi, n_slab):
    """Specular R and regular T are iadpython's unscattered r, t (incl. unscattered internal bounces)."""

    iad = pytest.importorskip("iadpython")
    sample = iad.Sample(a=0.5, b=1.0, g=0.9, n=n_slab, quad_pts=QUAD_PTS)
    r_unscattered, t_unscattered = (float(v) for v in sample.unscattered_rt())  # closed form, exact
    n = 400_000
    r = read(optical(0.5, 1.0, 0.9, n_slab), rays=n)
    assert within(r.specular_reflectance[0], r_unscattered, n, 1e-6)
    assert within(r.regular_transmittance[0], t_unscattered, n, 1e-6)


# --- exact cases -------------------------------------------------------------------------


@pytest.mark.parametrize("tau, n_slab", [(0.01, 1.0), (1.0, 1.4), (100.0, 1.0)])
def test_conservative_slab_absorbs_nothing(mi, tau, n_slab):
    """Albedo 1: every ray leaves, R + T = 1 exactly (a count identity, no tolerance)."""

    r = read(optical(1.0, tau, 0.5, n_slab), rays=20_000, wavelengths=[500, 600])
    assert np.all(r.absorbed == 0) and np.all(r.capped == 0)
    assert np.all(r.reflected + r.transmitted == r.rays)


def test_pure_forward_scattering_only_absorbs(mi):
    """g = 1 never changes direction: at normal incidence T = exp(−μa·d) and R = 0 exactly."""

    n = 400_000
    r = read(slab(mu_a=1.0, mu_s=5.0, g=1.0, thickness=1.0), rays=n)
    assert r.reflected[0] == 0
    assert within(r.transmittance[0], math.exp(-1.0), n)
    assert within(r.regular_transmittance[0], math.exp(-6.0), n)  # never scattered: e^(−μt·d)


@pytest.mark.parametrize("beam", ["collimated", "diffuse"])
def test_clear_slab_of_lower_index_than_its_surroundings(mi, beam):
    """mu_s = 0, n = 1 between media of index 1.5: exact incoherent slab reflectance (TIR included)."""

    n = 400_000
    bsdf = slab(mu_a=0.0, mu_s=0.0, thickness=1.0, eta=1.0, eta_above=1.5, eta_below=1.5)
    r = read(bsdf, rays=n, beam=beam)
    expected = (float(clear_slab_reflectance(1.0, 1.0, 1.5, 1.5)) if beam == "collimated"
                else clear_slab_diffuse_reflectance(1.0, 1.5, 1.5))
    assert within(r.reflectance[0], expected, n, 1e-6)
    assert r.absorbed[0] == 0
    # Nothing scatters: every exit is a delta event.
    assert r.specular_reflected[0] == r.reflected[0] and r.regular_transmitted[0] == r.transmitted[0]


def test_clear_absorbing_slab_with_different_media(mi):
    n = 400_000
    bsdf = slab(mu_a=0.7, mu_s=0.0, thickness=1.0, eta=1.33, eta_above=1.0, eta_below=1.52)
    r = read(bsdf, rays=n, theta_i=40.0)
    expected = float(clear_slab_reflectance(math.cos(math.radians(40.0)), 1.33, 1.0, 1.52, 0.7))
    assert within(r.reflectance[0], expected, n, 1e-6)


def test_diffuse_beam_gives_the_hemispherical_fresnel_reflectance(mi):
    """simple_dielectric n = 1.5 under diffuse light: 2∫F(μ)μdμ = 0.091778 (anchors §2a)."""

    n = 400_000
    r = read({"type": "simple_dielectric", "eta": 1.5}, rays=n, beam="diffuse")
    assert within(r.reflectance[0], 0.091778, n, 1e-6)


def test_diffuse_beam_directions_are_cosine_distributed(mi):
    from virtspec_mi.runtime.scene import find_bench
    from virtspec_mi.kernel.tracer import ReadingPlan, trace_rays

    instrument = find_bench(vm.instrument_scene({"type": "simple_dielectric"}))
    for sampling in ("jittered", "random"):
        rays = trace_rays(instrument, ReadingPlan(551.0, 0.0, 0.0, 200_000), 200_000, seed=0, beam="diffuse",
                          sampling=sampling)
        cos = rays["wi"][:, 2]
        assert np.all(cos >= 0.0)
        # cos θ has density 2μ on [0, 1]: E[μ] = 2/3 (sd 0.2357), E[μ²] = 1/2 (sd 0.2041); 5 sigma.
        assert abs(cos.mean() - 2 / 3) < K * 0.2357 / math.sqrt(cos.size)
        assert abs((cos**2).mean() - 0.5) < K * 0.2041 / math.sqrt(cos.size)
        # Azimuths uniform: E[cos φ] = E[sin φ] = 0 (sd ≤ 0.71 each).
        phi = np.arctan2(rays["wi"][:, 1], rays["wi"][:, 0])
        assert abs(np.cos(phi).mean()) < K * 0.71 / math.sqrt(cos.size)
        # Targets cover the specimen disk uniformly: E[r²] = r2²/2.
        radius2 = (rays["target"] ** 2).sum(axis=1) / 12.5**2
        assert abs(radius2.mean() - 0.5) < K * 0.2887 / math.sqrt(cos.size)


# --- plugin behaviour ----------------------------------------------------------------------


def test_spectral_parameters_are_evaluated_per_wavelength(mi):
    """A spectrum-valued mu_a gives exactly the counts of constant slabs at its node values."""

    # One wavelength per reading, so both specimens use the same rays (a constant slab is
    # wavelength-independent and would share the first reading's rays across wavelengths).
    spectrum = {"type": "regular", "wavelength_min": 500.0, "wavelength_max": 600.0, "values": "1, 5"}
    varying = []
    for wavelength, mu_a in ((500, 1.0), (600, 5.0)):
        varying.append(read(slab(mu_a=spectrum, mu_s=3.0), rays=50_000, wavelengths=[wavelength]))
        constant = read(slab(mu_a=mu_a, mu_s=3.0), rays=50_000, wavelengths=[wavelength])
        assert varying[-1].reflected[0] == constant.reflected[0]
        assert varying[-1].transmitted[0] == constant.transmitted[0]
    assert varying[0].reflected[0] != varying[1].reflected[0]
    assert not mi.load_dict(slab(mu_a=spectrum)).wavelength_independent
    assert mi.load_dict(slab(mu_a=2.0)).wavelength_independent


def test_xml_spectrum_and_semi_infinite_thickness(mi):
    bsdf = mi.load_string(
        '<bsdf version="3.0.0" type="turbid_slab"><spectrum name="mu_a" value="500:1, 600:5"/>'
        '<float name="mu_s" value="3"/><float name="thickness" value="inf"/>'
        '<spectrum name="eta" value="1.4"/></bsdf>'
    )
    assert not bsdf.wavelength_independent and bsdf.thickness == math.inf
    assert bsdf.constants["eta"] == pytest.approx(1.4)


def test_back_lit_ray_walks_the_mirrored_slab(mi):
    """A ray from below sees the slab with its outer media swapped: same walk, z mirrored."""

    import drjit as dr

    def sample(bsdf, wi_z):
        si = dr.zeros(mi.SurfaceInteraction3f, 5000)
        si.wi = mi.Vector3f(0.6, 0.0, wi_z)
        si.wavelengths = mi.Spectrum(550.0)
        u = np.random.default_rng(3).random((3, 5000)).astype(np.float32)
        bs, w = bsdf.sample(mi.BSDFContext(), si, mi.Float(u[0]), mi.Point2f(u[1], u[2]))
        dr.eval(bs, w)
        return np.array(bs.wo), np.array(w)[0], np.array(bs.sampled_component)

    params = dict(mu_a=0.5, mu_s=4.0, g=0.6, thickness=0.5, eta=1.4)
    front = sample(mi.load_dict(slab(eta_above=1.0, eta_below=1.6, **params)), 0.8)
    back = sample(mi.load_dict(slab(eta_above=1.6, eta_below=1.0, **params)), -0.8)
    assert np.array_equal(front[0][:2], back[0][:2]) and np.array_equal(front[0][2], -back[0][2])
    assert np.array_equal(front[1], back[1]) and np.array_equal(front[2], back[2])


def test_capped_walks_are_reported(mi):
    n = 20_000
    with pytest.warns(RuntimeWarning, match="step cap"):
        r = read(slab(mu_a=0.0, mu_s=50.0, thickness=1.0, max_steps=3), rays=n)
    assert r.capped[0] > 0 and r.absorbed[0] == 0  # no absorption: every uncapped walk left
    assert r.reflected[0] + r.transmitted[0] + r.capped[0] == n


@pytest.mark.parametrize("name, value, match", [
    ("mu_a", -1.0, "'mu_a' must satisfy 0 <= mu_a"),
    ("mu_s", math.inf, "'mu_s' must satisfy"),
    ("g", 1.5, "'g' must satisfy -1 <= g <= 1"),
    ("eta", 0.0, "'eta' must satisfy 0 < eta"),
    ("eta_below", -2.0, "'eta_below'"),
    ("thickness", 0.0, "'thickness' must be a number > 0 or inf"),
    ("max_steps", 0, "'max_steps' must be a whole number"),
    ("mu_a", "lots", "'mu_a' must be a number or a spectrum"),
])
def test_bad_parameters_are_refused(mi, name, value, match):
    with pytest.raises(Exception, match=match):
        mi.load_dict(slab(**{name: value}))


def test_semi_infinite_clear_medium_is_refused(mi):
    with pytest.raises(Exception, match="needs mu_a \\+ mu_s > 0"):
        mi.load_dict(slab(mu_a=0.0, mu_s=0.0, thickness=float("inf")))


@pytest.mark.parametrize("params, beam", [
    # index 1.33 between glass (1.52) above and air below, oblique collimated light
    (dict(mu_a=0.4, mu_s=6.0, g=0.8, thickness=0.6, eta=1.33, eta_above=1.52, eta_below=1.0), "collimated"),
    # a scattering slab of lower index (1.0) than the media around it (1.5), diffuse light
    (dict(mu_a=0.5, mu_s=4.5, g=0.5, thickness=0.4, eta=1.0, eta_above=1.5, eta_below=1.5), "diffuse"),
])
def test_numpy_reference_walk_agrees_with_the_plugin(mi, params, beam):
    """Media that iadpython cannot model (it has air outside): two independent Monte Carlos."""

    n_plugin, n_numpy = 400_000, 200_000
    r = read(slab(**params), rays=n_plugin, theta_i=25.0 if beam == "collimated" else 0.0, beam=beam)
    ref = walk_slab(n_numpy, **params, beam=beam, cos_theta_i=math.cos(math.radians(25.0)), seed=5)
    for measured, expected in ((r.reflectance[0], ref.reflectance), (r.transmittance[0], ref.transmittance),
                               (r.specular_reflectance[0], ref.specular / n_numpy)):
        p = 0.5 * (measured + expected)
        sigma = math.sqrt(max(p * (1 - p), 1e-6) * (1 / n_plugin + 1 / n_numpy))
        assert abs(measured - expected) <= K * sigma


def test_specular_and_regular_parts_follow_the_sampled_event_type(mi, diamond):
    """The split is general: a delta event is specular/regular, anything else diffuse."""

    r = vm.measure(diamond, rays=50_000)
    assert np.array_equal(r.specular_reflected, r.reflected)
    assert np.array_equal(r.regular_transmitted, r.transmitted)
    lambertian = read({"type": "diffuse"}, rays=50_000)
    assert lambertian.specular_reflected[0] == 0 and lambertian.reflected[0] > 0
    assert lambertian.diffuse_reflectance[0] == lambertian.reflectance[0]
    assert "specular_reflectance" in lambertian.as_dict()
    # A mixed BSDF is counted per ray, also when one chunk holds several readings.
    bsdf = slab(mu_a=1.0, mu_s=1.0, thickness=float("inf"), eta=1.5)
    several = read(bsdf, rays=50_000, wavelengths=[500, 600, 700])
    alone = read(bsdf, rays=50_000, wavelengths=[500])
    assert several.specular_reflected[0] == alone.specular_reflected[0]
    assert several.reflected[0] == alone.reflected[0]
    assert all(within(p, 0.04, 50_000) for p in several.specular_reflectance)  # R0 = 0.04
    assert np.all(several.specular_reflected < several.reflected)


# --- command line and shipped scene -----------------------------------------------------------


def test_cli_measures_the_shipped_slab_with_a_diffuse_beam(scenes_dir):
    import json

    result = subprocess.run(
        [sys.executable, "-m", "virtspec_mi.cli", "measure", str(scenes_dir / "mcml_slab.xml"),
         "--beam", "diffuse", "--rays", "200000", "--json"], capture_output=True, text=True,
    )
    assert result.returncode == 0, result.stderr
    data = json.loads(result.stdout)
    assert data["settings"]["beam"] == "diffuse"
    assert within(data["reflectance"][0], 0.19109, 200_000, AD_ACCURACY)  # URU (anchors §2b)
    assert within(data["transmittance"][0], 0.50182, 200_000, AD_ACCURACY)  # UTU
    assert data["diffuse_reflectance"] == data["reflectance"]


def test_render_the_shipped_slab(mi, scenes_dir):
    scene = mi.load_file(str(scenes_dir / "mcml_slab.xml"))
    table = np.array(mi.render(scene, spp=200_000))
    assert table.shape == (1, 3)
    assert within(float(table[0, 0]), 0.09739, 200_000) and within(float(table[0, 1]), 0.66096, 200_000)
    diffuse = mi.load_file(str(scenes_dir / "mcml_slab.xml"), beam="diffuse")
    table = np.array(mi.render(diffuse, spp=200_000))
    assert within(float(table[0, 0]), 0.19109, 200_000, AD_ACCURACY)  # URU
    reading = diffuse.integrator().last_reading
    assert reading.settings.beam == "diffuse" and "cosine-weighted over the hemisphere" in reading.summary()
    assert reading.backlit_fraction == 0.0


def test_settings_accept_the_diffuse_beam():
    assert vm.Settings(beam="diffuse").beam == "diffuse"
    with pytest.raises(ValueError, match="beam must be one of conical, collimated, diffuse"):
        vm.Settings(beam="hemispherical")


# --- adding-doubling grid and hard cases (slow) --------------------------------------------------

GRID = [(a, tau, g, n) for a in (0.5, 0.9, 0.99) for tau in (0.5, 2.0, 8.0) for g in (0.0, 0.75)
        for n in (1.0, 1.4)]
HARD = [
    (0.9, 0.01, 0.0, 1.0),   # optically thin
    (0.9, 100.0, 0.5, 1.0),  # optically thick
    (0.95, 2.0, 0.99, 1.0),  # strongly forward
    (0.95, 2.0, -0.99, 1.0),  # strongly backward
    (0.9, 2.0, 0.5, 2.4),    # strong internal reflection
    (1.0, 4.0, 0.9, 1.4),    # conservative
]


@pytest.mark.slow
@pytest.mark.parametrize("beam", ["collimated", "diffuse"])
def test_adding_doubling_grid_and_hard_cases(mi, beam):
    """
    UR1/UT1 (collimated, normal) and URU/UTU (diffuse) over 42 slabs: 84 comparisons per
    beam, each within 5 sigma + AD_ACCURACY (false-failure probability < 84 · 5.7e-7 = 5e-5).
    """

    n = 400_000
    failures = []
    for albedo, tau, g, n_slab in GRID + HARD:
        ur1, ut1, uru, utu = adding_doubling(albedo, tau, g, n_slab)
        expected_r, expected_t = (ur1, ut1) if beam == "collimated" else (uru, utu)
        r = read(optical(albedo, tau, g, n_slab), rays=n, beam=beam, seed=11)
        assert r.capped[0] == 0
        for name, measured, expected in (("R", r.reflectance[0], expected_r), ("T", r.transmittance[0], expected_t)):
            if not within(measured, expected, n, AD_ACCURACY):
                failures.append((albedo, tau, g, n_slab, name, measured, expected))
    assert not failures, failures


# --- issue 12: values float32 cannot hold, booleans and out-of-range spectra are refused ------


@pytest.mark.parametrize("name, value, match", [
    ("mu_a", 1e-40, "'mu_a' must satisfy 0 <= mu_a"),  # a float32 denormal
    ("mu_s", 1e39, "'mu_s' must satisfy"),  # inf in float32
    ("g", True, "'g' must be a number or a spectrum"),
    ("eta", float("nan"), "'eta' must satisfy 0 < eta"),
    ("thickness", 1e39, "'thickness' must be a number > 0 or inf"),
    ("thickness", True, "'thickness' must be a number > 0 or inf"),
    ("thickness", 1e-31, r"'thickness' must be a number > 0 or inf \(1e-30 <= thickness <= 1e\+30\)"),
    ("mu_a", 1e31, r"'mu_a' must satisfy 0 <= mu_a <= 1e\+30 \(0 or at least 1e-30\)"),
    ("mu_s", 1e-31, "'mu_s' must satisfy 0 <= mu_s <= 1e"),
    ("eta_above", 1e7, r"'eta_above' must satisfy 0 < eta_above <= 1e\+06 \(at least 1e-06\)"),
])
def test_values_float32_cannot_hold_are_refused(mi, name, value, match):
    with pytest.raises(Exception, match=match):
        mi.load_dict(slab(**{name: value}))


def _spectrum(low: float, high: float) -> dict:
    return {"type": "regular", "wavelength_min": 400, "wavelength_max": 700, "values": f"{low}, {high}"}


@pytest.mark.parametrize("name, spectrum, wavelengths, match", [
    ("g", _spectrum(1.5, 1.5), [551], r"'g' \(a spectrum\) must satisfy -1 <= g <= 1 .*got 1.5 at 551.0 nm"),
    ("g", _spectrum(0.2, 0.9), [450, 550], None),
    ("mu_a", _spectrum(1e31, 2.0), [400, 700], r"'mu_a' \(a spectrum\) must satisfy 0 <= mu_a .*got 1e\+31 at 400.0 nm"),
    # a spectrum is 0 outside its range: an index of 0 at 800 nm
    ("eta", _spectrum(1.3, 1.4), [500, 800], r"'eta' \(a spectrum\) must satisfy 0 < eta .*got 0 at 800.0 nm"),
])
def test_spectral_parameters_are_checked_at_the_wavelengths_traced(mi, name, spectrum, wavelengths, match):
    scene = vm.instrument_scene(slab(**{name: spectrum, "mu_s": 5.0}))
    if match is None:
        reading = vm.measure(scene, rays=2000, wavelengths=wavelengths)
        assert np.all(reading.reflected + reading.transmitted + reading.absorbed == 2000)
        return
    with pytest.raises(ValueError, match=match):
        vm.measure(scene, rays=2000, wavelengths=wavelengths)
    with pytest.raises(ValueError, match=match):
        vm.sweep(scene, rays=2000, wavelengths=wavelengths, theta_i=[0, 30])


def test_a_semi_infinite_slab_needs_extinction_at_every_wavelength(mi):
    scene = vm.instrument_scene(slab(mu_a=_spectrum(1.0, 2.0), mu_s=0.0, thickness=float("inf")))
    assert vm.measure(scene, rays=100, wavelengths=500).absorbed.tolist() == [100]
    with pytest.raises(ValueError, match=r"semi-infinite slab .* needs mu_a \+ mu_s > 0 \(got 0 at 800.0 nm\)"):
        vm.measure(scene, rays=100, wavelengths=[500, 800])  # the spectrum is 0 outside 400-700 nm
