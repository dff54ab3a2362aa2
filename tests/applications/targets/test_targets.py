"""
The targets' table (virtspec_mi/applications/targets/targets.py: TARGETS, TargetKind): each
row is a constructor whose signature gives the ':' arguments and the options of a text; the
package's top-level names are the rows; a new target is one constructor and one row, as
docs/guide/add_a_target.md shows (its code run here).
"""

from __future__ import annotations

from pathlib import Path

import pytest

import code_blocks
import virtspec_mi as vm
from virtspec_mi.applications.targets import targets
from virtspec_mi.applications.targets.targets import TARGETS, BandTarget, TargetKind, target_kind

PAGE = Path(__file__).resolve().parents[3] / "docs" / "guide" / "add_a_target.md"


def test_the_rows_are_the_five_targets_with_their_options_from_the_signatures():
    assert list(TARGETS) == ["colour", "band", "index", "fapar", "albedo"]
    assert TARGETS["colour"].options() == {"dE00": float, "illuminant": str, "observer": str, "quantity": str,
                                           "step": float}
    assert TARGETS["band"].options() == {"tolerance": float, "quantity": str, "step": float}
    assert TARGETS["index"].options() == {"tolerance": float, "step": float}  # bands= is a dict: not a text option
    assert TARGETS["albedo"].options()["low"] is float  # float | None: converted as a float
    assert [TARGETS[k].arguments() for k in TARGETS] == [(0, 0), (1, None), (1, 1), (0, 0), (0, 0)]
    assert TARGETS["colour"].keyword("dE00") == "tolerance_dE00" and TARGETS["band"].keyword("step") == "step"


def test_a_kind_is_found_by_name_or_spelling_in_any_case():
    assert target_kind("Color")[0] == "colour" and target_kind(" BAND ")[0] == "band"
    with pytest.raises(ValueError, match="the kind must be one of colour, band, index, fapar, albedo"):
        target_kind("ndvi")


def test_the_top_level_names_are_the_rows():
    for name, kind in TARGETS.items():
        assert getattr(vm, name) is kind.make and name in dir(vm) and name in vm.__all__


def test_a_row_added_is_a_target_everywhere(monkeypatch):
    def red(tolerance: float = 0.01, edge: float = 680.0) -> BandTarget:
        """A red band from 620 nm to ``edge``."""

        return targets.band((620.0, edge), tolerance=tolerance)

    monkeypatch.setitem(TARGETS, "red", TargetKind(red, spellings=("rouge",)))
    from virtspec_mi.applications.targets.parse import parse_target

    made = parse_target("rouge,edge=700,tolerance=0.02")
    assert made.bands[0].edges == (620.0, 700.0) and made.tolerance == 0.02
    assert vm.red is red and "red" in dir(vm) and "red" in vm.__all__
    with pytest.raises(ValueError, match=r"target must be made by vm.colour, vm.band, vm.index, vm.fapar, vm.albedo "
                                         r"or vm.red"):
        vm.measure(vm.instrument_scene({"type": "diffuse"}), target=object())


def test_the_how_to_add_a_target_runs(tmp_path, monkeypatch):
    """docs/guide/add_a_target.md: its blocks run as written (their rows taken out afterwards)."""

    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(targets, "TARGETS", TARGETS)  # the same table: the page adds its rows to it
    try:
        for index, block in enumerate(code_blocks.blocks(PAGE, "python")):
            exec(compile(block, f"{PAGE.name} python block {index}", "exec"), {"__name__": "__main__"})
        assert {"ndwi", "par_albedo"} <= set(TARGETS)
    finally:
        for name in ("ndwi", "par_albedo"):
            TARGETS.pop(name, None)
    assert "ndwi" not in dir(vm)
