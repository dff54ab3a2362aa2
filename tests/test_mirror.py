"""
Tests mirror the package (issue 38 item 5): every module of ``virtspec_mi`` has its test
file ``tests/<subpackage>/test_<module>.py`` — a package's ``__init__.py`` is tested in
``tests/<subpackage>/<package>/test_<package>.py``, the root package in
``tests/test_package.py`` — or is named in :data:`COVERED_ELSEWHERE` with the test files
that cover it and why. A module with nothing to test of its own (``__main__.py``, or an
``__init__.py`` that defines no function and no class: re-exports and a docstring) needs
none. The list names no module that has its mirror file (then it goes), no test file that
does not exist, and no module that does not exist.
"""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "virtspec_mi"

COVERED_ELSEWHERE: dict[str, tuple[tuple[str, ...], str]] = {
    # module: (the test files that cover it, why it has none of its own)
}
"""Modules covered by other test files: module → (those files, the reason)."""


def mirror(path: Path) -> Path:
    """The test file of the module at ``path``."""

    relative = path.relative_to(PACKAGE)
    if relative == Path("__init__.py"):
        return ROOT / "tests" / "test_package.py"
    folder = relative.parent.parts
    name = folder[-1] if relative.name == "__init__.py" else relative.stem
    return ROOT / "tests" / Path(*folder) / f"test_{name}.py"


def dotted(path: Path) -> str:
    relative = path.relative_to(ROOT).with_suffix("")
    parts = relative.parts[:-1] if relative.name == "__init__" else relative.parts
    return ".".join(parts)


def needs_a_test(path: Path) -> bool:
    """False for a ``__main__.py`` and an ``__init__.py`` that defines nothing (no function, no class)."""

    if path.name == "__main__.py":
        return False
    if path.name != "__init__.py":
        return True
    tree = ast.parse(path.read_text())
    return any(isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)) for node in tree.body)


MODULES = {dotted(path): path for path in sorted(PACKAGE.rglob("*.py"))}


def test_every_module_has_its_mirror_test_file_or_is_listed():
    missing = [f"{name} (tests/{mirror(path).relative_to(ROOT / 'tests')})" for name, path in MODULES.items()
               if needs_a_test(path) and not mirror(path).exists() and name not in COVERED_ELSEWHERE]
    assert not missing, "modules without their test file (write it, or list the module in COVERED_ELSEWHERE with " \
                        "the files that cover it and why):\n  " + "\n  ".join(missing)


def test_the_list_names_existing_modules_without_a_mirror_and_existing_test_files():
    for name, (files, reason) in COVERED_ELSEWHERE.items():
        assert name in MODULES, f"{name} is no module of virtspec_mi"
        assert not mirror(MODULES[name]).exists(), f"{name} has its mirror test file: take it off the list"
        assert reason.strip() and files, name
        for file in files:
            assert (ROOT / file).is_file(), f"{name}: {file} does not exist"


def test_the_mirror_rule_finds_the_files_it_should():
    """Planted: a module's, a package's and the root's test files; a docstring-only ``__init__`` needs none."""

    assert mirror(PACKAGE / "engine" / "checkpoint.py") == ROOT / "tests" / "engine" / "test_checkpoint.py"
    assert mirror(PACKAGE / "instruments" / "gloss" / "__init__.py") == \
        ROOT / "tests" / "instruments" / "gloss" / "test_gloss.py"
    assert mirror(PACKAGE / "__init__.py") == ROOT / "tests" / "test_package.py"
    assert not needs_a_test(PACKAGE / "__main__.py") and needs_a_test(PACKAGE / "engine" / "checkpoint.py")
    assert not needs_a_test(PACKAGE / "exchange" / "__init__.py") or "def " in (
        PACKAGE / "exchange" / "__init__.py").read_text()
