"""
Tests of :mod:`virtspec_mi.plugins` (its ``__init__``): the specimens' table, its entry-point
group read once per process, and :func:`~virtspec_mi.plugins.load_specimen`'s refusals.

Every row of :data:`SPECIMENS` names a BSDF class in a module of the package; outside entry
points are added after them, a name already taken is left out with a warning, the installed
packages are read once until the cache is cleared, and :func:`specimen_rows` hands out a copy.
The outside package's specimen measured and fitted by name, and a broken entry point at
registration, are tested in ``tests/plugins/test_specimen.py``.

References
----------
Python Packaging User Guide, "Entry points specification".
"""

from __future__ import annotations

import warnings
from importlib.metadata import EntryPoint

import pytest

import virtspec_mi.plugins as plugins
from virtspec_mi.plugins import ENTRY_POINTS, SPECIMENS, load_specimen, specimen_rows


@pytest.fixture
def reread():
    """The installed packages' specimens read again in the test, and after it (the cache of the real ones)."""

    plugins.discovered_specimens.cache_clear()
    yield
    plugins.discovered_specimens.cache_clear()


def test_every_row_names_a_class_in_a_module_of_the_package(mi):
    assert ENTRY_POINTS == "virtspec_mi.specimens"
    for name, row in SPECIMENS.items():
        module, _, cls = row.partition(":")
        assert module.startswith("virtspec_mi.plugins.bsdfs.") and cls, name
        plugin = load_specimen(name, row)
        assert plugin.__name__ == cls and plugin.__module__ == module


def test_outside_rows_follow_the_projects_and_a_taken_name_is_left_out(monkeypatch, reread):
    points = [EntryPoint("grey_leaf", "grey_leaf:GreyLeaf", ENTRY_POINTS),
              EntryPoint("turbid_slab", "elsewhere:Slab", ENTRY_POINTS)]
    monkeypatch.setattr(plugins, "entry_points", lambda group: points if group == ENTRY_POINTS else [])
    with pytest.warns(RuntimeWarning, match=r"specimen entry point 'turbid_slab' \(elsewhere:Slab\) takes the name "
                                            r"'turbid_slab', already taken: left out"):
        rows = specimen_rows()
    assert list(rows) == [*SPECIMENS, "grey_leaf"]
    assert rows["turbid_slab"] == SPECIMENS["turbid_slab"] and rows["grey_leaf"] == "grey_leaf:GreyLeaf"


def test_the_installed_packages_are_read_once_and_the_rows_are_a_copy(monkeypatch, reread):
    calls = []
    monkeypatch.setattr(plugins, "entry_points", lambda group: calls.append(group) or [])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        first = specimen_rows()
        first["mine"] = "x:Y"  # the caller's copy
        assert "mine" not in specimen_rows()
    assert calls == [ENTRY_POINTS]  # read once
    plugins.discovered_specimens.cache_clear()
    specimen_rows()
    assert calls == [ENTRY_POINTS, ENTRY_POINTS]


def test_a_class_without_the_protocol_is_refused_naming_what_it_lacks(mi, tmp_path, monkeypatch):
    (tmp_path / "bare_bsdf.py").write_text(
        "import mitsuba as mi\n\n\nclass Bare(mi.BSDF):\n    wavelength_range = None\n\n\nclass NotABSDF:\n    pass\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    with pytest.raises(TypeError, match="declares no PARAMETERS, wavelength_independent, check_wavelengths"):
        load_specimen("bare", "bare_bsdf:Bare")
    with pytest.raises(TypeError, match="not a Mitsuba BSDF class"):
        load_specimen("nota", "bare_bsdf:NotABSDF")
    with pytest.raises(ModuleNotFoundError):
        load_specimen("gone", "no_such_module_for_virtspec:Leaf")
