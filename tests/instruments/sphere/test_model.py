"""
Tests of virtspec_mi.instruments.sphere.model: the one rule from a sphere description to the sphere
theory's inputs, and the simulation validated against virtspec_mi.instruments.sphere.theory with it —
readings of grey samples (substitution error, comparison residual), the leaf sphere's
transmittance, and the correction of instrument readings (SphereResult.corrected) on the
ABM leaf and the turbid slab.

Tolerances are the certificates: a reading's interval (each detector fraction at δ/2,
Clopper–Pearson, union bound) holds the expected reading with probability ≥ 1 − δ; the
correction is increasing, so that interval's ends map to an interval that holds the
corrected expected reading.
"""

from __future__ import annotations

import dataclasses
import re
from pathlib import Path

import numpy as np
import pytest

import virtspec_mi as vm
from virtspec_mi.instruments.sphere import theory as st
from virtspec_mi.instruments.sphere.geometry import Port, Sphere
from virtspec_mi.instruments.sphere import SphereOptions
from virtspec_mi.instruments.sphere.model import correct_readings, disk_share, invertible_range, theory_inputs

ROOT = Path(__file__).resolve().parents[3]
LAB, LEAF = "scenes/sphere_150mm_8d.xml", "scenes/sphere_leaf_60mm.xml"
RAYS, DELTA = 105_967, 1e-3
SLAB = {"type": "turbid_slab", "mu_a": 1.0, "mu_s": 100.0, "g": 0.75, "thickness": 0.1, "eta": 1.4}


def loaded(path):
    mi = vm.mitsuba()
    scene = mi.load_file(str(ROOT / path))
    options = scene.integrator().sphere_options
    return scene, options.sphere, options


def with_specimen(path: str, bsdf: str):
    text = (ROOT / path).read_text()
    text = re.sub(r'<bsdf type="[a-z_]+">.*?</bsdf>', bsdf, text, flags=re.S)
    return vm.mitsuba().load_string(text.replace('<default name="data_dir" value=""/>', ''))


def slab_xml(slab=SLAB) -> str:
    values = "".join(f'<float name="{k}" value="{v}"/>' for k, v in slab.items() if k != "type")
    return f'<bsdf type="turbid_slab">{values}</bsdf>'


# ------------------------------------------------------------------------------ the mapping
def test_the_150mm_sphere_maps_its_ports_by_role():
    _, sphere, options = loaded(LAB)
    cap = {p.role: sphere.cap_fraction(p) for p in sphere.ports}
    sci = theory_inputs(sphere, options, [551.0])
    assert sci["sample_fraction"] == cap["sample"] and sci["detector_fraction"] == cap["detector"]
    assert sci["open_fraction"] == cap["entrance"] and sci["trap_fraction"] == cap["specular"]
    assert sci["reference_fraction"] == cap["reference"]  # a plug in substitution: wall in the theory
    assert (sci["method"], sci["mode"], sci["port_surface"], sci["standard_reflectance"]) == \
        ("substitution", "SCI", "flat", 0.99)
    assert np.array_equal(sci["wall_reflectance"], [0.98])
    # every keyword is one the theory takes, and the forward model runs on them
    assert 0 < st.instrument_reading(0.5, **sci) < 0.5
    sce = theory_inputs(sphere, options.updated(specular="SCE", method="comparison"), [400, 700])
    assert sce["mode"] == "SCE" and sce["method"] == "comparison" and sce["wall_reflectance"].shape == (2,)
    assert st.comparison_reading(0.5, **{k: v for k, v in sce.items() if k != "method"}).shape == (2,)


def test_the_leaf_sphere_maps_transmittance_and_spectral_walls():
    _, sphere, options = loaded(LEAF)
    kw = theory_inputs(sphere, options.updated(measurement="transmittance"), [400, 550, 900])
    assert set(kw) == {"wall_reflectance", "entrance_fraction", "sample_fraction", "detector_fraction",
                       "open_fraction", "standard_reflectance", "port_surface"}
    assert kw["entrance_fraction"] == sphere.cap_fraction("entrance") and kw["open_fraction"] == 0.0
    assert kw["wall_reflectance"] == pytest.approx([0.97, 0.98, 0.99])
    assert 0 < st.transmittance_reading(0.4, sample_reflectance=0.5, **kw)[0] < 1


def test_a_disk_smaller_than_its_port_leaves_an_open_ring():
    sphere = Sphere(60, 0.98, (Port("s", "sample", 180, 0, 10), Port("e", "entrance", 15.54, 0, 10),
                               Port("d", "detector", 90, 90, 4)))
    a = sphere.cap_fraction("s")
    assert disk_share(sphere, "s", 10.0) == a
    assert disk_share(sphere, "s", 5.0) == pytest.approx(25 / (4 * 900 * (1 - a)), rel=1e-12)
    kw = theory_inputs(sphere, SphereOptions(), [551.0], specimen_radius=5.0)
    assert kw["sample_fraction"] + kw["open_fraction"] == pytest.approx(a + sphere.cap_fraction("e"), rel=1e-12)
    with pytest.raises(ValueError, match="disk_radius must satisfy"):
        disk_share(sphere, "s", 11.0)
    with pytest.raises(ValueError, match="role 'detector'"):
        theory_inputs(Sphere(60, 0.98, sphere.ports[:2]), SphereOptions(), [551.0])


def test_correct_readings_inverts_and_clips_to_the_invertible_range():
    _, sphere, options = loaded(LEAF)
    kw = theory_inputs(sphere, options, [550.0, 850.0])
    x = np.array([0.1, 0.45])
    readings = st.instrument_reading(x, **kw)
    assert correct_readings(readings, kw) == pytest.approx(x, abs=1e-12)
    low, high = invertible_range(kw)
    both = correct_readings(np.stack([readings - 1.0, high + 0.1], axis=-1), kw)  # beyond the range: its ends
    assert both == pytest.approx(np.array([[0.0, 1.0], [0.0, 1.0]]), abs=1e-12)
    assert np.isnan(correct_readings(np.array([np.nan, readings[1]]), kw)[0])
    # a given diffuse-light reflectance u = x + r: the linear inverse is the theory's inverse
    for method, mode, r in (("substitution", "SCI", 0.04), ("substitution", "SCE", 0.04), ("comparison", "SCI", 0.0)):
        lab = theory_inputs(loaded(LAB)[1], SphereOptions(method=method, specular=mode), [550.0, 850.0])
        m = st.instrument_reading(x, specular_reflectance=r, **lab)
        assert correct_readings(m, lab, specular_reflectance=r, sample_reflectance=x + r) == \
            pytest.approx(x + r, abs=1e-12)
    # per-wavelength specular parts with an interval (n, 2): each row brackets its corrected point
    lab = theory_inputs(loaded(LAB)[1], SphereOptions(), [550.0, 850.0])
    r = np.array([0.04, 0.05])
    m = st.instrument_reading(x, specular_reflectance=r, **lab)
    for u in (None, x + r):
        rows = correct_readings(np.stack([m - 0.01, m + 0.01], axis=-1), lab, specular_reflectance=r,
                                sample_reflectance=u)
        assert np.all(rows[:, 0] < x + r) and np.all(x + r < rows[:, 1])
    with pytest.raises(ValueError, match="sample_reflectance must satisfy"):
        correct_readings(readings, kw, sample_reflectance=1.5)
    kt = theory_inputs(sphere, options.updated(measurement="transmittance"), [550.0])
    with pytest.raises(ValueError, match="sample_reflectance is required"):
        correct_readings(0.5, kt)


# ------------------------------------------------ grey samples: substitution and comparison
def unbaffled_lab():
    """The 150 mm sphere without its baffle: the theory's sphere (it models no baffle)."""

    _, sphere, _ = loaded(LAB)
    return dataclasses.replace(sphere, baffle=None)


def grey_reading(rho, method, sphere):
    scene = with_specimen(LAB, f'<bsdf type="diffuse"><float name="reflectance" value="{rho}"/></bsdf>')
    return vm.sphere_measure(scene, sphere=sphere, rays=RAYS, delta=DELTA, method=method)


GREYS = [0.05, 0.15, 0.25, 0.35, 0.45, 0.55, 0.65, 0.75, 0.85, 0.95]


@pytest.mark.parametrize("rho", [0.45, *(pytest.param(g, marks=pytest.mark.slow) for g in GREYS if g != 0.45)])
def test_grey_substitution_error_and_comparison_residual_match_the_theory(rho):
    """
    Single-beam substitution reads low by the theory's substitution error (flat model,
    exact cap fractions: M = ρ((1 − a_s) − ρw a_w L(ρ_std))/((1 − a_s) − ρw a_w L(ρ))); the
    comparison method (standard in the reference port, swapped with the sample) reads the
    theory's small flat-geometry residual M = (1 − a_r(1 − ρ_std)) ρ/L(ρ) instead. Both
    theory values lie in the certified reading intervals; the substitution value lies
    outside the comparison interval (the comparison method removes the error) wherever
    the error exceeds the interval's half-width.
    """

    sphere = unbaffled_lab()
    substitution, comparison = (grey_reading(rho, method, sphere) for method in ("substitution", "comparison"))
    for result in (substitution, comparison):
        assert result.certified[0] and result.hemispherical_interval[0, 0] <= rho <= result.hemispherical_interval[0, 1]
        predicted = st.instrument_reading(rho, **result.theory_inputs())[0]
        low, high = result.reading_interval[0]
        assert low <= predicted <= high, (result.options["method"], predicted, low, high)
    kw = substitution.theory_inputs()
    error = st.instrument_reading(rho, **kw)[0] - rho
    residual = st.instrument_reading(rho, **dict(kw, method="comparison"))[0] - rho
    assert error < 0 < residual < abs(error) / 10  # the theory's orders: G a (ρ_std − ρ) against a (ρ_std − ρ)
    low, high = comparison.reading_interval[0]
    if abs(error) > (high - low) / 2:
        assert not low <= rho + error <= high


def test_sce_on_a_dielectric_excludes_the_fresnel_reflectance():
    """SCE on simple_dielectric (η = 1.5): the light trap takes the Fresnel reflectance at 8° (theory's function)."""

    scene = with_specimen(LAB, '<bsdf type="simple_dielectric"><float name="eta" value="1.5"/></bsdf>')
    sce = vm.sphere_measure(scene, specular="SCE", rays=RAYS, delta=DELTA)
    trapped = sce.counts["sample"]["lost_specular"][0]
    assert trapped == sce.counts["sample"]["hemispherical_specular"][0]
    from virtspec_mi.budgets.intervals import clopper_pearson

    low, high = clopper_pearson(np.array([trapped]), RAYS, DELTA)
    assert low[0] <= st.fresnel_reflectance(8.0, 1.5) <= high[0]


# -------------------------------------------------------------- the leaf sphere's transmittance
def abaxial_diffuse_reflectance(wavelengths: str) -> np.ndarray:
    """The leaf's reflectance for diffuse light on the face the sphere sees in transmittance."""

    leaf = vm.instrument_scene({"type": "abm_b", "side": "abaxial"})
    return np.ravel(vm.measure(leaf, beam="diffuse", rays=RAYS, wavelengths=wavelengths).reflectance)


def test_leaf_transmittance_reads_high_as_the_theory_says():
    """
    The leaf at the entrance port, referenced to the open port (Kessel 1986's one-port
    sphere): the leaf returns into the sphere the light the open port lost, so the sphere
    is brighter with the leaf than for the 100 % line and the reading is high — by the
    theory's factor for this 60 mm sphere with 20 mm ports (ρw = 0.99 at 850 nm).
    """

    scene, _, _ = loaded(LEAF)
    result = vm.sphere_measure(scene, measurement="transmittance", theta_i=0, rays=RAYS, delta=DELTA,
                               wavelengths="850")
    u = abaxial_diffuse_reflectance("850")
    predicted = st.transmittance_reading(result.hemispherical, sample_reflectance=u, **result.theory_inputs())
    low, high = result.reading_interval[0]
    assert low <= predicted[0] <= high
    assert result.instrument_error[0] > 0.2 and result.hemispherical[0] < low  # certified: far above


# ------------------------------------------------------------------------------ the correction
def check_corrected(result, **assumptions):
    """Corrected interval holds the same rays' hemispherical value; the uncorrected interval does not."""

    corrected = result.corrected(**assumptions)
    interval = result.corrected_interval(**assumptions)
    hemispherical = result.hemispherical
    assert np.all(interval[:, 0] <= corrected) and np.all(corrected <= interval[:, 1])
    assert np.all(interval[:, 0] <= hemispherical) and np.all(hemispherical <= interval[:, 1]), \
        (corrected, interval, hemispherical)
    reading = result.reading_interval
    assert np.all((hemispherical < reading[:, 0]) | (hemispherical > reading[:, 1]))
    assert np.all(np.abs(corrected - hemispherical) < np.abs(result.instrument_error) / 3)
    return corrected - hemispherical


def test_corrected_leaf_readings_match_the_hemispherical_readings():
    scene, _, _ = loaded(LEAF)
    reflectance = vm.sphere_measure(scene, rays=RAYS, delta=DELTA, wavelengths="550, 850")
    residual = check_corrected(reflectance)
    # the leaf is not Lambertian: it reflects the sphere's diffuse light with more than its 8° reflectance
    # (0.53 against 0.49 at 850 nm); told so, the correction lowers its value there (the Lambertian
    # one is biased high). The shift is a function of this reading and u (not of the noise both
    # residuals share): 0.0043-0.0095 over seeds 0-11 with either walk generator (issue 25), so > 0.003.
    # (Whether |told| < |Lambertian residual| / 2 in one reading is chance: 4 of those 12 seeds each.)
    adaxial = np.ravel(vm.measure(vm.instrument_scene({"type": "abm_b"}), beam="diffuse", rays=RAYS,
                                  wavelengths="550, 850").reflectance)
    assert adaxial[1] > reflectance.hemispherical[1] + 0.02
    told = check_corrected(reflectance, sample_reflectance=adaxial)
    assert told[1] < residual[1] - 0.003
    transmittance = vm.sphere_measure(scene, measurement="transmittance", theta_i=0, rays=RAYS, delta=DELTA,
                                      wavelengths="550, 850")
    check_corrected(transmittance, sample_reflectance=abaxial_diffuse_reflectance("550, 850"))


def test_corrected_slab_readings_match_the_hemispherical_readings():
    """turbid_slab (η = 1.4): its Fresnel reflection is the specular part the correction is told."""

    scene = with_specimen(LEAF, slab_xml())
    r = st.fresnel_reflectance(8.0, SLAB["eta"])
    reflectance = vm.sphere_measure(scene, rays=RAYS, delta=DELTA, wavelengths="550")
    assert reflectance.fraction("hemispherical_specular")[0] == pytest.approx(r, abs=0.005)
    check_corrected(reflectance, specular_reflectance=r)
    transmittance = vm.sphere_measure(scene, measurement="transmittance", theta_i=0, rays=RAYS, delta=DELTA,
                                      wavelengths="550")
    u = np.ravel(vm.measure(vm.instrument_scene(SLAB), beam="diffuse", rays=RAYS, wavelengths="550").reflectance)
    check_corrected(transmittance, sample_reflectance=u)


def test_the_correction_travels_with_the_result_file(tmp_path):
    scene, sphere, _ = loaded(LEAF)
    result = vm.sphere_measure(scene, rays=3000, wavelengths="550, 850")
    assert result.sphere_description == sphere and result.specimen_radius == 10.0
    for suffix in (".json", ".nc"):
        back = type(result).read(result.write(tmp_path / f"r{suffix}"))
        assert back.sphere_description == sphere
        assert np.array_equal(back.corrected(), result.corrected())
    empty = vm.SphereResult._of(result.data.assign_attrs(sphere_parameters={}))  # a result written without it
    with pytest.raises(ValueError, match="no sphere description"):
        empty.corrected()


@pytest.mark.slow
def test_the_manuals_validation_tables_are_the_tool_output():
    import importlib.util

    spec = importlib.util.spec_from_file_location("sphere_validation", ROOT / "tools" / "sphere_validation.py")
    tool = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(tool)
    readme = (ROOT / "docs" / "guide" / "sphere.md").read_text().splitlines()  # the manual's sphere page
    for table in (tool.ideal_table(), tool.grey_table(), tool.correction_table()):
        rows = table.splitlines()
        assert rows[0] in readme, "the table's header is not in the manual's sphere page"
        start = readme.index(rows[0])
        for made, shown in zip(rows, readme[start:start + len(rows)], strict=True):
            _same_row(made, shown)


def _same_row(made: str, shown: str) -> None:
    """
    A table row as the tool makes it and as the README shows it: the same text between the
    numbers, and numbers within 5e-4. The walk's float32 arithmetic differs between SIMD
    widths (AVX2 / AVX-512), which can move a few of the rays of a reading: the README's
    tables were made on one machine; another gives the same rows up to the last digit.
    """

    number = re.compile(r"[-+]?\d+\.\d+")
    assert number.sub("#", made) == number.sub("#", shown), (made, shown)
    for a, b in zip(number.findall(made), number.findall(shown), strict=True):
        assert abs(float(a) - float(b)) <= 5e-4, (made, shown)
