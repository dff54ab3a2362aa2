"""Tests of virtspec_mi.engine.bench: scenes in, instrument geometry out, clear errors."""

from __future__ import annotations

import pytest

import virtspec_mi as vm
from virtspec_mi.engine.bench import SceneError


@pytest.mark.parametrize("name", ["diamond_conical.xml", "diamond_collimated.xml"])
def test_shipped_scenes_have_the_papers_geometry(mi, scenes_dir, name):
    instrument = vm.find_bench(str(scenes_dir / name))
    g = instrument.geometry
    assert (g.emitter_radius, g.specimen_radius, g.distance) == pytest.approx((8.0, 12.5, 100.0))
    assert instrument.integrator is not None
    assert g.backlit_threshold == pytest.approx(85.4261, abs=1e-4)  # atan(D / r1)


def test_dict_and_loaded_scene_are_accepted(mi):
    scene = vm.instrument_scene({"type": "simple_dielectric"}, emitter_radius=5, specimen_radius=10, distance=50)
    for form in (scene, mi.load_dict(scene)):
        g = vm.find_bench(form).geometry
        assert (g.emitter_radius, g.specimen_radius, g.distance) == pytest.approx((5.0, 10.0, 50.0))


def test_reading_does_not_depend_on_where_the_instrument_stands(mi):
    """Rotate and move the whole instrument: the specimen frame carries the measurement."""

    scene = vm.instrument_scene({"type": "simple_dielectric"})
    moved = dict(scene)
    transform = mi.ScalarTransform4f().translate([3.0, -2.0, 7.0]) @ mi.ScalarTransform4f().rotate([0.6, 0.8, 0.0], 50)
    for key in ("emitter", "specimen"):
        moved[key] = dict(scene[key], to_world=transform @ scene[key]["to_world"])
    a = vm.measure(scene, theta_i=60, phi_i=20, seed=9)
    b = vm.measure(moved, theta_i=60, phi_i=20, seed=9)
    # same random numbers, geometry equal up to float32 rounding: at most a few rays differ
    assert abs(int(a.reflected[0]) - int(b.reflected[0])) <= 5


@pytest.mark.parametrize(
    "scene, message",
    [
        ({"type": "scene", "specimen": {"type": "disk"}}, "no shape with id 'emitter'"),
        ({"type": "scene", "emitter": {"type": "disk"}}, "no shape with id 'specimen'"),
        ({"type": "scene", "emitter": {"type": "disk"}, "specimen": {"type": "disk"},
          "baffle": {"type": "sphere"}}, "remove the other shapes \\['baffle'\\]"),
        ({"type": "scene", "emitter": {"type": "rectangle"}, "specimen": {"type": "disk"}},
         "shape 'emitter' must be a Mitsuba 'disk'"),
        ({"type": "scene", "emitter": {"type": "disk"},
          "specimen": {"type": "disk", "bsdf": {"type": "no_such_bsdf"}}}, 'Plugin "no_such_bsdf" not found'),
        ({"type": "scene", "emitter": {"type": "disk"},
          "specimen": {"type": "disk", "to_world": None}}, "could not load scene"),
    ],
)
def test_bad_scenes_get_clear_errors(mi, scene, message):
    if scene.get("specimen", {}).get("to_world", 1) is None:
        scene["specimen"]["to_world"] = mi.ScalarTransform4f().scale([2.0, 1.0, 1.0])
        message = "disk 'specimen' is not circular"
    with pytest.raises(SceneError, match=message):
        vm.find_bench(scene)


def test_coincident_disks_are_refused(mi):
    with pytest.raises(SceneError, match="distance D must be > 0"):
        vm.find_bench({"type": "scene", "emitter": {"type": "disk"}, "specimen": {"type": "disk"}})


@pytest.mark.parametrize("name", ["emitter_radius", "specimen_radius", "distance"])
@pytest.mark.parametrize("value", [0.0, -1.0, float("inf")])
def test_non_positive_lengths_are_refused(mi, name, value):
    with pytest.raises(ValueError, match=f"{name} must be a finite number > 0"):
        vm.instrument_scene({"type": "diffuse"}, **{name: value})


def test_malformed_and_missing_files(mi, tmp_path):
    bad = tmp_path / "bad.xml"
    bad.write_text('<scene version="3.0.0"><shape type="disk" id="emitter"></scene>')
    with pytest.raises(SceneError, match="could not load scene .*bad.xml.*mismatch"):
        vm.find_bench(str(bad))
    with pytest.raises(SceneError, match="scene file not found"):
        vm.find_bench(str(tmp_path / "missing.xml"))
    with pytest.raises(SceneError, match="scene must be an XML path, a dict or a mitsuba Scene"):
        vm.find_bench(42)


def test_bad_integrator_parameter_names_it(mi):
    scene = vm.instrument_scene({"type": "diffuse"}, integrator={"theta_i": 120.0})
    with pytest.raises(SceneError, match="spectrophotometer: theta_i must satisfy 0 <= theta_i <= 90"):
        vm.find_bench(scene)
