"""
The manual (``docs/``, Sphinx): it builds with warnings as errors, and every ``python``
block and shell command of its pages runs, as the README's do (``tests/test_readme.py``);
every ``xml`` block loads in Mitsuba (a whole scene is measured, a fragment — a BSDF — is
loaded on its own).
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

import code_blocks

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
PAGES = sorted(p for p in DOCS.rglob("*.md") if "_build" not in p.parts and "_generated" not in p.parts
               and "notebooks" not in p.parts)
PYTHON = [(page, i) for page in PAGES for i in range(len(code_blocks.blocks(page, "python")))]
SHELL = [(page, command) for page in PAGES for command in code_blocks.shell_commands(page)]
XML = [(page, i) for page in PAGES for i in range(len(code_blocks.blocks(page, "xml")))]


def _id(item: tuple[Path, object]) -> str:
    return f"{item[0].relative_to(DOCS)}:{item[1]}"


@pytest.mark.slow
def test_the_manual_builds_without_a_warning(tmp_path):
    run = subprocess.run([sys.executable, "-m", "sphinx", "-E", "-W", "--keep-going", "-q", "-b", "html",
                          str(DOCS), str(tmp_path / "html")], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr[-6000:]
    assert (tmp_path / "html" / "index.html").is_file()


@pytest.fixture(scope="module")
def workdir(tmp_path_factory):
    """A scratch checkout-like folder: scenes/ and docs/ (the package ships its data)."""

    work = tmp_path_factory.mktemp("docs") / "work"
    (work / "docs").mkdir(parents=True)
    (work / "scenes").symlink_to(ROOT / "scenes")
    return work


def test_the_manual_has_code_to_run():
    assert PAGES and PYTHON and XML


@pytest.mark.parametrize("item", XML, ids=[_id(item) for item in XML])
def test_xml_block_loads(item, mi):
    import re

    import virtspec_mi as vm

    page, index = item
    source = code_blocks.blocks(page, "xml")[index]
    if "version=" not in source.split(">", 1)[0]:  # a fragment: its root element gets the format version
        source = re.sub(r"^\s*<(\w+)", r'<\1 version="3.0.0"', source, count=1)
    loaded = mi.load_string(source)
    if isinstance(loaded, mi.Scene):
        reading = vm.measure(loaded, rays=500, wavelengths=[551])
        assert reading.rays == 500
    else:
        assert isinstance(loaded, mi.BSDF)


@pytest.mark.slow
@pytest.mark.parametrize("item", PYTHON, ids=[_id(item) for item in PYTHON])
def test_python_block_runs(item, workdir, monkeypatch):
    from virtspec_mi.applications.targets.targets import TARGETS

    page, index = item
    monkeypatch.chdir(workdir)
    source = code_blocks.blocks(page, "python")[index]
    rows = dict(TARGETS)  # a how-to adds a target's row: the table is left as it was found, for the tests after it
    try:
        exec(compile(source, f"{page.name} python block {index}", "exec"), {"__name__": "__main__"})  # a script each
    finally:
        TARGETS.clear()
        TARGETS.update(rows)


@pytest.mark.slow
@pytest.mark.parametrize("item", SHELL, ids=[_id(item) for item in SHELL])
def test_shell_command_runs(item, workdir):
    env = dict(os.environ, PATH=f"{Path(sys.executable).parent}{os.pathsep}{os.environ['PATH']}")
    result = subprocess.run(["bash", "-c", item[1]], cwd=workdir, env=env, capture_output=True, text=True)
    assert result.returncode == 0, f"{item[1]}\n{result.stderr[-2000:]}"


def test_the_sidebar_lists_each_page_once_and_no_caption_repeats_a_page():
    """Every page is in one toctree entry only, and no toctree caption is the title of a page beside it."""

    import re

    toctree = re.compile(r"^```\{toctree\}\n(.*?)^```", re.M | re.S)
    entries, captions = [], []
    for page in DOCS.rglob("*.md"):
        if "_build" in page.parts or "_generated" in page.parts or "notebooks" in page.parts:
            continue
        for body in toctree.findall(page.read_text()):
            captions += re.findall(r"^:caption:\s*(.+)$", body, re.M)
            for line in body.splitlines():
                if line.strip() and not line.startswith(":"):
                    name = line.strip()
                    entries.append(name.lstrip("/") if name.startswith("/") else
                                   str((page.parent / name).relative_to(DOCS)))
    assert len(entries) == len(set(entries)), sorted(e for e in entries if entries.count(e) > 1)
    titles = {}
    for entry in entries:
        source = DOCS / f"{entry}.md"
        if source.is_file():
            titles[entry] = source.read_text().splitlines()[0].lstrip("# ").strip()
    assert not set(captions) & set(titles.values()), set(captions) & set(titles.values())
