"""
Docstrings, comments, pages and notebooks cite only files in the checkout or published references:
the package, its tools, scenes, tests, benchmarks, docs, notebooks and the README.
"""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
OUTSIDE = re.compile(r"abm\.md|anchors\.md|\.\./shared|shared/research")


def test_no_citation_of_files_outside_the_checkout():
    folders = ("virtspec_mi", "tools", "tests", "benchmarks", "docs", "notebooks")
    paths = [ROOT / "README.md", *(path for folder in folders for path in sorted((ROOT / folder).rglob("*"))
                                   if path.suffix in (".py", ".xml", ".md", ".ipynb") and "_build" not in path.parts)]
    found = [f"{path.relative_to(ROOT)}:{number}: {line.strip()}"
             for path in paths if path != Path(__file__).resolve()
             for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1)
             if OUTSIDE.search(line)]
    assert found == []


def test_the_leaf_data_message_names_the_published_source_not_a_local_path(monkeypatch, tmp_path):
    import pytest

    from virtspec_mi.plugins.leaf_data import ENV_VAR, leaf_data_dir

    from virtspec_mi.plugins import leaf_data

    monkeypatch.delenv(ENV_VAR, raising=False)
    monkeypatch.setattr(leaf_data, "SHIPPED", tmp_path / "absent")  # an installation that lost its data
    with pytest.raises(FileNotFoundError) as info:
        leaf_data_dir(None)
    message = str(info.value)
    assert "github.com/turtlesoupy/ABM-U-and-ABM-B-CPP" in message and ENV_VAR in message and "shared" not in message
