"""
The README's code runs: every ``python`` block and every shell command of it is executed.

Python blocks run one by one, each in a fresh namespace (so each must import what it
uses); shell commands are the lines of ``sh`` blocks and the ``$ ``-prefixed lines of
output blocks, run with the project's ``virtspec`` on ``PATH`` (``make`` and ``export``
lines set the machine up and are left to CI). Everything runs in a scratch directory
that holds ``scenes/`` (the package ships its leaf data), so the commands
work as written and write nothing into the checkout.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

import code_blocks

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"


def blocks(kind: str) -> list[str]:
    return code_blocks.blocks(README, kind)


def shell_commands() -> list[str]:
    return code_blocks.shell_commands(README)


@pytest.fixture(scope="module")
def workdir(tmp_path_factory):
    """A scratch checkout-like folder: scenes/ and docs/ (nothing beside it: the package ships its data)."""

    base = tmp_path_factory.mktemp("readme")
    work = base / "work"
    (work / "docs").mkdir(parents=True)
    (work / "scenes").symlink_to(ROOT / "scenes")
    return work


def test_the_readme_has_code_to_run():
    assert len(blocks("python")) >= 1 and len(shell_commands()) >= 5  # a front door; the manual holds the rest


@pytest.mark.slow
@pytest.mark.parametrize("index", range(len(blocks("python"))))
def test_python_block_runs(index, workdir, monkeypatch):
    monkeypatch.chdir(workdir)
    source = blocks("python")[index]
    exec(compile(source, f"README.md python block {index}", "exec"), {"__name__": "__readme__"})


@pytest.mark.slow
@pytest.mark.parametrize("command", shell_commands())
def test_shell_command_runs(command, workdir):
    env = dict(os.environ, PATH=f"{Path(sys.executable).parent}{os.pathsep}{os.environ['PATH']}")
    result = subprocess.run(["bash", "-c", command], cwd=workdir, env=env, capture_output=True, text=True)
    assert result.returncode == 0, f"{command}\n{result.stderr[-2000:]}"


def test_the_readme_is_a_front_door():
    """Short (≤ 300 lines): the two commands, a Python example, a figure; every link into the checkout resolves."""

    import re

    text = README.read_text()
    assert len(text.splitlines()) <= 300
    assert "make demo" in text and "make test" in text and blocks("python") and "![" in text
    links = re.findall(r"\]\(([^)#\s]+)(?:#[^)]*)?\)", text)
    local = [link for link in links if "://" not in link]
    assert len(local) >= 15, local  # the manual's pages
    missing = [link for link in local if not (ROOT / link).exists()]
    assert missing == []
