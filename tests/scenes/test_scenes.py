"""The shipped scenes by name (virtspec_mi.scenes): paths, summaries, resolution, the CLI listing."""

from __future__ import annotations

import subprocess
from pathlib import Path
import sys

import pytest

import virtspec_mi as vm
from virtspec_mi import scenes
from virtspec_mi.engine.bench import SceneError


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


def test_virtspec_scenes_lists_them_with_their_files():
    run = subprocess.run([sys.executable, "-m", "virtspec_mi", "scenes"], capture_output=True, text=True, check=True)
    assert run.stdout.strip() == scenes.listing()
    lines = run.stdout.splitlines()
    assert [line.split()[0] for line in lines[::2]] == scenes.names()
    assert [Path(line.strip()) for line in lines[1::2]] == [scenes.path(name) for name in scenes.names()]


def test_virtspec_scenes_path_and_copy(tmp_path, monkeypatch, capsys):
    from virtspec_mi.cli import main

    monkeypatch.chdir(tmp_path)
    assert main(["scenes", "--path", "sphere_150mm_8d"]) == 0
    assert capsys.readouterr().out.strip() == str(scenes.path("sphere_150mm_8d"))
    assert main(["scenes", "--copy", "sphere_150mm_8d", "mine.xml"]) == 0
    assert capsys.readouterr().out.strip() == "mine.xml"
    assert (tmp_path / "mine.xml").read_bytes() == scenes.path("sphere_150mm_8d").read_bytes()
    (tmp_path / "mine.xml").write_text("edited")
    assert main(["scenes", "--copy", "sphere_150mm_8d", "mine.xml"]) == 1
    assert "mine.xml exists (it is kept" in capsys.readouterr().err
    assert (tmp_path / "mine.xml").read_text() == "edited"
    assert main(["scenes", "--path", "soybean_abm"]) == 1
    assert "did you mean 'soybean_abmb'?" in capsys.readouterr().err
    assert main(["scenes", "mine.xml"]) == 1
    assert "give --copy NAME DEST" in capsys.readouterr().err


def test_the_help_examples_give_shipped_scenes_by_name():
    """Each --help example that takes a scene runs anywhere: it names a shipped scene, not a checkout path."""

    from virtspec_mi.cli import MEASURING, build_parser

    parser = build_parser()
    for row in MEASURING.values():
        for example in row.command.examples:
            args = parser.parse_args(example.split()[1:])
            assert args.scene in scenes.names(), example


def test_a_name_is_sent_to_workers_as_the_shipped_file_whatever_the_directory(tmp_path, monkeypatch):
    from virtspec_mi.runtime.scaleout import portable_scene

    monkeypatch.chdir(tmp_path)  # the workers' directory holds no file of that name
    assert portable_scene("diamond_conical") == str(scenes.path("diamond_conical"))
    (tmp_path / "diamond_conical").write_text("<scene/>")  # a file of that name in the directory wins
    assert portable_scene("diamond_conical") == str(tmp_path / "diamond_conical")


@pytest.mark.slow
def test_a_named_scene_on_two_workers_counts_as_in_process(mi, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    options = dict(theta_i=[0, 70], wavelengths=[450, 650], rays=4000, defines={"seed": 3}, progress=False)
    there = vm.sweep("soybean_abmb", workers=2, **options)
    here = vm.sweep(str(scenes.path("soybean_abmb")), **options)
    assert there.reflected.tolist() == here.reflected.tolist()
    assert there.source["scene"] == "soybean_abmb"


def test_a_folder_of_a_shipped_scenes_name_does_not_hide_it(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "mcml_slab").mkdir()
    assert scenes.resolve("mcml_slab") == scenes.path("mcml_slab")
    assert vm.find_bench("mcml_slab").bsdf is not None


def test_a_misspelt_name_or_a_checkout_path_gets_the_name_to_use(mi, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(SceneError, match="scene file not found: soybean_abm; did you mean the shipped scene "
                                            "'soybean_abmb'"):
        vm.find_bench("soybean_abm")
    with pytest.raises(SceneError, match=r"not found: scenes/diamond_conical.xml; the shipped scene "
                                            r"'diamond_conical' is given by its name alone"):
        vm.find_bench("scenes/diamond_conical.xml")
    with pytest.raises(SceneError, match="virtspec scenes lists them"):
        vm.find_bench("nothing_like_it")
    with pytest.raises(ValueError, match="did you mean 'mcml_slab'"):
        scenes.path("mcml_slb")


def test_an_xml_scene_includes_a_shipped_scene_by_its_file_name(mi, tmp_path):
    own = tmp_path / "mine.xml"
    own.write_text('<scene version="3.0.0">\n  <include filename="diamond_conical.xml"/>\n</scene>\n')
    options = dict(theta_i=70, rays=3000, wavelengths=[550])
    assert vm.measure(own, **options).reflected.tolist() == vm.measure("diamond_conical", **options).reflected.tolist()


def test_defines_set_a_named_scenes_parameters(mi):
    options = dict(rays=3000, wavelengths=[550])
    by_name = vm.measure("diamond_conical", defines={"theta_i": 30}, **options)
    by_path = vm.measure(scenes.path("diamond_conical"), theta_i=30, **options)
    assert by_name.reflected.tolist() == by_path.reflected.tolist()
    assert by_name.source["defines"] == {"theta_i": "30"}


def test_copy_gives_a_template_and_never_replaces_a_file(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    copied = scenes.copy("sphere_150mm_8d")
    assert copied == Path("sphere_150mm_8d.xml") and copied.read_bytes() == scenes.path("sphere_150mm_8d").read_bytes()
    copied.write_text("edited")
    with pytest.raises(FileExistsError, match="sphere_150mm_8d.xml exists"):
        scenes.copy("sphere_150mm_8d")
    assert copied.read_text() == "edited"
    assert scenes.copy("sphere_150mm_8d", tmp_path / "mine.xml").is_file()
    (tmp_path / "templates").mkdir()
    assert scenes.copy("mcml_slab", "templates") == Path("templates/mcml_slab.xml")
    with pytest.raises(FileNotFoundError, match="folder nowhere does not exist"):
        scenes.copy("mcml_slab", "nowhere/x.xml")
    with pytest.raises(ValueError, match="no shipped scene"):
        scenes.copy("nothing")


@pytest.mark.slow
def test_virtspec_measure_of_a_named_scene_on_workers_from_any_folder(mi, tmp_path, monkeypatch, capsys):
    import json

    from virtspec_mi.cli import main

    monkeypatch.chdir(tmp_path)  # no scenes/ here: the workers must find the shipped file
    assert main(["measure", "diamond_conical", "--theta-i", "70", "--rays", "2000", "--workers", "2", "--json"]) == 0
    there = json.loads(capsys.readouterr().out)
    here = vm.measure("diamond_conical", theta_i=70, rays=2000)
    assert there["reflected"] == here.reflected.tolist()
