"""The ABM leaf walk (``abm_b``/``abm_u``): conventions, conservation, hard cases, parameters."""

from __future__ import annotations

import shutil

import drjit as dr
import numpy as np
import pytest

import virtspec_mi as vm
from virtspec_mi.engine.bench import SceneError
from virtspec_mi.plugins.leaf_data import LEAF_DATA_FILES

PLUGINS = ("abm_b", "abm_u")


def leaf(plugin: str, **params) -> dict:
    return vm.instrument_scene({"type": plugin, **params})


def check_reading(reading) -> None:
    """Every ray has a fate: R + T + A = 1 exactly, each in [0, 1], no NaN, no capped walk."""

    n = reading.rays
    assert np.all(reading.capped == 0) and np.all(reading.weight_violations == 0)
    assert np.all(reading.reflected + reading.transmitted + reading.absorbed == n)
    for values in (reading.reflectance, reading.transmittance, reading.absorptance):
        assert np.all(np.isfinite(values)) and np.all((values >= 0) & (values <= 1))


@pytest.mark.parametrize("plugin", PLUGINS)
@pytest.mark.parametrize("side", ["adaxial", "abaxial"])
def test_every_ray_has_a_fate_at_hard_wavelengths(mi, plugin, side):
    """400 and 1940 nm (strongly absorbing) and 800 nm (nearly transparent mesophyll)."""

    reading = vm.measure(leaf(plugin, side=side), theta_i=8, beam="collimated",
                         wavelengths=[400, 800, 1940], rays=20_000)
    check_reading(reading)
    a400, a800, a1940 = reading.absorptance
    # adaxial 400 nm: A ≈ 0.95 (reference R/T = 0.046/0.001); 800 nm: A ≈ 0.04; 1940 nm: A ≈ 0.89
    assert a400 > 0.7 and a1940 > 0.6 and a800 < 0.1


@pytest.mark.parametrize("plugin", PLUGINS)
def test_zero_absorption_gives_r_plus_t_exactly_one(mi, plugin, tmp_path, leaf_data_dir):
    """All concentrations 0 and a data directory whose water absorption is 0: α = 0 everywhere."""

    for name, _, _ in LEAF_DATA_FILES.values():
        shutil.copy(leaf_data_dir / name, tmp_path / name)
    (tmp_path / LEAF_DATA_FILES["water"][0]).write_text("0\n" * 421)
    zero = dict(chlorophyll_a=0.0, chlorophyll_b=0.0, carotenoids=0.0, protein=0.0, cellulose=0.0, lignin=0.0)
    for side in ("adaxial", "abaxial"):
        reading = vm.measure(leaf(plugin, data_dir=str(tmp_path), side=side, **zero), theta_i=30,
                             wavelengths=[400, 680, 1940, 2500], rays=20_000)
        check_reading(reading)
        assert np.all(reading.absorbed == 0)
        assert np.all(reading.reflected + reading.transmitted == reading.rays)
        assert np.all(reading.reflectance > 0.1) and np.all(reading.transmittance > 0.1)


@pytest.mark.parametrize("plugin", PLUGINS)
def test_grazing_incidence(mi, plugin):
    """θi = 90° collimated (cos θ = 6e-17): F = 1 at the cuticle, every ray is reflected;
    89° is an ordinary reading with high reflectance."""

    reading = vm.measure(leaf(plugin), theta_i=90, beam="collimated", wavelengths=[551, 1450], rays=10_000)
    check_reading(reading)
    assert np.all(reading.reflected == reading.rays)
    reading = vm.measure(leaf(plugin), theta_i=89, beam="collimated", wavelengths=[551, 1450], rays=10_000)
    check_reading(reading)
    assert np.all(reading.reflectance > 0.5)


@pytest.mark.parametrize("plugin", PLUGINS)
@pytest.mark.parametrize("aspect", [1.0, 50.0])
def test_extreme_aspect_ratios(mi, plugin, aspect):
    names = [n for n in ("cuticle", "epidermis", "palisade", "spongy")
             if plugin == "abm_b" or n != "palisade"]
    params = {f"{n}_aspect_ratio": aspect for n in names}
    reading = vm.measure(leaf(plugin, **params), theta_i=45, wavelengths=[551, 800, 1450], rays=20_000)
    check_reading(reading)
    assert np.all(reading.reflectance > 0.02) and np.all(reading.transmittance > 0.02)


@pytest.mark.parametrize("plugin", PLUGINS)
def test_very_thick_and_very_thin_leaves(mi, plugin):
    # 1 cm: the chlorophyll band is opaque (α·d_m ≥ 100 at 680 nm) -> nothing transmitted
    thick = vm.measure(leaf(plugin, thickness=1e-2), theta_i=8, wavelengths=[680, 800], rays=20_000)
    check_reading(thick)
    assert thick.transmitted[0] == 0 and thick.reflectance[0] > 0.02
    # 0.1 µm: α·d_m ≤ 0.004 even at 400 nm -> little absorption; the interfaces alone still
    # scatter light both ways (like the 800 nm plateau, R ≈ T ≈ 0.48)
    thin = vm.measure(leaf(plugin, thickness=1e-7), theta_i=8, wavelengths=[400, 800], rays=20_000)
    check_reading(thin)
    assert np.all(thin.absorptance < 0.05)
    assert np.all(thin.reflectance > 0.3) and np.all(thin.transmittance > 0.3)


def test_capped_walks_are_reported(mi):
    """max_steps = 2 stops every walk still inside the leaf: counted in capped, in no tally."""

    with pytest.warns(RuntimeWarning, match="step cap"):
        reading = vm.measure(leaf("abm_b", max_steps=2), theta_i=8, wavelengths=[800], rays=10_000)
    assert reading.capped[0] > 1000
    assert reading.reflected[0] + reading.transmitted[0] + reading.absorbed[0] + reading.capped[0] == reading.rays


def sample_directly(mi, plugin_dict: dict, wi: np.ndarray, wavelength: float = 800.0, seed: int = 0):
    """Call the plugin's ``sample`` on many copies of one incident direction."""

    bsdf = mi.load_dict(plugin_dict)
    n = 20_000
    rng = np.random.default_rng(seed)
    si = dr.zeros(mi.SurfaceInteraction3f)
    si.wi = mi.Vector3f(*(np.full(n, c, dtype=np.float32) for c in wi))
    si.wavelengths = mi.Spectrum(wavelength)
    s1 = mi.Float(rng.random(n, dtype=np.float32))
    s2 = mi.Point2f(rng.random(n, dtype=np.float32), rng.random(n, dtype=np.float32))
    bs, weight = bsdf.sample(mi.BSDFContext(mi.TransportMode.Importance), si, s1, s2, True)
    reflection = mi.has_flag(bs.sampled_type, mi.BSDFFlags.Reflection)
    dr.eval(bs, weight, reflection)
    return np.array(bs.wo), np.array(mi.Spectrum(weight)[0]), np.array(reflection), np.array(bs.sampled_component)


@pytest.mark.parametrize("plugin", PLUGINS)
def test_sampled_type_matches_the_exit_side(mi, plugin):
    """Reflection ⇔ the ray leaves on the side it came from; exits have unit weight, absorption 0."""

    theta = np.radians(8.0)
    wi = np.array([np.sin(theta), 0.0, np.cos(theta)])
    wo, weight, reflection, component = sample_directly(mi, {"type": plugin}, wi)
    exits = weight == 1.0
    assert np.all((weight == 0.0) | exits) and exits.mean() > 0.9
    assert np.all(reflection[exits] == (wo[2, exits] > 0)) and np.all(wo[2, exits] != 0)
    assert np.all(component[exits] == np.where(reflection[exits], 0, 1))
    assert np.allclose(np.linalg.norm(wo[:, exits], axis=0), 1.0, atol=1e-5)


@pytest.mark.parametrize("plugin", PLUGINS)
def test_back_lit_adaxial_equals_front_lit_abaxial(mi, plugin):
    """Light from below an adaxial-up leaf is the same walk as light from above a turned leaf:
    identical exits, mirrored in z — so 'abaxial' reflectance is light leaving the lit side."""

    theta = np.radians(8.0)
    below = np.array([np.sin(theta), 0.0, -np.cos(theta)])
    wo_a, weight_a, refl_a, _ = sample_directly(mi, {"type": plugin, "side": "adaxial"}, below)
    wo_b, weight_b, refl_b, _ = sample_directly(mi, {"type": plugin, "side": "abaxial"}, below * [1, 1, -1])
    assert np.array_equal(weight_a, weight_b) and np.array_equal(refl_a, refl_b)
    exits = weight_a == 1.0
    assert np.array_equal(wo_a[:2, exits], wo_b[:2, exits]) and np.array_equal(wo_a[2, exits], -wo_b[2, exits])
    assert np.all(wo_a[2, exits & refl_a] < 0)  # back-lit adaxial leaf: reflected light goes down


def test_wavelengths_outside_the_data_are_refused(mi):
    for bad in ([399.0], [551.0, 2500.5]):
        with pytest.raises(ValueError, match="400 <= wavelength <= 2500 nm for the specimen abm_b"):
            vm.measure(leaf("abm_b"), wavelengths=bad, rays=10)
    check_reading(vm.measure(leaf("abm_u"), wavelengths=[400, 2500], rays=1000))  # both ends included


def test_step_lookup_reads_the_grid_value_below(mi):
    """551 nm reads the 550 nm data: same seed -> identical counts; linear lookup differs."""

    def counts(lookup, wavelength):
        r = vm.measure(leaf("abm_b", lookup=lookup), wavelengths=wavelength, rays=20_000, seed=4)
        return int(r.reflected[0]), int(r.transmitted[0])

    assert counts("step", 550) == counts("step", 551)
    assert counts("linear", 550) == counts("step", 550)  # on the grid both lookups agree exactly
    assert counts("linear", 553) != counts("step", 553)


def test_one_kernel_for_many_wavelengths(mi):
    """Tables are data: a new set of wavelengths reuses the compiled kernel."""

    scene = mi.load_dict(leaf("abm_b"))
    vm.measure(scene, wavelengths=[500, 600], rays=1000)
    dr.set_flag(dr.JitFlag.KernelHistory, True)
    dr.kernel_history_clear()
    try:
        vm.measure(scene, wavelengths=[650, 1500], rays=1000)
        kernels = [k for k in dr.kernel_history() if k["type"] == dr.KernelType.JIT]
    finally:
        dr.set_flag(dr.JitFlag.KernelHistory, False)
    assert kernels and all(k["cache_hit"] for k in kernels)


@pytest.mark.parametrize(
    "params, message",
    [
        ({"thickness": -1.0}, "'thickness' must be a finite number > 0"),
        ({"mesophyll_fraction": 1.5}, "0 < mesophyll_fraction <= 1"),
        ({"protein": -0.1}, "'protein' must be a finite number >= 0"),
        ({"spongy_aspect_ratio": 0.0}, "'spongy_aspect_ratio' must be a finite number > 0"),
        ({"side": "top"}, "'side' must be 'adaxial' or 'abaxial'"),
        ({"lookup": "cubic"}, "'lookup' must be 'step' or 'linear'"),
        ({"sieve_detour": "yes"}, "'sieve_detour' must be true or false"),
        ({"max_steps": 0}, "'max_steps' must be an integer"),
        ({"data_dir": "/nonexistent/leaf"}, "does not exist; point VIRTSPEC_LEAF_DATA"),
    ],
)
def test_bad_parameters_are_refused(mi, params, message):
    with pytest.raises(SceneError, match=message):
        vm.measure(leaf("abm_b", **params), rays=10)


def test_abm_u_has_no_palisade(mi):
    with pytest.raises(SceneError, match="palisade_aspect_ratio"):
        vm.measure(leaf("abm_u", palisade_aspect_ratio=1.0), rays=10)


def test_defaults_are_soybean_and_corn(mi):
    b = mi.load_dict({"type": "abm_b"})
    u = mi.load_dict({"type": "abm_u"})
    assert b.params["thickness"] == 1.66e-4 and b.params["protein"] == 78.7059 and b.sieve_detour
    assert u.params["thickness"] == 2.04e-4 and u.params["cuticle_aspect_ratio"] == 10.0
    assert np.isclose(b.mesophyll_thickness, 8.3e-5) and b.side == "adaxial" and b.lookup == "step"
    assert "ABMB[" in str(b)


# --- issue 12: numbers float32 cannot hold are refused; huge absorption computes without overflow ----


@pytest.mark.parametrize("params, message", [
    ({"thickness": 1e300}, r"'thickness' must be a finite number > 0 \(a float32"),  # NumPy's overflow warning before
    ({"thickness": 1e-40}, r"'thickness' must be a finite number > 0 \(a float32"),
    ({"protein": True}, "'protein' must be a finite number >= 0"),
    ({"cuticle_aspect_ratio": float("inf")}, "'cuticle_aspect_ratio' must be a finite number > 0"),
])
def test_values_float32_cannot_hold_are_refused(mi, params, message):
    with pytest.raises(SceneError, match=message):
        vm.measure(leaf("abm_b", **params), rays=10)


def test_absorption_beyond_float32_absorbs_without_overflow(mi):
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")  # NumPy's "overflow encountered in cast" was printed here
        reading = vm.measure(leaf("abm_b", thickness=1e30, chlorophyll_a=3e38), rays=2000, wavelengths=[551, 800])
    check_reading(reading)
    assert np.all(reading.transmitted == 0)  # every ray that enters the mesophyll is absorbed
