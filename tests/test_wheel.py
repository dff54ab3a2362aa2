"""
The package anyone can install: the built wheel and sdist hold every subpackage, the
plugins, the shipped scenes, the leaf data and the PROSPECT-D coefficients with their
licences; the wheel installed with its dependencies into a fresh virtual environment outside
the source tree (no editable finder, nothing beside it) takes a leaf reading (ABM-B, and
PROSPECT-D without ``prosail``), a sweep, runs the command line and runs the quick start
page's commands (``docs/guide/quickstart.md``) from a folder of its own; the wheel's metadata
holds the project's licence and the data's.
"""

from __future__ import annotations

import os
import subprocess
import sys
import tarfile
import zipfile
from pathlib import Path

import pytest

import code_blocks

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "virtspec_mi"


def _expected_files() -> set[str]:
    """Every file the installed package needs: modules, scenes, leaf data, licence."""

    wanted = {p for p in PACKAGE.rglob("*") if p.is_file() and "__pycache__" not in p.parts}
    return {str(p.relative_to(ROOT)) for p in wanted if p.suffix in (".py", ".xml", ".txt", ".md") or p.name == "LICENSE"}


@pytest.fixture(scope="module")
def built(tmp_path_factory) -> dict[str, Path]:
    out = tmp_path_factory.mktemp("dist")
    subprocess.run([sys.executable, "-m", "build", "--wheel", "--sdist", "--outdir", str(out), str(ROOT)],
                   check=True, capture_output=True)
    return {"wheel": next(out.glob("*.whl")), "sdist": next(out.glob("*.tar.gz"))}


@pytest.mark.slow
def test_the_wheel_and_the_sdist_hold_the_whole_package(built):
    expected = _expected_files()
    assert {"virtspec_mi/data/abm-npsg/LICENSE", "virtspec_mi/data/prospect-d/LICENSE",
            "virtspec_mi/data/prospect-d/prospect_d_coefficients.txt", "virtspec_mi/scenes/soybean_abmb.xml",
            "virtspec_mi/plugins/bsdfs/abm_b.py", "virtspec_mi/kernel/tracer.py"} <= expected
    wheel = set(zipfile.ZipFile(built["wheel"]).namelist())
    assert expected <= wheel, sorted(expected - wheel)
    info = next(name.split("/")[0] for name in wheel if name.endswith(".dist-info/METADATA"))
    assert {f"{info}/licenses/LICENSE", f"{info}/licenses/virtspec_mi/data/abm-npsg/LICENSE",
            f"{info}/licenses/virtspec_mi/data/prospect-d/LICENSE"} <= wheel
    metadata = zipfile.ZipFile(built["wheel"]).read(f"{info}/METADATA").decode()
    assert "License-Expression: BSD-3-Clause" in metadata and "License-File: LICENSE" in metadata
    with tarfile.open(built["sdist"]) as sdist:
        members = {"/".join(name.split("/")[1:]) for name in sdist.getnames()}
    assert expected <= members, sorted(expected - members)


@pytest.mark.slow
def test_the_installed_wheel_measures_a_leaf_sweeps_and_runs_the_cli(built, tmp_path):
    # nothing of the checkout on the path, pip included (a PYTHONPATH holding the source tree and its
    # egg-info would make pip skip the wheel as "already satisfied")
    env = {k: v for k, v in os.environ.items() if k not in ("VIRTSPEC_LEAF_DATA", "VIRTSPEC_PROSPECT_DATA",
                                                            "PYTHONPATH")}
    venv = tmp_path / "venv"
    subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True, env=env)
    python, virtspec = venv / "bin" / "python", venv / "bin" / "virtspec"
    subprocess.run([str(python), "-m", "pip", "install", "--quiet", str(built["wheel"])], check=True,
                   capture_output=True, env=env)
    away = tmp_path / "elsewhere"  # no source tree, no shared folder beside it: only the installed package
    away.mkdir()
    script = (
        "import virtspec_mi as vm\n"
        "assert 'site-packages' in vm.__file__, vm.__file__\n"
        "leaf = vm.measure('soybean_abmb', wavelengths=[551, 800], rays=3000)\n"
        "assert leaf.reflectance.shape == (2,) and 0.03 < leaf.reflectance[0] < 0.2 < leaf.reflectance[1]\n"
        "table = vm.sweep(vm.instrument_scene({'type': 'abm_b'}), theta_i=[0, 40], wavelengths=[551], rays=2000,"
        " progress=False)\n"
        "assert table.reflectance.shape == (1, 2)\n"
        "import importlib.util\n"  # PROSPECT-D from the shipped coefficients, prosail nowhere
        "assert importlib.util.find_spec('prosail') is None\n"
        "from virtspec_mi.plugins.bsdfs.prospect_model import prospect_coefficients\n"
        "assert 'shipped' in prospect_coefficients().source\n"
        "green = vm.measure(vm.instrument_scene({'type': 'prospect_d'}), wavelengths=[551, 800], rays=3000)\n"
        "assert 0.03 < green.reflectance[0] < 0.2 < green.reflectance[1]\n"
        "print('ok')\n")
    run = subprocess.run([str(python), "-c", script], cwd=away, env=env, capture_output=True, text=True)
    assert run.returncode == 0 and run.stdout.strip() == "ok", run.stderr
    for command in (["scenes"], ["measure", "corn_abmu", "--rays", "2000", "--wavelengths", "551"]):
        run = subprocess.run([str(virtspec), *command], cwd=away, env=env, capture_output=True, text=True)
        assert run.returncode == 0, run.stderr
    assert "soybean_abmb" in subprocess.run([str(virtspec), "scenes"], cwd=away, env=env, capture_output=True,
                                            text=True).stdout
    # the quick start's commands, as a newcomer runs them: from a folder of their own, the venv's bin on PATH
    quickstart = ROOT / "docs" / "guide" / "quickstart.md"
    newcomer = tmp_path / "newcomer"
    newcomer.mkdir()
    env["PATH"] = f"{venv / 'bin'}{os.pathsep}{env['PATH']}"
    commands = code_blocks.shell_commands(quickstart)
    assert any(c.startswith("virtspec measure diamond_conical") for c in commands), commands
    for command in commands:
        run = subprocess.run(["bash", "-c", command], cwd=newcomer, env=env, capture_output=True, text=True)
        assert run.returncode == 0, f"{command}\n{run.stderr[-2000:]}"
    for source in code_blocks.blocks(quickstart, "python"):
        run = subprocess.run([str(python), "-c", source], cwd=newcomer, env=env, capture_output=True, text=True)
        assert run.returncode == 0, f"{source}\n{run.stderr[-2000:]}"
    assert {"leaf.png", "my_specimen.xml", "gold.nc", "gold.csv"} <= {p.name for p in newcomer.iterdir()}
