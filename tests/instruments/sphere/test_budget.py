"""
Tests of virtspec_mi.instruments.sphere.budget: a sphere reading's error split into its
sources, each a difference of two readings of the same rays, adding up to the error.
"""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest

import virtspec_mi as vm
from virtspec_mi.instruments.sphere.budget import features_of, ideal_sphere, without

SCENE = "scenes/sphere_150mm_8d.xml"
SETTINGS = {"rays": 4000, "wavelengths": "450, 650", "seed": 4}


def take(sphere, **options):
    return vm.sphere_measure(SCENE, sphere=sphere, **SETTINGS, **options)


@pytest.fixture(scope="module")
def real():
    base = vm.mitsuba().load_file(SCENE).integrator().sphere_options.sphere
    ports = tuple(replace(p, depth=4.0, edge_reflectance=0.0, field_of_view=40.0) if p.role == "detector" else
                  replace(p, aperture=9.0, mask_reflectance=0.1) if p.role == "sample" else p for p in base.ports)
    return base, replace(base, ports=ports, beam_profile="shape=rectangle width=20 height=8 divergence=1",
                         wall_specular=0.3)


def test_features_are_removed_one_at_a_time(real):
    base, sphere = real
    assert features_of(sphere) == ["port_walls", "holder", "beam", "wall", "field_of_view"]
    assert features_of(base) == [] and ideal_sphere(sphere) == base
    assert features_of(without(sphere, "beam")) == ["port_walls", "holder", "wall", "field_of_view"]
    assert without(sphere, "holder").port("detector") == sphere.port("detector")
    with pytest.raises(ValueError, match="feature must be one of port_walls, holder, beam, wall, field_of_view"):
        without(sphere, "baffle")


def test_the_parts_add_up_to_the_error_and_are_paired_differences(real):
    base, sphere = real
    result = take(sphere)
    budget = result.budget(take)
    assert list(budget.parts) == ["port_walls", "holder", "beam", "wall", "field_of_view", "substitution", "ports",
                                  "interactions"]
    assert np.allclose(sum(budget.parts.values()), result.reading - result.hemispherical, rtol=0, atol=1e-12)
    beam = take(without(sphere, "beam"))  # one part, by hand: the reading with and without the beam profile
    assert np.array_equal(budget.parts["beam"], result.reading - beam.reading)
    low, high = result.reading_interval, beam.reading_interval
    assert np.array_equal(budget.intervals["beam"][..., 0], low[..., 0] - high[..., 1])
    assert budget.readings == 9 and budget.joint_confidence == pytest.approx(1 - 9 * result.delta)
    assert all(np.all(i[..., 0] <= v) and np.all(v <= i[..., 1]) for v, i in
               ((budget.parts[k], budget.intervals[k]) for k in budget.parts))
    text = budget.summary()
    assert "union bound over 9 Clopper-Pearson certificates" in text and "interactions" in text
    assert json.dumps(budget.as_dict())


def test_a_plain_sphere_has_no_interactions(real):
    """No feature: the error is the substitution error plus the ideal sphere's own, exactly."""

    base, _ = real
    budget = take(base).budget(take)
    assert list(budget.parts) == ["substitution", "ports", "interactions"]
    assert np.all(np.abs(budget.parts["interactions"]) < 1e-12)


def test_a_budget_needs_the_same_rays(real):
    base, sphere = real
    result = take(sphere)
    with pytest.raises(ValueError, match="not of the same rays"):
        result.budget(lambda s, **o: vm.sphere_measure(SCENE, sphere=s, **{**SETTINGS, "seed": 5}, **o))


def test_the_command_line_prints_the_budget(capsys):
    from virtspec_mi.cli import main

    assert main(["sphere", SCENE, "--rays", "2000", "--wavelengths", "550", "--budget"]) == 0
    out = capsys.readouterr().out
    assert "error budget" in out and "substitution" in out and "ports" in out
