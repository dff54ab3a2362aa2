"""Scenes loaded once where they enter the API (virtspec_mi.runtime.scene): LoadedScene, fingerprints."""

from __future__ import annotations

import pytest

import virtspec_mi as vm
from virtspec_mi.runtime.scene import LoadedScene, loaded, scene_fingerprint

from mirror_specimen import register_mirror


def test_a_loaded_scene_is_taken_as_it_is(mi):
    once = loaded("diamond_collimated")
    assert isinstance(once, LoadedScene) and loaded(once) is once and once.source["scene"] == "diamond_collimated"
    with pytest.raises(ValueError, match="defines: give them when the scene is loaded"):
        loaded(once, {"alpha": 0.1})
    reading = vm.measure(once, rays=1000)
    assert reading.scene == once.fingerprint


def test_a_dict_holding_a_loaded_python_plugin_has_a_fingerprint(mi):
    """
    A scene dict that holds a loaded BSDF whose Python class has no ``to_string`` (Mitsuba's
    ``repr`` raises): the fingerprint describes it by its class and parameters, the same
    every time (the Klems export's turned-over back side is such a dict).
    """

    name = register_mirror(mi, "mirror_scene_fingerprint", lambda bs, weight, *_: (bs, weight))
    front = loaded(vm.instrument_scene({"type": name}))
    with pytest.raises(RuntimeError):
        repr(front.bench.bsdf)
    holding = [vm.instrument_scene({"type": "twosided", "bsdf": front.bench.bsdf}) for _ in range(2)]
    first, second = loaded(holding[0]), loaded(holding[1])
    assert first.fingerprint == second.fingerprint != front.fingerprint
    assert scene_fingerprint(holding[0], first.bench) == first.fingerprint


def test_a_scene_dict_is_named_by_its_specimen_as_the_dict_writes_it(mi):
    from virtspec_mi.runtime.scene import scene_source

    scene = vm.instrument_scene({"type": "prospect_d"})
    assert scene_source(scene, loaded(scene).bench)["scene"] == "scene dict, specimen prospect_d"  # not ProspectD
    rough = vm.instrument_scene({"type": "roughconductor"})
    assert scene_source(rough, loaded(rough).bench)["scene"] == "scene dict, specimen RoughConductor"
