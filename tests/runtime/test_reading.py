"""
The run keywords (virtspec_mi/runtime/reading.py: RunOptions), declared once: the API's run
functions' signatures are built from them, the settings and the instrument's options, and
take them apart with RunOptions.split.
"""

from __future__ import annotations

import inspect

import pytest

import virtspec_mi as vm
from virtspec_mi.instruments import commanding
from virtspec_mi.runtime.reading import RunOptions
from virtspec_mi.settings import Settings

RUN = ("theta_i", "parameters", "points", "defines", "checkpoint", "out", "progress", "workers", "task_readings")


def test_the_run_keywords_are_declared_once_with_their_defaults():
    assert RunOptions.names() == RUN
    defaults = {p.name: p.default for p in RunOptions.keyword_parameters()}
    assert defaults == {**dict.fromkeys(RUN), "points": False}
    run, rest = RunOptions.split({"theta_i": 8, "rays": 100, "cone": 2})
    assert run == {**dict.fromkeys(RUN), "points": False, "theta_i": 8} and rest == {"rays": 100, "cone": 2}
    run, rest = RunOptions.split({"theta_i": 8, "progress": True}, only=("progress",))
    assert run == {"progress": True} and rest == {"theta_i": 8}


@pytest.mark.parametrize("function, options", [
    (vm.sweep, None), (vm.gonio, "gonio"), (vm.sphere_measure, "sphere_measure"), (vm.gloss, "gloss")])
def test_every_run_function_lists_every_keyword(function, options):
    parameters = inspect.signature(function).parameters
    declared = [*RUN, *Settings.names(), *(() if options is None else commanding(options).options.names())]
    assert set(declared) <= set(parameters) and len(parameters) == len(set(parameters))
    assert parameters["points"].default is False and parameters["rays"].default is None
    assert all(p.kind is p.KEYWORD_ONLY for name, p in parameters.items() if name != "scene")


def test_measure_and_take_list_their_own():
    measure = inspect.signature(vm.measure).parameters
    assert {"target", "parameters", "defines", "progress", "theta_i", *Settings.names()} == set(measure) - {"scene"}
    take = inspect.signature(vm.take).parameters
    assert list(take)[:2] == ["instrument", "scene"] and set(RUN) <= set(take)
    assert take["options"].kind is inspect.Parameter.VAR_KEYWORD


def test_a_keyword_measure_does_not_take_is_refused_naming_it():
    with pytest.raises(TypeError, match="measure\\(\\) got unexpected keyword argument\\(s\\) checkpoint"):
        vm.measure("diamond_conical", checkpoint="x.json")
