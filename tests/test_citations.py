"""Docstrings and comments of the package and its tools cite only files in the checkout or published references."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
OUTSIDE = re.compile(r"abm\.md|anchors\.md|\.\./shared|shared/research")


def test_no_citation_of_files_outside_the_checkout():
    found = [f"{path.relative_to(ROOT)}:{number}: {line.strip()}"
             for folder in ("virtspec_mi", "tools")
             for path in sorted((ROOT / folder).rglob("*"))
             if path.suffix in (".py", ".xml", ".md")
             for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1)
             if OUTSIDE.search(line)]
    assert found == []


def test_the_leaf_data_message_names_the_published_source_not_a_local_path(monkeypatch, tmp_path):
    import pytest

    from virtspec_mi.leaf_data import ENV_VAR, leaf_data_dir

    from virtspec_mi import leaf_data

    monkeypatch.delenv(ENV_VAR, raising=False)
    monkeypatch.setattr(leaf_data, "SHIPPED", tmp_path / "absent")  # an installation that lost its data
    with pytest.raises(FileNotFoundError) as info:
        leaf_data_dir(None)
    message = str(info.value)
    assert "github.com/turtlesoupy/ABM-U-and-ABM-B-CPP" in message and ENV_VAR in message and "shared" not in message
