"""
The registry is the one place that knows the instruments (virtspec_mi.instruments): no module
outside an instrument's own module looks one up by its name, branches on its name, or asks
a result which kind it is. The command line, the result files, the integrator and the
contract test are generated from the rows (a static reading of every module; the API's
documented thin aliases, ``measure``/``sweep``/``gonio``/``sphere_measure``, name their
instrument once each).
"""

from __future__ import annotations

import ast
from pathlib import Path

from virtspec_mi.instruments import INSTRUMENTS
from virtspec_mi.results.base import KINDS

PACKAGE = Path(__file__).resolve().parents[2] / "virtspec_mi"
ALIASES = PACKAGE / "api.py"
"""The API's hand-written aliases of take(name, …): each names its instrument once."""


def outside_instruments() -> list[Path]:
    return [p for p in sorted(PACKAGE.rglob("*.py")) if "instruments" not in p.relative_to(PACKAGE).parts]


def test_no_module_outside_the_instruments_looks_one_up_or_branches_on_its_name():
    names = set(INSTRUMENTS)
    found = []
    for path in outside_instruments():
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Subscript) and isinstance(node.value, ast.Name) and node.value.id == "INSTRUMENTS" \
                    and isinstance(node.slice, ast.Constant) and node.slice.value in names:
                found.append(f"{path.relative_to(PACKAGE)}:{node.lineno} INSTRUMENTS[{node.slice.value!r}]")
            sides = (node.left, *node.comparators) if isinstance(node, ast.Compare) else ()
            if any(isinstance(c, ast.Constant) and c.value in names for c in sides) and any(_key(c) for c in sides):
                found.append(f"{path.relative_to(PACKAGE)}:{node.lineno} compares an instrument's name")
    assert found == []


def test_no_module_asks_a_result_which_kind_it_is():
    kinds = {kind.__name__ for kind in KINDS.values()}
    found = []
    for path in outside_instruments():
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id == "isinstance" \
                    and len(node.args) == 2:
                classes = node.args[1].elts if isinstance(node.args[1], ast.Tuple) else [node.args[1]]
                named = [c.id for c in classes if isinstance(c, ast.Name) and c.id in kinds]
                if named and path.stem not in {"base", "kinds"} and not _defines(path, named):
                    found.append(f"{path.relative_to(PACKAGE)}:{node.lineno} isinstance(…, {', '.join(named)})")
    assert found == []


def test_the_api_names_each_instrument_in_its_alias_only():
    text = ALIASES.read_text()
    for name in ("goniophotometer", "sphere"):
        assert text.count(f'_reading("{name}"') == 1, name


def _key(node: ast.AST) -> bool:
    """A variable or attribute that holds an instrument's (or a subcommand's) name."""

    word = node.id if isinstance(node, ast.Name) else node.attr if isinstance(node, ast.Attribute) else ""
    return word in {"instrument", "name", "command", "kind"}


def _defines(path: Path, classes: list[str]) -> bool:
    """True when ``path`` defines the classes it asks about (a kind's own module)."""

    tree = ast.parse(path.read_text())
    defined = {node.name for node in tree.body if isinstance(node, ast.ClassDef)}
    return set(classes) <= defined
