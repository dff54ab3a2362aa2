"""
Tests of virtspec_mi.instruments.sphere.double: the double_sphere instrument's options and their refusals,
its budget, the command line, and the same specimen's single- and double-sphere readings side by side.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

import virtspec_mi as vm
from virtspec_mi.instruments.sphere.double import DoubleSphereOptions, single_and_double
from virtspec_mi.instruments.sphere.geometry import Port, Sphere

SCENE = "double_sphere_leaf"


def test_the_shipped_scene_gives_both_spheres():
    result = vm.double_sphere(SCENE, wavelengths=[850], rays=2000, seed=1)
    assert result.sphere_description.port("sample").radius == 5.0
    assert result.transmittance_description.port("entrance").radius == 5.0
    assert result.counts["sample"]["rays"].tolist() == [2000]
    assert 0.0 < result.reflectance[0] < 1.0 and 0.0 < result.transmittance[0] < 1.5


def test_the_budget_certifies_each_of_four_fractions_at_a_quarter_of_delta():
    from virtspec_mi.budgets.bounds import hoeffding_mu

    result = vm.double_sphere(SCENE, wavelengths=[850], mu=0.05, delta=0.1, seed=1)
    n = int(result.counts["sample"]["rays"][0])
    assert hoeffding_mu(n, 0.1 / 4) <= 0.05 < hoeffding_mu(n - 1, 0.1 / 4)
    assert result.fraction_delta == pytest.approx(0.025)
    with pytest.raises(ValueError, match="sized in advance"):
        vm.double_sphere(SCENE, wavelengths=[850], bound="two-stage", mu=0.05, seed=1)


@pytest.mark.parametrize("changes, message", [
    ({"transmittance_sphere": None}, "needs two spheres"),
    ({"transmittance_sphere": Sphere(30, 0.98, (Port("detector", "detector", 90, 90, 2.0),))},
     "transmittance_sphere: a double sphere needs ports with roles entrance, detector"),
    ({"transmittance_sphere": Sphere(30, 0.98, (Port("entrance", "entrance", 0, 0, 5.0),
                                                Port("detector", "detector", 90, 90, 2.0, depth=3.0)))},
     "ideal spheres"),
    ({"transmittance_sphere": Sphere(30, 0.98, (Port("entrance", "entrance", 0, 0, 4.0),
                                                Port("detector", "detector", 90, 90, 2.0)))},
     "larger than transmittance_sphere's port"),
    ({"theta_i": 40}, "entrance port"),
    ({"beam": "diffuse"}, "collimated"),
])
def test_what_a_double_sphere_cannot_take_is_refused_naming_it(changes, message):
    keywords = {"wavelengths": [550], "rays": 100, **changes}
    if "transmittance_sphere" in changes and changes["transmittance_sphere"] is None:
        keywords["transmittance_sphere"] = None
        scene = vm.instrument_scene({"type": "diffuse"}, specimen_radius=5.0)
        keywords["sphere"] = Sphere(30, 0.98, (Port("sample", "sample", 180, 0, 5.0),
                                              Port("entrance", "entrance", 15.54, 0, 2.0),
                                              Port("detector", "detector", 90, 90, 2.0)))
        with pytest.raises(ValueError, match=message):
            vm.double_sphere(scene, **{k: v for k, v in keywords.items() if v is not None})
        return
    with pytest.raises(ValueError, match=message):
        vm.double_sphere(SCENE, **keywords)


def test_single_and_double_readings_side_by_side():
    """The recipe: the double sphere, then each sphere alone with the same settings and seed."""

    readings = single_and_double(vm.take, SCENE, wavelengths=[850], rays=3000, seed=2)
    double, r, t = readings["double"], readings["reflectance"], readings["transmittance"]
    assert r.options["measurement"] == "reflectance" and t.options["measurement"] == "transmittance"
    assert r.sphere_description == double.sphere_description
    assert t.sphere_description == double.transmittance_description
    # the same rays meet the same specimen first: the hemispherical values of the same rays are equal
    assert r.hemispherical[0] == pytest.approx(double.hemispherical_reflectance[0], abs=0)
    assert t.hemispherical[0] == pytest.approx(double.hemispherical_transmittance[0], abs=0)
    options = DoubleSphereOptions(sphere=double.sphere_description,
                                  transmittance_sphere=double.transmittance_description)
    assert options.single()[1]["sphere"] == double.transmittance_description


def test_cli_double_sphere(capsys):
    from virtspec_mi.cli import main

    assert main(["double_sphere", SCENE, "--rays", "1500", "--wavelengths", "850", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["format"] == "virtspec-mi double sphere 1"
    assert data["counts"]["open"]["rays"] == [1500]
    assert np.isfinite(data["transmittance"][0])
    assert main(["double_sphere", SCENE, "--rays", "100", "--theta-i", "40"]) == 1
    assert "entrance port" in capsys.readouterr().err


def test_two_dask_workers_give_the_same_counts():
    """The layouts are plain values: pickled to workers, they walk the same rays to the same fates."""

    keywords = {"wavelengths": [550, 850, 1650], "rays": 2000, "seed": 4}
    here, there = vm.double_sphere(SCENE, **keywords), vm.double_sphere(SCENE, workers=2, **keywords)
    for configuration, named in here.counts.items():
        for name, values in named.items():
            assert np.array_equal(values, there.counts[configuration][name]), (configuration, name)
