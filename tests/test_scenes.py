"""The shipped scenes by name (virtspec_mi.scenes): paths, summaries, resolution, the CLI listing."""

from __future__ import annotations

import subprocess
import sys

import pytest

import virtspec_mi as vm
from virtspec_mi import scenes


def test_every_shipped_scene_has_a_path_and_a_one_line_summary():
    assert scenes.names() == sorted(p.stem for p in scenes.FOLDER.glob("*.xml"))
    assert {"diamond_conical", "soybean_abmb", "sphere_150mm_8d"} <= set(scenes.names())
    for name in scenes.names():
        assert scenes.path(name).is_file()
        summary = scenes.describe(name)
        assert summary and "\n" not in summary and len(summary) < 140
    lines = scenes.catalogue().splitlines()
    assert [line.split()[0] for line in lines] == scenes.names()


def test_an_unknown_name_lists_the_shipped_scenes():
    with pytest.raises(ValueError, match="no shipped scene 'diamond'; the shipped scenes are corn_abmu, "):
        scenes.path("diamond")


def test_a_name_is_resolved_and_a_path_or_dict_is_kept(tmp_path):
    assert scenes.resolve("mcml_slab") == scenes.FOLDER / "mcml_slab.xml"
    existing = tmp_path / "mcml_slab"  # a file of that name in the working directory wins
    existing.write_text("")
    assert scenes.resolve(str(existing)) == str(existing)
    assert scenes.resolve({"type": "scene"}) == {"type": "scene"}


def test_a_reading_of_a_named_scene_is_the_reading_of_its_file():
    by_name = vm.measure("diamond_conical", theta_i=70, rays=5000)
    by_path = vm.measure(str(scenes.path("diamond_conical")), theta_i=70, rays=5000)
    assert by_name.reflected.tolist() == by_path.reflected.tolist()
    assert by_name.scene == by_path.scene  # one fingerprint: the same file


def test_virtspec_scenes_lists_them():
    run = subprocess.run([sys.executable, "-m", "virtspec_mi", "scenes"], capture_output=True, text=True, check=True)
    assert run.stdout.strip() == scenes.catalogue()
