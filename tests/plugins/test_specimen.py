"""
The specimen protocol (virtspec_mi/plugins/specimen.py) and the specimens' table with its
entry-point group (virtspec_mi/plugins/__init__.py): every project specimen implements the
protocol, a Mitsuba BSDF reads as the general case, the engine reads it, and an outside
package's leaf model — a fake distribution (a ``*.dist-info`` with ``entry_points.txt``) on
the path of a subprocess, the class of ``docs/guide/add_a_specimen.md`` — is listed,
registered, measured and fitted by name, as the how-to's own code shows.
"""

from __future__ import annotations

import math
import os
import re
import subprocess
import sys
import warnings
from importlib.metadata import EntryPoint
from pathlib import Path

import numpy as np
import pytest

import code_blocks
import virtspec_mi as vm
import virtspec_mi.plugins as plugins
from virtspec_mi.engine.readings import check_specimen, shares_wavelengths
from virtspec_mi.plugins import ENTRY_POINTS, SPECIMENS, load_specimen, specimen_rows
from virtspec_mi.plugins.specimen import MEMBERS, Parameter, missing, specimen_of

ROOT = Path(__file__).resolve().parents[2]
PAGE = ROOT / "docs" / "guide" / "add_a_specimen.md"


@pytest.mark.parametrize("name", sorted(SPECIMENS))
def test_every_project_specimen_implements_the_protocol(mi, name):
    plugin = load_specimen(name, SPECIMENS[name])
    assert missing(plugin) == []
    assert all(isinstance(p, Parameter) and p.lowest < p.highest and p.units for p in plugin.PARAMETERS)
    if name == "tabulated":  # needs a table: tests/plugins/test_tabulated.py
        return
    bsdf = mi.load_dict({"type": name})
    view = specimen_of(bsdf)
    exposed = {key.rpartition(".")[2]: value for key, value in mi.traverse(bsdf).items()}
    declared = {p.name: p for p in view.parameters}
    assert set(exposed) <= set(declared), f"{name}: parameters shown but not declared: {set(exposed) - set(declared)}"
    for key, value in exposed.items():
        assert declared[key].within(float(np.ravel(value)[0])), (name, key, value)


def test_a_mitsuba_bsdf_reads_as_the_general_case(mi):
    diffuse = mi.load_dict({"type": "diffuse"})
    view = specimen_of(diffuse)
    assert missing(diffuse) == list(MEMBERS)
    assert (view.wavelength_range, view.wavelength_independent, view.parameters) == (None, False, ())
    view.check_wavelengths([300.0, 3000.0])  # nothing of its own to refuse


def test_the_project_specimens_declare_what_they_know(mi):
    leaf, slab = specimen_of(mi.load_dict({"type": "abm_b"})), specimen_of(mi.load_dict({"type": "turbid_slab"}))
    assert (leaf.name, leaf.wavelength_range, leaf.wavelength_independent) == ("abm_b", (400.0, 2500.0), False)
    assert leaf.parameter("thickness") == Parameter("thickness", 0.0, math.inf, "m",
                                                    "Whole-leaf thickness h in m (> 0)")
    assert leaf.parameter("mesophyll_fraction").highest == 1.0 and leaf.parameter("palisade_aspect_ratio")
    assert specimen_of(mi.load_dict({"type": "abm_u"})).parameter("palisade_aspect_ratio") is None  # no palisade
    assert slab.wavelength_independent and slab.parameter("mu_a").units == "1/length"
    assert specimen_of(mi.load_dict({"type": "simple_dielectric"})).wavelength_independent
    prospect = specimen_of(mi.load_dict({"type": "prospect_d"}))
    assert prospect.parameter("Cab") == Parameter("Cab", 0.0, 150.0, "ug/cm2", "chlorophylls a + b")


def test_a_turned_over_specimen_keeps_the_nested_protocol(mi):
    flipped = specimen_of(mi.load_dict({"type": "virtspec_flipped", "nested": {"type": "abm_b"}}))
    assert flipped.wavelength_range == (400.0, 2500.0) and not flipped.wavelength_independent
    assert specimen_of(mi.load_dict({"type": "virtspec_flipped", "nested": {"type": "simple_dielectric"}})
                       ).wavelength_independent


def test_the_engine_reads_the_protocol(mi):
    leaf = mi.load_dict({"type": "abm_b"})
    with pytest.raises(ValueError, match="400 <= wavelength <= 2500 nm for the specimen abm_b"):
        check_specimen(leaf, [350.0])
    check_specimen(leaf, [400.0, 2500.0])
    diamond = vm.find_bench(vm.instrument_scene({"type": "simple_dielectric"}))
    assert shares_wavelengths(diamond)
    assert not shares_wavelengths(vm.find_bench(vm.instrument_scene({"type": "diffuse"})))


def test_the_fit_names_each_parameter_with_its_units_and_bounds():
    measured = (np.array([500.0, 600.0]), np.array([0.1, 0.1]), np.array([0.01, 0.01]))
    with pytest.raises(ValueError, match=r"no parameter 'Chl' \(its parameters: .*Cab \(ug/cm2, 0-150\)"):
        vm.fit(measured, "prospect_d", {"Chl": (10, 80)})


@pytest.fixture
def reread():
    """The installed packages' specimens read again in the test, and after it (the cache of the real ones)."""

    plugins.discovered_specimens.cache_clear()
    yield
    plugins.discovered_specimens.cache_clear()


def test_an_entry_point_taking_a_project_name_or_broken_is_left_out_with_a_warning(mi, monkeypatch, reread):
    points = [EntryPoint("abm_b", "somewhere:Leaf", ENTRY_POINTS),
              EntryPoint("broken_leaf", "no_such_module_38:Leaf", ENTRY_POINTS)]
    monkeypatch.setattr(plugins, "entry_points", lambda group: points if group == ENTRY_POINTS else [])
    with pytest.warns(RuntimeWarning, match="'abm_b' .* already taken"):
        rows = specimen_rows()
    assert rows["abm_b"] == SPECIMENS["abm_b"] and rows["broken_leaf"] == "no_such_module_38:Leaf"
    from virtspec_mi import runtime

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        runtime.register()  # every plugin registered again; the broken one named, not fatal
        listed = runtime.specimens()
    assert any("'broken_leaf'" in str(w.message) and "could not be registered" in str(w.message) for w in caught)
    assert "broken_leaf" not in listed and set(SPECIMENS) <= set(listed)


def _fake_distribution(site: Path) -> None:
    """The how-to's package, as an installed distribution: its module and a ``*.dist-info`` with its entry point."""

    source = PAGE.read_text()
    module = re.search(r"write_text\(textwrap\.dedent\('''\n(.*?)'''\)\)", source, re.S).group(1)
    site.mkdir()
    (site / "grey_leaf.py").write_text(__import__("textwrap").dedent(module))
    info = site / "grey_leaf-0.1.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: grey-leaf\nVersion: 0.1\n")
    (info / "entry_points.txt").write_text(f"[{ENTRY_POINTS}]\ngrey_leaf = grey_leaf:GreyLeaf\n")


def test_the_how_to_specimen_from_an_outside_package_runs(tmp_path, monkeypatch):
    """The page's second block, run as written, with the fake distribution where pip would have put it."""

    _fake_distribution(tmp_path / "grey_site")
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]))
    block = code_blocks.blocks(PAGE, "python")[1]
    assert "grey_site" in block and "--specimen" in block
    exec(compile(block, f"{PAGE.name} python block 1", "exec"), {"__name__": "__main__"})


def test_an_outside_specimen_is_listed_and_in_the_fit_help(tmp_path):
    _fake_distribution(tmp_path / "grey_site")
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(tmp_path / "grey_site"), str(ROOT)]))
    script = ("import virtspec_mi as vm\nfrom virtspec_mi.plugins import specimen_rows\n"
              "print(specimen_rows()['grey_leaf']); print(vm.specimens()['grey_leaf'])\n")
    shown = subprocess.run([sys.executable, "-c", script], env=env, capture_output=True, text=True, check=True).stdout
    assert shown.splitlines() == ["grey_leaf:GreyLeaf",
                                  "A grey leaf: reflects ``reflectance`` and transmits ``transmittance`` of the "
                                  "light, diffusely."]
    helped = subprocess.run([sys.executable, "-m", "virtspec_mi", "fit", "--help"], env=env, capture_output=True,
                            text=True, check=True).stdout
    assert "grey_leaf" in " ".join(helped.split())
