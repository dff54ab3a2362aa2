"""
The registry is the one place that knows the instruments (virtspec_mi.instruments): no module
outside an instrument's own module looks one up by its name, branches on its name, or asks
a result which kind it is. The command line, the result files, the integrator and the
contract test are generated from the rows (a static reading of every module). The API's
documented functions (``measure``/``sweep``/``gonio``/``sphere_measure``) find their
instrument by their own word (:func:`virtspec_mi.instruments.commanding`).
"""

from __future__ import annotations

import ast
from pathlib import Path

from virtspec_mi.instruments import INSTRUMENTS
from virtspec_mi.results.base import KINDS

from source_trees import parse

PACKAGE = Path(__file__).resolve().parents[2] / "virtspec_mi"


def outside_instruments() -> list[Path]:
    return [p for p in sorted(PACKAGE.rglob("*.py")) if "instruments" not in p.relative_to(PACKAGE).parts]


def test_no_module_outside_the_instruments_looks_one_up_or_branches_on_its_name():
    names = set(INSTRUMENTS)
    found = []
    for path in outside_instruments():
        for node in ast.walk(parse(path.read_text())):
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
        for node in ast.walk(parse(path.read_text())):
            if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id == "isinstance" \
                    and len(node.args) == 2:
                classes = node.args[1].elts if isinstance(node.args[1], ast.Tuple) else [node.args[1]]
                named = [c.id for c in classes if isinstance(c, ast.Name) and c.id in kinds]
                if named and path.stem not in {"base", "kinds"} and not _defines(path, named):
                    found.append(f"{path.relative_to(PACKAGE)}:{node.lineno} isinstance(…, {', '.join(named)})")
    assert found == []


def test_no_module_outside_an_instruments_folder_names_it():
    """
    The done-when of issue 29: outside ``instruments/<name>/`` (and the registry, which lists
    the rows) no module imports an instrument's folder, writes its module path, or passes its
    registry name as a value (an argument, ``instrument=``, an ``INSTRUMENTS`` key). Docstrings
    and comments may name it (documentation); a word that is also a physical quantity (a
    sphere result's ``hemispherical`` reading of the same rays) is not passed as a name. A
    folder may hold more than one row (the sphere folder: the single and the double sphere):
    its modules may name each of its own rows.
    """

    names = set(INSTRUMENTS)
    housed = {name: row.__module__.split(".")[2] for name, row in INSTRUMENTS.items()
              if row.__module__.startswith("virtspec_mi.instruments.")}
    found = []
    for path in sorted(PACKAGE.rglob("*.py")):
        parts = path.relative_to(PACKAGE).parts
        if parts == ("instruments", "__init__.py"):
            continue  # the registry
        own = parts[1] if parts[0] == "instruments" and len(parts) > 2 else None
        tree = parse(path.read_text())
        where = f"{path.relative_to(PACKAGE)}"
        for node in ast.walk(tree):
            if isinstance(node, (ast.Import, ast.ImportFrom)):
                modules = [a.name for a in node.names] if isinstance(node, ast.Import) else [node.module or ""]
                found += [f"{where}:{node.lineno} imports {m}" for m in modules if _folder(m, names, own)]
            elif isinstance(node, ast.Constant) and isinstance(node.value, str) and _folder(node.value, names, own):
                found.append(f"{where}:{node.lineno} writes the module path {node.value!r}")
            elif isinstance(node, ast.Call):
                values = [*node.args, *(k.value for k in node.keywords)]
                found += [f"{where}:{node.lineno} passes the name {v.value!r}" for v in values
                          if isinstance(v, ast.Constant) and v.value in names - {own}
                          and housed.get(v.value) != own]
    assert found == []


def test_the_grep_finds_what_it_forbids():
    """The rule above is not vacuous: the old API's alias and import are caught."""

    names = set(INSTRUMENTS)
    assert _folder("virtspec_mi.instruments.sphere.result", names, None)
    assert not _folder("virtspec_mi.instruments.sphere.result", names, "sphere")
    assert not _folder("virtspec_mi.instruments.base", names, None)
    assert "goniophotometer" in names and "sphere" in names


def _folder(module: str, names: set[str], own: str | None) -> bool:
    """True when ``module`` (a dotted or slashed path) is inside the folder of an instrument other than ``own``."""

    parts = module.replace("/", ".").split(".")
    return len(parts) >= 3 and parts[:2] == ["virtspec_mi", "instruments"] and parts[2] in names - {own}


def _key(node: ast.AST) -> bool:
    """A variable or attribute that holds an instrument's (or a subcommand's) name."""

    word = node.id if isinstance(node, ast.Name) else node.attr if isinstance(node, ast.Attribute) else ""
    return word in {"instrument", "name", "command", "kind"}


def _defines(path: Path, classes: list[str]) -> bool:
    """True when ``path`` defines the classes it asks about (a kind's own module)."""

    tree = parse(path.read_text())
    defined = {node.name for node in tree.body if isinstance(node, ast.ClassDef)}
    return set(classes) <= defined
