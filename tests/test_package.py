"""The top level of the package (``virtspec_mi/__init__.py``): its public names, tab completion, every result kind."""

from __future__ import annotations

import importlib

import virtspec_mi as vm
from virtspec_mi.results.kinds import KINDS


def test_dir_lists_every_public_name_and_each_resolves():
    from virtspec_mi.api import aliases

    assert dir(vm) == sorted({*vm.__all__, *aliases()})  # the API functions generated from the registry too
    assert "gloss" in aliases() and callable(vm.gloss)
    assert len(set(vm.__all__)) == len(vm.__all__)
    for name in vm.__all__:
        assert getattr(vm, name) is not None, name


def test_every_lazy_name_is_the_object_of_the_module_that_defines_it():
    for name, module in vm._LAZY.items():
        assert name in vm.__all__, f"{name} is importable but not listed by dir(vm)"
        assert getattr(vm, name) is getattr(importlib.import_module(module), name)


def test_compare_and_every_result_kind_are_at_the_top():
    from virtspec_mi.applications.comparison import compare
    from virtspec_mi.applications.tables.table import AlbedoTable
    from virtspec_mi.applications.klems.matrices import KlemsMeasurement
    from virtspec_mi.instruments.gloss import GlossResult

    assert vm.compare is compare
    for kind in (*KINDS.values(), AlbedoTable, KlemsMeasurement, GlossResult, vm.Comparison):
        assert getattr(vm, kind.__name__) is kind, kind.__name__


def test_the_instruments_own_names_come_from_the_registry_not_the_api():
    """``vm.GonioResult``, ``vm.Sphere`` …: the registry's ``exports``, reached by the root itself (issue 29)."""

    from virtspec_mi import api
    from virtspec_mi.instruments import exported, exports

    assert not {"exported", "exports"} & set(api.__all__)
    names = exports()
    assert {"GonioResult", "Sphere", "Port", "Baffle", "SphereResult", "GlossResult"} <= set(names) <= set(dir(vm))
    for name in names:
        assert getattr(vm, name) is exported(name)


def test_an_unknown_name_is_an_attribute_error_naming_it():
    import pytest

    with pytest.raises(AttributeError, match="no attribute 'mesure'"):
        vm.mesure  # noqa: B018


def test_make_lab_opens_the_notebooks_with_the_notebook_extra():
    """``make lab`` installs the ``notebook`` extra (JupyterLab) into .venv when missing, then opens notebooks/."""

    import subprocess
    import tomllib
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    extras = tomllib.loads((root / "pyproject.toml").read_text())["project"]["optional-dependencies"]
    assert any(requirement.startswith("jupyterlab") for requirement in extras["notebook"])
    plan = subprocess.run(["make", "-n", "lab"], cwd=root, capture_output=True, text=True)
    assert plan.returncode == 0, plan.stderr
    assert "notebook]" in plan.stdout and "jupyter lab notebooks" in plan.stdout


def test_the_project_has_a_bsd_3_clause_licence_in_its_metadata_and_the_leaf_data_keeps_its_own():
    import tomllib
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    text = (root / "LICENSE").read_text()
    assert text.startswith("BSD 3-Clause License") and "the virtspec-mi developers" in text
    assert "Neither the name of the copyright holder" in text
    project = tomllib.loads((root / "pyproject.toml").read_text())["project"]
    assert project["license"] == "BSD-3-Clause"
    assert project["license-files"] == ["LICENSE", "virtspec_mi/data/abm-npsg/LICENSE",
                                        "virtspec_mi/data/prospect-d/LICENSE"]
    assert "Natural Phenomena Simulation Group" in (root / "virtspec_mi/data/abm-npsg/LICENSE").read_text()
    prospect = (root / "virtspec_mi/data/prospect-d/LICENSE").read_text()
    assert "MIT License\n\nCopyright (c) 2020-present Jean-Baptiste Féret\n" in prospect
    assert "prospect_d_coefficients.txt" in prospect.split("MIT License")[0]  # says what it covers


def test_the_test_extra_brings_jupyter_nbconvert():
    """A newcomer reaches for ``jupyter nbconvert --execute``: the test extra installs it (issue 42, item 6)."""

    import importlib.util
    import tomllib
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    extras = tomllib.loads((root / "pyproject.toml").read_text())["project"]["optional-dependencies"]
    assert any(requirement.startswith("nbconvert") for requirement in extras["test"])
    assert importlib.util.find_spec("nbconvert") is not None  # installed where the tests run
