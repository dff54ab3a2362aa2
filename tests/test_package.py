"""The top level of the package (``virtspec_mi/__init__.py``): its public names, tab completion, every result kind."""

from __future__ import annotations

import importlib

import virtspec_mi as vm
from virtspec_mi.results.kinds import KINDS


def test_dir_lists_every_public_name_and_each_resolves():
    assert dir(vm) == sorted(vm.__all__)
    assert len(set(vm.__all__)) == len(vm.__all__)
    for name in vm.__all__:
        assert getattr(vm, name) is not None, name


def test_every_lazy_name_is_the_object_of_the_module_that_defines_it():
    for name, module in vm._LAZY.items():
        assert name in vm.__all__, f"{name} is importable but not listed by dir(vm)"
        assert getattr(vm, name) is getattr(importlib.import_module(module), name)


def test_compare_and_every_result_kind_are_at_the_top():
    from virtspec_mi.comparison import compare
    from virtspec_mi.exchange.albedo import AlbedoTable
    from virtspec_mi.exchange.klems import KlemsMeasurement
    from virtspec_mi.instruments.gloss import GlossResult

    assert vm.compare is compare
    for kind in (*KINDS.values(), AlbedoTable, KlemsMeasurement, GlossResult, vm.Comparison):
        assert getattr(vm, kind.__name__) is kind, kind.__name__


def test_an_unknown_name_is_an_attribute_error_naming_it():
    import pytest

    with pytest.raises(AttributeError, match="no attribute 'mesure'"):
        vm.mesure  # noqa: B018
