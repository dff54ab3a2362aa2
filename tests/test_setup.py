"""
``make setup``'s virtual environment (the ``venv`` target of the Makefile), run on a
throw-away copy of the Makefile with stand-ins for ``python3`` and ``apt-get``: a
``.venv`` left half-made (no pip: Debian/Ubuntu without ``python3-venv``) is made again,
and a missing ``python3-venv`` is installed with apt, or named when apt is not there.
"""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

# python3 -m venv DIR: without the marker file "venv-installed" it behaves as Debian's without python3-venv
# (a DIR/bin/python without pip, "ensurepip is not available", exit 1); with it, DIR/bin/python has pip.
FAKE_PYTHON = """#!/bin/sh
here=$(dirname "$0")
[ "$1 $2" = "-m venv" ] || exit 2
mkdir -p "$3/bin"
if [ -e "$here/venv-installed" ]; then
  printf '#!/bin/sh\\nexit 0\\n' > "$3/bin/python"; chmod +x "$3/bin/python"; exit 0
fi
printf '#!/bin/sh\\necho "No module named pip" >&2; exit 1\\n' > "$3/bin/python"; chmod +x "$3/bin/python"
echo "The virtual environment was not created successfully because ensurepip is not available." >&2
exit 1
"""
FAKE_APT = """#!/bin/sh
here=$(dirname "$0")
echo "$@" >> "$here/apt.log"
case "$*" in *install*python3-venv*) touch "$here/venv-installed";; esac
"""


@pytest.fixture
def checkout(tmp_path):
    if shutil.which("make") is None:
        pytest.skip("make is not installed")
    shutil.copy(ROOT / "Makefile", tmp_path / "Makefile")
    (tmp_path / "pyproject.toml").write_text("")
    tools = tmp_path / "tools"
    tools.mkdir()
    for name, text in (("python3", FAKE_PYTHON), ("apt", FAKE_APT)):
        (tools / name).write_text(text)
        (tools / name).chmod(0o755)
    return tmp_path


def make_venv(checkout: Path, apt: str) -> subprocess.CompletedProcess:
    return subprocess.run(["make", "--no-print-directory", "venv", f"PYTHON={checkout / 'tools' / 'python3'}",
                           f"APT={apt}", "SUDO="], cwd=checkout, capture_output=True, text=True, timeout=60)


def test_a_half_made_venv_is_made_again(checkout):
    (checkout / "tools" / "venv-installed").touch()  # python3-venv is there; the .venv was left without pip
    (checkout / ".venv" / "bin").mkdir(parents=True)
    (checkout / ".venv" / "bin" / "python").write_text("#!/bin/sh\necho 'No module named pip' >&2; exit 1\n")
    (checkout / ".venv" / "bin" / "python").chmod(0o755)
    run = make_venv(checkout, "no-such-apt")
    assert run.returncode == 0, run.stdout + run.stderr
    assert ".venv has no working pip (a half-made virtual environment): making it again" in run.stdout
    assert subprocess.run([checkout / ".venv" / "bin" / "python", "-m", "pip", "--version"]).returncode == 0
    again = make_venv(checkout, "no-such-apt")  # a working .venv is kept as it is
    assert again.returncode == 0 and again.stdout == ""


def test_a_missing_python3_venv_is_installed_with_apt(checkout):
    run = make_venv(checkout, str(checkout / "tools" / "apt"))
    assert run.returncode == 0, run.stdout + run.stderr
    assert "the system package python3-venv is missing" in run.stdout and "installing python3-venv" in run.stdout
    assert "install -y -qq python3-venv" in (checkout / "tools" / "apt.log").read_text()
    assert subprocess.run([checkout / ".venv" / "bin" / "python", "-m", "pip", "--version"]).returncode == 0


def test_without_apt_the_missing_package_is_named_and_nothing_half_made_is_left(checkout):
    run = make_venv(checkout, "no-such-apt")
    assert run.returncode != 0
    assert "the system package python3-venv is missing" in run.stdout
    assert "install python3-venv (Debian/Ubuntu: sudo apt-get install python3-venv)" in run.stderr
    assert not (checkout / ".venv").exists()
