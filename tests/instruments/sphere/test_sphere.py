"""Tests of virtspec_mi.instruments.sphere and vm.sphere_measure: the readout, its certificate, its interfaces."""

from __future__ import annotations

import json
import numpy as np
import pytest

import virtspec_mi as vm
from virtspec_mi.instruments.sphere import theory as st
from virtspec_mi.budgets.bounds import hoeffding_mu
from virtspec_mi.instruments.sphere.result import SphereResult

SCENE = "scenes/sphere_150mm_8d.xml"


def test_sphere_options_are_validated():
    from virtspec_mi.instruments.sphere import SphereOptions

    assert SphereOptions(specular="sce").specular == "SCE"
    with pytest.raises(ValueError, match="method must be one of substitution, comparison"):
        SphereOptions(method="double")
    with pytest.raises(ValueError, match="standard must satisfy 0 < standard <= 1"):
        SphereOptions(standard=1.5)
    with pytest.raises(ValueError, match="max_bounces must be a whole number"):
        SphereOptions(max_bounces=0)
    # a numeric string is read as the number, as every setting is; a boolean is not a number
    assert SphereOptions(max_bounces="100", standard="0.5").max_bounces == 100
    for name, value in (("max_bounces", True), ("standard", True), ("sphere", 150.0)):
        with pytest.raises(ValueError, match=name):
            SphereOptions(**{name: value})
    with pytest.raises(TypeError, match="diameter; the sphere options are measurement"):
        SphereOptions().updated(diameter=150)


def test_hemispherical_reading_is_the_measure_of_the_same_rays():
    result = vm.sphere_measure(SCENE, rays=20000, wavelengths="500, 600")
    scene = vm.instrument_scene({"type": "diffuse", "reflectance": 0.5}, specimen_radius=12.7)
    reading = vm.measure(scene, theta_i=8, beam="collimated", rays=20000, wavelengths="500, 600")
    assert np.array_equal(result.counts["sample"]["hemispherical_reflected"], reading.reflected)
    for name in ("sample", "standard"):  # conservation: every ray has one fate
        counts = result.counts[name]
        fates = sum(v for k, v in counts.items() if k in ("detected", "absorbed_wall", "absorbed_specimen",
                                                           "absorbed_other", "capped", "invalid_directions")
                    or k.startswith("lost_"))
        assert np.all(fates == 20000)


def test_sce_excludes_the_fresnel_specular_reflectance():
    import xml.etree.ElementTree as ET

    mi = vm.mitsuba()
    tree = ET.parse(SCENE)
    root = tree.getroot()
    bsdf = root.find("./shape[@id='specimen']/bsdf")
    bsdf.attrib["type"] = "simple_dielectric"
    for child in list(bsdf):
        bsdf.remove(child)
    text = ET.tostring(root, encoding="unicode")
    scene = mi.load_string(text)
    rays, delta = 50_000, 1e-3
    sce = vm.sphere_measure(scene, specular="SCE", rays=rays)
    trapped = sce.counts["sample"]["lost_specular"][0]
    assert trapped == sce.counts["sample"]["hemispherical_reflected"][0]  # every specular ray, exactly
    assert sce.counts["sample"]["hemispherical_specular"][0] == trapped and sce.hemispherical_diffuse[0] == 0
    assert sce.counts["sample"]["detected"][0] == 0
    assert abs(trapped / rays - st.fresnel_reflectance(8.0, 2.419)) < hoeffding_mu(rays, delta)
    sci = vm.sphere_measure(scene, specular="SCI", rays=rays)
    assert sci.counts["sample"]["detected"][0] > 0 and sci.counts["sample"]["lost_specular"][0] == 0


def test_readout_interval_and_result_files(tmp_path):
    result = vm.sphere_measure(SCENE, rays=30000, method="comparison")
    interval = result.reading_interval[0]
    assert interval[0] <= result.reading[0] <= interval[1]
    assert result.reading[0] == pytest.approx(0.99 * result.detector_fraction[0] / result.standard_fraction[0])
    assert result.instrument_error[0] == pytest.approx(result.reading[0] - result.hemispherical[0])
    assert result.fraction_mu[0] == pytest.approx(hoeffding_mu(30000, 0.005))
    assert "NOT CERTIFIED" not in result.summary()
    for suffix in (".json", ".nc"):
        back = SphereResult.read(result.write(tmp_path / f"r{suffix}"))
        assert np.array_equal(back.counts["standard"]["detected"], result.counts["standard"]["detected"])
        assert back.reading == pytest.approx(result.reading)
    assert json.loads(json.dumps(result.as_dict(), allow_nan=False))["format"] == "virtspec-mi sphere 1"


def test_default_rays_certify_each_fraction_at_half_delta():
    from virtspec_mi.budgets.bounds import hoeffding_rays

    result = vm.sphere_measure(SCENE, mu=0.05)
    assert np.all(result.rays == hoeffding_rays(0.05, 0.005))  # per reading and configuration
    assert result.fraction_mu[0] <= 0.05


def test_comparison_removes_most_of_the_substitution_error():
    """A dark grey sample: substitution reads low by several per cent; the comparison method does not."""

    loaded = vm.mitsuba().load_file(SCENE, reflectance="0.2")
    substitution = vm.sphere_measure(loaded, rays=105_967)
    comparison = vm.sphere_measure(loaded, rays=105_967, method="comparison")
    # certified: the substitution reading's interval lies below the hemispherical value's
    assert substitution.reading_interval[0, 1] < 0.2
    assert comparison.reading_interval[0, 0] < 0.2 < comparison.reading_interval[0, 1]


def test_bad_sphere_readings_name_the_problem():
    with pytest.raises(ValueError, match="larger than its port"):
        vm.sphere_measure(vm.instrument_scene({"type": "diffuse"}, specimen_radius=13.0),
                          sphere=_sphere(), rays=100)
    with pytest.raises(ValueError, match="theta_i = 30"):
        vm.sphere_measure(SCENE, theta_i=30, rays=100)
    with pytest.raises(ValueError, match="role 'detector'"):
        vm.sphere_measure(SCENE, sphere=vm.Sphere(150, 0.98, _sphere().ports[:2]), rays=100)
    with pytest.raises(ValueError, match="needs a sphere"):
        vm.sphere_measure(vm.instrument_scene({"type": "diffuse"}), rays=100)
    from virtspec_mi.engine.bench import SceneError

    with pytest.raises(SceneError, match="role must be one of"):
        vm.load_scene({"type": "scene", "integrator": {"type": "integrating_sphere", "diameter": 60.0,
                                                       "port_a": "role=window polar=0 radius=5"}})


def _sphere():
    return vm.Sphere(150, 0.98, (vm.Port("sample", "sample", 180, 0, 12.7),
                                 vm.Port("entrance", "entrance", 15.88, 0, 12.7),
                                 vm.Port("detector", "detector", 90, 90, 6.35)))


def test_cli_sphere(capsys):
    from virtspec_mi.cli import main

    assert main(["sphere", SCENE, "--rays", "2000", "--specular", "SCE", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["options"]["specular"] == "SCE"
    assert data["counts"]["sample"]["rays"] == data["counts"]["standard"]["rays"] == [2000]
    assert main(["sphere", SCENE, "--theta-i", "40", "--rays", "100"]) == 1
    assert "entrance port" in capsys.readouterr().err


def test_the_standard_read_as_a_sample_reads_its_own_value_exactly():
    """Sample = the standard itself: both configurations trace identical rays, so the reading is ρ_std exactly."""

    scene = vm.mitsuba().load_file(SCENE, reflectance="0.99")
    result = vm.sphere_measure(scene, rays=3000)
    assert result.counts["sample"]["detected"][0] == result.counts["standard"]["detected"][0] > 0
    assert result.reading[0] == 0.99


def test_transmittance_of_an_open_port_is_one_and_keeps_the_same_rays():
    leaf = "scenes/sphere_leaf_60mm.xml"
    mi = vm.mitsuba()
    text = open(leaf).read().replace('<bsdf type="abm_b"><string name="data_dir" value="$data_dir"/></bsdf>',
                                     '<bsdf type="null"/>').replace(
        '<default name="data_dir" value=""/>', '')
    result = vm.sphere_measure(mi.load_string(text), measurement="transmittance", theta_i=0, rays=3000)
    assert result.reading[0] == 1.0 and result.hemispherical[0] == 1.0
    grey = text.replace('<bsdf type="null"/>', '<bsdf type="roughdielectric"/>')
    scene = mi.load_string(grey)
    result = vm.sphere_measure(scene, measurement="transmittance", theta_i=0, rays=3000, wavelengths="500, 700")
    reading = vm.measure(scene, theta_i=0, rays=3000, wavelengths="500, 700")
    assert np.array_equal(result.counts["sample"]["hemispherical_transmitted"], reading.transmitted)
    assert np.array_equal(result.wall_reflectance, [0.9766666666666667, 0.99])
    assert result.counts["sample"]["lost_entrance"][0] > 0  # reflected by the specimen, out of the sphere


def test_capped_walks_are_counted_apart_and_not_certified():
    result = vm.sphere_measure(SCENE, rays=2000, max_bounces=2)
    capped = result.counts["sample"]["capped"][0]
    assert capped > 0 and not result.certified[0]
    assert np.isnan(result.reading_interval[0]).all() and np.isnan(result.fraction_mu[0])
    assert "NOT CERTIFIED" in result.summary()
    data = json.loads(json.dumps(result.as_dict(), allow_nan=False))
    assert data["fraction_mu"] == [None] and data["counts"]["sample"]["capped"] == [int(capped)]


def test_a_scene_dict_gives_the_counts_of_the_xml_scene():
    mi = vm.mitsuba()
    xml = mi.load_file(SCENE)
    integrator = xml.integrator()
    scene = vm.instrument_scene({"type": "diffuse", "reflectance": 0.5}, specimen_radius=12.7)
    scene["integrator"] = {"type": "integrating_sphere", "theta_i": 8.0, "beam": "collimated",
                           **integrator.sphere_options.sphere.parameters()}
    from_dict = vm.sphere_measure(scene, rays=3000)
    from_xml = vm.sphere_measure(xml, rays=3000)
    assert from_dict.counts["sample"]["detected"] == from_xml.counts["sample"]["detected"]
    assert from_dict.counts["standard"]["wall_reflections"] == from_xml.counts["standard"]["wall_reflections"]


def test_two_stage_sizes_each_configurations_detector_fraction():
    """Two-stage: each configuration's N from its pilot's detector fraction at delta/2; the same rays in both."""

    scene = vm.mitsuba().load_file(SCENE, reflectance="0.99")  # the sample is the standard itself
    result = vm.sphere_measure(scene, bound="two-stage", mu=0.01, wavelengths="500, 600")
    assert result.pilot is not None and np.all(result.pilot["sample"]["rays"] == 1000)  # ceil(10/mu)
    assert np.array_equal(result.counts["sample"]["rays"], result.counts["standard"]["rays"])
    assert np.all(result.reading == 0.99)  # identical configurations, identical rays, identical N
    assert np.all(result.fraction_mu == pytest.approx(0.01))
    grey = vm.sphere_measure(SCENE, bound="two-stage", mu=0.01, wavelengths="500")
    assert grey.counts["sample"]["rays"][0] != grey.counts["standard"]["rays"][0]  # each sized from its own pilot


def test_a_two_stage_reading_and_its_pilot_are_written_and_read_back(tmp_path):
    """The pilot's counts are its first interactions' fates, held to their own rules: every format reads back."""

    result = vm.sphere_measure(SCENE, bound="two-stage", mu=0.05, wavelengths="500, 600", seed=3)
    for suffix in (".nc", ".json", ".csv"):
        back = vm.read_result(result.write(tmp_path / f"two_stage{suffix}"))
        for configuration in ("sample", "standard"):
            for name, values in result.pilot[configuration].items():
                assert np.array_equal(back.pilot[configuration][name], values), (suffix, configuration, name)
        assert back.summary() == result.summary()


def test_a_sphere_reading_over_theta_i_and_parameters_is_keyed_like_a_sweep():
    """Several theta_i and specimen parameter points: labelled dims, each reading the one-angle reading's counts."""

    scene = vm.instrument_scene({"type": "roughdielectric", "alpha": 0.3, "int_ior": 1.5}, specimen_radius=12.7)
    scene["integrator"] = {"type": "integrating_sphere", "beam": "collimated",
                           **vm.mitsuba().load_file(SCENE).integrator().sphere_options.sphere.parameters()}
    both = vm.sphere_measure(scene, theta_i=[8, 12], wavelengths="500, 600", rays=3000,
                             parameters={"specimen.alpha": [0.2, 0.4]})
    assert both.dims == ("wavelength", "theta_i", "specimen.alpha", "configuration")
    assert both.counts["sample"]["detected"].shape == (2, 2, 2)
    one = vm.sphere_measure(scene, theta_i=8, wavelengths="500, 600", rays=3000, parameters={"specimen.alpha": [0.2]})
    assert np.array_equal(one.counts["sample"]["detected"][:, 0], both.counts["sample"]["detected"][:, 0, 0])
    with pytest.raises(ValueError, match="theta_i = 40"):
        vm.sphere_measure(scene, theta_i=[8, 40], rays=100)


def test_a_tolerance_on_the_reading_is_met_with_the_rays_a_pilot_sized(tmp_path):
    """
    tolerance=: a pilot (the seed's second stream) sizes N for the reading's interval to
    lie within ±tolerance; the reading is then the same call's with rays=N (the same
    counts), its pilot kept beside it, the tolerance met and stated, and the file says it too.
    """

    result = vm.sphere_measure(SCENE, tolerance=0.02, wavelengths=[450, 650], seed=2)
    interval, reading = result.reading_interval, result.reading
    assert result.tolerance == 0.02 and np.all(result.tolerance_met)
    assert np.all(np.maximum(reading - interval[..., 0], interval[..., 1] - reading) <= 0.02)
    assert np.all(result.pilot["sample"]["rays"] == 50_000) and np.all(result.pilot["standard"]["rays"] == 50_000)
    rays = int(result.counts["sample"]["rays"].flat[0])
    assert np.all(result.rays == rays) and 10_000 < rays < 5_000_000
    same = vm.sphere_measure(SCENE, rays=rays, wavelengths=[450, 650], seed=2)
    for configuration in ("sample", "standard"):
        assert np.array_equal(same.counts[configuration]["detected"], result.counts[configuration]["detected"])
    assert np.all(result.fraction_mu == pytest.approx(hoeffding_mu(rays, 0.005)))  # what N guarantees, not mu
    text = result.summary()
    assert "tolerance +-0.02 on the reading (rays sized by a pilot of 50,000 per configuration): met by every" in text
    result.write(tmp_path / "tolerance.nc")
    back = vm.read_result(tmp_path / "tolerance.nc")
    assert back.tolerance == 0.02 and np.array_equal(back.tolerance_met, result.tolerance_met)
    assert back.summary() == text


def test_a_tolerance_is_refused_beside_rays_a_two_stage_bound_or_expected_scores():
    for extra in ({"rays": 1000}, {"bound": "two-stage"}, {"detector": "expected"}):
        with pytest.raises(ValueError, match="tolerance = 0.02 sizes the rays from a pilot of counted detector"):
            vm.sphere_measure(SCENE, tolerance=0.02, wavelengths=[550], **extra)
    for bad in (0, 1, -0.1, "wide"):
        with pytest.raises(ValueError, match="tolerance"):
            vm.sphere_measure(SCENE, tolerance=bad, wavelengths=[550])
