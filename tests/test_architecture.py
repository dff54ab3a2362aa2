"""Architecture guards: no import cycles among virtspec-mi's modules; imports flow one way.

Static (``ast``) reading of every ``.py`` file of the package (``virtspec_mi/``; a
``[tool.setuptools.package-dir]`` table of pyproject.toml, if any, is followed). Nothing is
imported and Mitsuba is never touched, so this runs in well under a second.

What counts as an import edge ``A -> B`` (A, B project modules):

* every ``import`` / ``from ... import`` statement anywhere in A: module level, inside
  functions and methods, inside ``if TYPE_CHECKING:`` blocks, ``try`` blocks, ...;
* relative imports (``from .x import y``, ``from . import x``, ``from ..pkg import x``);
* ``importlib.import_module("literal")`` / ``import_module("literal")`` /
  ``__import__("literal")``; a relative literal is resolved against the ``package``
  argument when that is ``__name__``, ``__package__`` or a string literal;
* ``from P import name`` counts as importing ``P`` and, when ``P.name`` is a module,
  ``P.name`` too;
* importing ``P.Q.M`` also runs the ``__init__`` of ``P.Q`` (and of ``P``), so it adds edges
  to those packages too -- except to packages that contain A itself: those are already
  initialised before A's body runs. Since every module lives inside ``virtspec_mi``, no
  *implicit* edge ever points at the root package; only a statement that names it
  (``import virtspec_mi``, ``from virtspec_mi import twostage``) does.
* the plugin registry: ``virtspec_mi.runtime.register()`` imports every module of its
  ``PLUGINS`` table (read from the file as a literal), so ``virtspec_mi.runtime`` has an
  edge to each of them;
* NOT counted: the root package's lazy ``_LAZY`` table (``importlib.import_module(_LAZY[name])``
  in ``__getattr__``: resolved on attribute access, not on import). Real import statements
  in ``__init__.py`` files do count.

The layering rules use :data:`LAYERS` below: the layers of the package (issue 21), every
module in one (:func:`test_every_module_belongs_to_a_layer`), and the kernel importing
nothing of the package outside ``virtspec_mi.kernel``.
"""

from __future__ import annotations

import ast
import importlib.util
import tomllib
from collections import defaultdict
from pathlib import Path

import pytest

from source_trees import parse

ROOT = Path(__file__).resolve().parents[1]

# ---------------------------------------------------------------------------------------
# Layers, top to bottom. Data flows downward: a module may import modules of its own layer
# or of a layer below it, never of a layer above it. Each entry is a dotted-name prefix: it
# matches that module and everything under it ("virtspec_mi.kernel" matches
# "virtspec_mi.kernel.tracer"; "virtspec_mi.scene" does not match "virtspec_mi.scenes"), the
# most specific entry winning; "=name" matches that module alone. Every module of the
# package must be in a layer. The first layer (the CLI) is special: nothing outside it may
# import it at all.
# ---------------------------------------------------------------------------------------
LAYERS: list[tuple[str, tuple[str, ...]]] = [
    ("cli", ("virtspec_mi.cli", "virtspec_mi.__main__")),
    ("api", ("virtspec_mi.api", "virtspec_mi.comparison", "virtspec_mi.scaleout", "virtspec_mi.validation",
             "virtspec_mi.scene", "virtspec_mi.runtime",
             # the exchange formats that take their readings through the API
             "virtspec_mi.exchange.albedo", "virtspec_mi.exchange.tables", "virtspec_mi.exchange.klems_gonio",
             "virtspec_mi.exchange.flip",
             "virtspec_mi.exchange.engine_tables", "virtspec_mi.exchange.audit",
             # applications: clients of the API and the engine that answer a user's question (fits,
             # derived quantities; the maths that results read is below)
             "virtspec_mi.applications")),
    # the integrators: Mitsuba's entry (mi.render), thin adapters over the instruments
    ("adapter", ("virtspec_mi.plugins.integrators",)),
    ("instruments", ("virtspec_mi.instruments",)),
    ("results", ("virtspec_mi.results",
                 # the derived quantities' maths that Result.colour() reads (issue 30)
                 "virtspec_mi.applications.derived.functionals", "virtspec_mi.applications.derived.delta_e",
                 "virtspec_mi.applications.derived.colour")),
    ("engine", ("virtspec_mi.engine",)),
    ("settings", ("virtspec_mi.settings",)),
    # exchange: the file formats and their sizing (the modules that measure are in the api layer)
    ("budgets/geometry/references", ("virtspec_mi.budgets", "virtspec_mi.geometry", "virtspec_mi.references",
                                     "virtspec_mi.exchange")),
    ("plugins", ("=virtspec_mi.plugins", "virtspec_mi.plugins.bsdfs", "virtspec_mi.leaf_data")),
    ("kernel", ("virtspec_mi.kernel",)),
    # the root package imports llvm and scenes (its public names load lazily: not counted);
    # virtspec_mi.scenes (the shipped scene files by name) and virtspec_mi.interrupts (SIGINT and
    # SIGTERM at safe points: the engine's runs, the command line's whole command) import nothing of it
    ("base", ("virtspec_mi.checks", "virtspec_mi.files", "virtspec_mi.llvm", "virtspec_mi.scenes",
              "virtspec_mi.interrupts", "=virtspec_mi",
              "=virtspec_mi.applications", "=virtspec_mi.applications.derived")),
]
"""
The layers of the package, top to bottom (issue 21). An entry names a module and everything
under it; ``=name`` names that module alone (a package's ``__init__``). Every module of the
package belongs to one layer (:func:`test_every_module_belongs_to_a_layer`).
"""

Graph = dict[str, set[str]]
Site = tuple[str, int]  # (file relative to ROOT, line)


# ------------------------------------------------------------------------ module discovery
def package_roots() -> dict[str, Path]:
    """Dotted package name -> directory, from pyproject's ``[tool.setuptools.package-dir]``."""

    config = tomllib.loads((ROOT / "pyproject.toml").read_text())
    mapping = config.get("tool", {}).get("setuptools", {}).get("package-dir", {})
    roots = {name: ROOT / directory for name, directory in mapping.items() if name}
    return roots or {"virtspec_mi": ROOT / "virtspec_mi"}


def project_files() -> dict[str, tuple[Path, bool]]:
    """Dotted module name -> (file, is_package) for every ``.py`` file of the project."""

    roots = package_roots()
    modules: dict[str, tuple[Path, bool]] = {}
    for package, directory in roots.items():
        for path in sorted(directory.rglob("*.py")):
            parts = path.relative_to(directory).with_suffix("").parts
            if "__pycache__" in parts or not all(part.isidentifier() for part in parts):
                continue
            is_package = parts[-1] == "__init__"
            if is_package:
                parts = parts[:-1]
            name = ".".join((package, *parts))
            # Where package-dir entries nest (virtspec_mi.plugins -> plugins/), the most specific
            # entry owns the name, not a same-named directory inside the outer one.
            owner = max((r for r in roots if name == r or name.startswith(r + ".")), key=len)
            if owner == package:
                modules[name] = (path, is_package)
    return modules


# ------------------------------------------------------------------------ import extraction
def _is_import_module_call(node: ast.Call) -> bool:
    func = node.func
    if isinstance(func, ast.Attribute):
        return func.attr == "import_module" and isinstance(func.value, ast.Name) and func.value.id == "importlib"
    return isinstance(func, ast.Name) and func.id in ("import_module", "__import__")


def _literal_import(node: ast.Call, module: str, package: str) -> str | None:
    """Absolute module name of an ``import_module("...")``-style call, or None when not literal."""

    if not node.args or not isinstance(node.args[0], ast.Constant) or not isinstance(node.args[0].value, str):
        return None
    name = node.args[0].value
    if not name.startswith("."):
        return name
    if isinstance(node.func, ast.Name) and node.func.id == "__import__":
        return None
    anchor_node = node.args[1] if len(node.args) > 1 else next(
        (kw.value for kw in node.keywords if kw.arg == "package"), None)
    if isinstance(anchor_node, ast.Name) and anchor_node.id == "__name__":
        anchor = module
    elif isinstance(anchor_node, ast.Name) and anchor_node.id == "__package__":
        anchor = package
    elif isinstance(anchor_node, ast.Constant) and isinstance(anchor_node.value, str):
        anchor = anchor_node.value
    else:
        return None
    try:
        return importlib.util.resolve_name(name, anchor)
    except (ImportError, ValueError):
        return None


def imports_of(source: str, module: str, is_package: bool, known: set[str]) -> list[tuple[str, int]]:
    """(imported project module, line) for every import in ``source`` (see module docstring)."""

    package = module if is_package else module.rpartition(".")[0]
    requested: list[tuple[str, int]] = []
    for node in ast.walk(parse(source)):
        if isinstance(node, ast.Import):
            requested += [(alias.name, node.lineno) for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                try:
                    base = importlib.util.resolve_name("." * node.level + (node.module or ""), package)
                except (ImportError, ValueError):
                    continue
            else:
                base = node.module or ""
            requested.append((base, node.lineno))
            requested += [(f"{base}.{alias.name}", node.lineno) for alias in node.names if alias.name != "*"]
        elif isinstance(node, ast.Call) and _is_import_module_call(node):
            name = _literal_import(node, module, package)
            if name:
                requested.append((name, node.lineno))

    found: list[tuple[str, int]] = []
    for name, line in requested:
        if name not in known:
            continue  # third-party, or ``from mod import function``
        found.append((name, line))
        parts = name.split(".")
        for i in range(1, len(parts)):
            ancestor = ".".join(parts[:i])
            if ancestor in known and not (module == ancestor or module.startswith(ancestor + ".")):
                found.append((ancestor, line))  # its __init__ runs first
    return [(name, line) for name, line in found if name != module]


def import_graph() -> tuple[Graph, dict[tuple[str, str], list[Site]]]:
    """The project's import graph and, for each edge, where it is made."""

    files = project_files()
    known = set(files)
    graph: Graph = {name: set() for name in files}
    sites: dict[tuple[str, str], list[Site]] = defaultdict(list)
    for name, (path, is_package) in files.items():
        for target, line in imports_of(path.read_text(encoding="utf-8"), name, is_package, known):
            graph[name].add(target)
            site = (str(path.relative_to(ROOT)), line)
            if site not in sites[name, target]:
                sites[name, target].append(site)
    for target, line in registered_plugins(files):
        graph["virtspec_mi.runtime"].add(target)
        sites["virtspec_mi.runtime", target].append(("virtspec_mi/runtime.py", line))
    return graph, sites


def registered_plugins(files: dict[str, tuple[Path, bool]]) -> list[tuple[str, int]]:
    """The modules ``virtspec_mi.runtime.register()`` imports: its ``PLUGINS`` table, as a literal."""

    tree = parse(files["virtspec_mi.runtime"][0].read_text(encoding="utf-8"))
    for node in ast.walk(tree):
        targets = [node.target] if isinstance(node, ast.AnnAssign) else getattr(node, "targets", [])
        if any(isinstance(t, ast.Name) and t.id == "PLUGINS" for t in targets) and node.value is not None:
            table = ast.literal_eval(node.value)
            return [(module, node.lineno) for _, module, _ in table.values()]
    raise AssertionError("virtspec_mi/runtime.py has no literal PLUGINS table")


# ------------------------------------------------------------------------ cycle finder
def strongly_connected_components(graph: Graph) -> list[list[str]]:
    """Tarjan's algorithm (iterative), components sorted, nodes sorted within each."""

    nodes = sorted(set(graph) | {t for targets in graph.values() for t in targets})
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    on_stack: set[str] = set()
    stack: list[str] = []
    components: list[list[str]] = []
    counter = 0
    for root in nodes:
        if root in index:
            continue
        work = [(root, iter(sorted(graph.get(root, ()))))]
        index[root] = low[root] = counter
        counter += 1
        stack.append(root)
        on_stack.add(root)
        while work:
            node, children = work[-1]
            child = next(children, None)
            if child is not None:
                if child not in index:
                    index[child] = low[child] = counter
                    counter += 1
                    stack.append(child)
                    on_stack.add(child)
                    work.append((child, iter(sorted(graph.get(child, ())))))
                elif child in on_stack:
                    low[node] = min(low[node], index[child])
                continue
            work.pop()
            if work:
                parent = work[-1][0]
                low[parent] = min(low[parent], low[node])
            if low[node] == index[node]:
                component = []
                while True:
                    member = stack.pop()
                    on_stack.discard(member)
                    component.append(member)
                    if member == node:
                        break
                components.append(sorted(component))
    return sorted(components)


def cyclic_components(graph: Graph) -> list[list[str]]:
    """Components that contain a cycle: more than one module, or a module importing itself."""

    return [c for c in strongly_connected_components(graph) if len(c) > 1 or c[0] in graph.get(c[0], ())]


def elementary_cycles(graph: Graph, component: list[str], limit: int = 100) -> list[list[str]]:
    """Every elementary cycle inside one component (at most ``limit``), each as ``[a, b, ..., a]``.

    Each cycle is reported once, starting from its alphabetically smallest module.
    """

    members = set(component)
    rank = {node: i for i, node in enumerate(component)}
    cycles: list[list[str]] = []
    for start in component:
        path = [start]
        work = [iter(sorted(t for t in graph.get(start, ()) if t in members and rank[t] >= rank[start]))]
        while work and len(cycles) < limit:
            child = next(work[-1], None)
            if child is None:
                work.pop()
                path.pop()
            elif child == start:
                cycles.append([*path, start])
            elif child not in path:
                path.append(child)
                work.append(iter(sorted(t for t in graph.get(child, ()) if t in members and rank[t] >= rank[start])))
    return cycles


def describe_cycles(graph: Graph, sites: dict[tuple[str, str], list[Site]] | None = None) -> str:
    """Human-readable report of every cycle of ``graph``; empty when there is none."""

    sites = sites or {}
    blocks = []
    for n, component in enumerate(cyclic_components(graph), 1):
        lines = [f"group {n}: {', '.join(component)}", "  cycles:"]
        cycles = elementary_cycles(graph, component)
        lines += [f"    {' -> '.join(cycle)}" for cycle in cycles]
        if len(cycles) >= 100:
            lines.append("    ... (more not listed)")
        lines.append("  imports inside this group (cut one per cycle):")
        for a in component:
            for b in sorted(graph.get(a, ())):
                if b in component:
                    where = ", ".join(f"{path}:{line}" for path, line in sites.get((a, b), []))
                    lines.append(f"    {a} -> {b}" + (f"  ({where})" if where else ""))
        blocks.append("\n".join(lines))
    return "\n\n".join(blocks)


# ------------------------------------------------------------------------ layering
def _in(module: str, prefixes: tuple[str, ...]) -> bool:
    return any(module == p[1:] if p.startswith("=") else module == p or module.startswith(p + ".")
               for p in prefixes)


INSTRUMENT_PARTS: dict[str, str] = {
    "walk": "kernel", "hook": "kernel",
    "geometry": "budgets/geometry/references", "bins": "budgets/geometry/references",
    # a sphere's real ports, its beam, and the walk of a real sphere (it extends the plain walk, so it
    # cannot be a kernel-side hook: the kernel receives it as plain values)
    "ports": "budgets/geometry/references", "beam": "budgets/geometry/references",
    "real": "budgets/geometry/references", "budget": "results",
    "model": "budgets/geometry/references", "theory": "budgets/geometry/references",
    "result": "results", "plot": "results",
    "integrator": "adapter",
}
"""
The layer of each part of an instrument's folder (``virtspec_mi.instruments.<name>.<part>``),
by the part's module name: its kernel-side exit hook (``walk``/``hook``: the kernel layer,
importing only ``virtspec_mi.kernel``), its geometry, bins and physics references, its result
and plots, its integrator; the folder's ``__init__`` (the instrument) is in the instruments layer.
"""


def layer_of(module: str) -> int | None:
    """
    Index into :data:`LAYERS` (0 = top) of the most specific matching prefix, or None; a
    part of an instrument's folder by :data:`INSTRUMENT_PARTS`.
    """

    parts = module.split(".")
    if len(parts) == 4 and parts[:2] == ["virtspec_mi", "instruments"] and parts[3] in INSTRUMENT_PARTS:
        return [name for name, _ in LAYERS].index(INSTRUMENT_PARTS[parts[3]])

    best: tuple[int, int] | None = None  # (prefix length, layer)
    for i, (_, prefixes) in enumerate(LAYERS):
        for p in prefixes:
            if _in(module, (p,)) and (best is None or len(p) > best[0]):
                best = (len(p), i)
    return None if best is None else best[1]


def layering_violations(graph: Graph, sites: dict[tuple[str, str], list[Site]] | None = None) -> list[str]:
    sites = sites or {}
    problems = []
    for a in sorted(graph):
        for b in sorted(graph[a]):
            la, lb = layer_of(a), layer_of(b)
            if lb == 0 and la != 0:
                rule = f"only the {LAYERS[0][0]} layer may import it"
            elif la is not None and lb is not None and lb < la:
                rule = f"{LAYERS[la][0]} must not import {LAYERS[lb][0]}"
            else:
                continue
            where = ", ".join(f"{path}:{line}" for path, line in sites.get((a, b), []))
            problems.append(f"{a} -> {b}: {rule}" + (f"  ({where})" if where else ""))
    return problems


# ------------------------------------------------------------------------ tests
@pytest.fixture(scope="module")
def project_graph() -> tuple[Graph, dict[tuple[str, str], list[Site]]]:
    return import_graph()


def test_the_import_graph_sees_the_project(project_graph):
    """Guard against a vacuous pass: both package roots are read and imports are found."""

    graph, _ = project_graph
    assert "virtspec_mi" in graph and "virtspec_mi.plugins" in graph
    assert "virtspec_mi.plugins.integrators.spectrophotometer" in graph["virtspec_mi.runtime"]
    assert any(name.startswith("virtspec_mi.plugins.") for name in graph)
    assert sum(map(len, graph.values())) > len(graph) // 2


def test_no_import_cycles(project_graph):
    graph, sites = project_graph
    report = describe_cycles(graph, sites)
    groups = cyclic_components(graph)
    assert not report, f"{len(groups)} group(s) of modules import one another in a cycle:\n\n{report}"


def test_imports_flow_down_the_layers(project_graph):
    graph, sites = project_graph
    problems = layering_violations(graph, sites)
    assert not problems, "imports against the layering (see LAYERS in this file):\n" + "\n".join(problems)


PAST_THE_API: tuple[str, ...] = ("virtspec_mi.engine", "virtspec_mi.kernel", "virtspec_mi.checks")
"""
What the command line reaches only through the API (issue 29): the engine and the kernel
below it, and the boundary's checks and parsers (:mod:`virtspec_mi.api` offers what the
command line needs of them: the parsers, the checkpoint of an ``out=`` path).
"""


def test_the_command_line_reaches_the_engine_only_through_the_api(project_graph):
    graph, sites = project_graph
    past = sorted(f"{a} -> {b}  ({', '.join(f'{p}:{line}' for p, line in sites.get((a, b), []))})"
                  for a in graph if _in(a, ("virtspec_mi.cli",)) for b in graph[a] if _in(b, PAST_THE_API))
    assert not past, "the command line imports past the API (take it from virtspec_mi.api):\n" + "\n".join(past)


def test_every_module_belongs_to_a_layer(project_graph):
    graph, _ = project_graph
    unplaced = sorted(name for name in graph if layer_of(name) is None)
    assert not unplaced, f"modules in no layer of LAYERS (place each in one): {', '.join(unplaced)}"
    assert layer_of("virtspec_mi") == len(LAYERS) - 1 and layer_of("virtspec_mi.plugins") == layer_of(
        "virtspec_mi.plugins.bsdfs.abm_b") != layer_of("virtspec_mi.plugins.integrators.spectrophotometer")


def test_cycle_finder_finds_a_cycle_and_passes_a_dag():
    acyclic = {"a": {"b", "c"}, "b": {"c"}, "c": set(), "d": {"a"}}
    assert cyclic_components(acyclic) == []
    assert describe_cycles(acyclic) == ""

    cyclic = {"a": {"b"}, "b": {"c"}, "c": {"a", "d"}, "d": set(), "e": {"e"}, "f": {"g"}, "g": {"f"}}
    assert cyclic_components(cyclic) == [["a", "b", "c"], ["e"], ["f", "g"]]
    assert elementary_cycles(cyclic, ["a", "b", "c"]) == [["a", "b", "c", "a"]]
    report = describe_cycles(cyclic)
    assert "a -> b -> c -> a" in report and "e -> e" in report and "f -> g -> f" in report
    assert "d" not in report.replace("imports inside", "")

    # two cycles sharing a node are both listed
    figure_eight = {"x": {"y", "z"}, "y": {"x"}, "z": {"x"}}
    assert elementary_cycles(figure_eight, ["x", "y", "z"]) == [["x", "y", "x"], ["x", "z", "x"]]


def test_import_extraction_counts_every_kind_of_import():
    source = '''
import importlib
from typing import TYPE_CHECKING
import numpy as np
import pkg.top
from pkg.sub import leaf, not_a_module
from . import sibling
from .. import outer

if TYPE_CHECKING:
    from pkg.typed import T

def f():
    import pkg.in_function
    importlib.import_module("pkg.dynamic")
    importlib.import_module(".by_package", __package__)
    importlib.import_module("..by_literal", package="pkg.inner")
    importlib.import_module(name_from_a_table)

class C:
    def m(self):
        from .sub2 import x
'''
    known = {
        "pkg", "pkg.top", "pkg.sub", "pkg.sub.leaf", "pkg.inner", "pkg.inner.mod", "pkg.inner.sibling",
        "pkg.outer", "pkg.typed", "pkg.in_function", "pkg.dynamic", "pkg.inner.by_package",
        "pkg.by_literal", "pkg.inner.sub2", "numpy_is_not_known",
    }
    # pkg.inner.mod is a plain module: "." is pkg.inner and ".." is pkg. Its enclosing packages
    # (pkg, pkg.inner) get no implicit edges, only the ones named by "from . / .. import".
    found = {name for name, _ in imports_of(source, "pkg.inner.mod", False, known)}
    assert found == {
        "pkg.top", "pkg.sub", "pkg.sub.leaf",
        "pkg.inner", "pkg.inner.sibling",  # from . import sibling
        "pkg", "pkg.outer",  # from .. import outer
        "pkg.typed", "pkg.in_function", "pkg.dynamic", "pkg.inner.by_package", "pkg.by_literal",
        "pkg.inner.sub2",
    }

    # In a package's __init__, "." is the package itself. Importing q.r.s runs q and q.r too.
    known = {"p", "p.a", "p.a.b", "q", "q.r", "q.r.s"}
    found = {name for name, _ in imports_of("from .a import b\nimport q.r.s", "p", True, known)}
    assert found == {"p.a", "p.a.b", "q", "q.r", "q.r.s"}

    # importlib.import_module(".x", __name__) resolves against the module's own name
    found = {name for name, _ in imports_of('import importlib\nimportlib.import_module(".x", __name__)', "p", True,
                                           {"p", "p.x"})}
    assert found == {"p.x"}


def test_the_kernel_imports_nothing_above_it(project_graph):
    """
    The kernel takes plain values: no module of ``virtspec_mi.kernel``, nor an instrument's
    kernel-side exit hook, imports a package module outside ``virtspec_mi.kernel``.
    """

    graph, sites = project_graph
    bottom = [name for name, _ in LAYERS].index("kernel")
    kernel = [name for name in graph if layer_of(name) == bottom]
    assert {"virtspec_mi.kernel.tracer", "virtspec_mi.instruments.sphere.walk",
            "virtspec_mi.instruments.goniophotometer.hook"} <= set(kernel)
    outside = sorted(f"{a} -> {b}  ({', '.join(f'{p}:{line}' for p, line in sites.get((a, b), []))})"
                     for a in kernel for b in graph[a]
                     if not (b == "virtspec_mi.kernel" or b.startswith("virtspec_mi.kernel.")))
    assert not outside, "the kernel imports modules above it:\n" + "\n".join(outside)
