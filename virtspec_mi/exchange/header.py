"""
Albedo tables as C/C++ headers, and published tables read back
==============================================================

:func:`write_header` prints a certified :class:`~virtspec_mi.applications.tables.table.AlbedoTable`
as a C/C++ header in the layout of Blender Cycles' generated tables
(``intern/cycles/app/cycles_precompute.cpp``): one ``static const float
table_<name>[<size>] = { … };`` per table, flat, in the engine's memory order
(Cycles: ``[z][y][x]`` = [η][μ][roughness], roughness fastest), so that a renderer can
replace its array with this one. Names follow Cycles: ``table_ggx_E``,
``table_ggx_Eavg``, ``table_ggx_glass_E``, ``table_ggx_glass_inv_E`` (light from
inside: 1/η), ``table_ggx_glass_Eavg``, ``table_ggx_glass_inv_Eavg`` (``beckmann``
in place of ``ggx`` for Beckmann tables). Values are printed with nine significant
digits (float32 round-trips exactly) and are not clamped (they are ratios of counts,
already in [0, 1]).

A comment block and ``#define`` constants carry the provenance and the certificate
(model, Mitsuba version, ε, δ, bound, rays, seed, grid, memory order, the statement),
and per table the largest certified tolerance ``<NAME>_EPSILON`` (ε plus rounding
bias). The header compiles as C99 and C++ (``tests/exchange/test_header.py`` compiles
it with the system compiler).

:func:`read_table_values` reads a published table for
:meth:`~virtspec_mi.applications.tables.table.AlbedoTable.compare`: ``.npy``, ``.nc``, ``.csv`` /
``.txt`` or a C/C++ header (the numbers between the braces of the named array,
``f`` suffixes and comments allowed).

References
----------
Kulla, C., Conty, A. (2017). Revisiting physically based shading at Imageworks. SIGGRAPH
course *Physically Based Shading in Theory and Practice* (the tables renderers ship).
"""

from __future__ import annotations

import os
import re
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["array_name", "write_header", "read_table_values"]


def array_name(table: Any, average: bool = False, side: str = "outside") -> str:
    """Cycles' name of a table's array: ``table_ggx_E``, ``table_ggx_glass_inv_Eavg`` …"""

    base = f"table_{table.distribution}" + ("_glass" if table.model == "glass" else "")
    if table.model == "glass" and side == "inside":
        base += "_inv"
    return base + ("_Eavg" if average else "_E")


def _floats(values: np.ndarray, per_line: int) -> str:
    flat = [f"{float(np.float32(v)):.9g}" for v in np.ravel(values)]
    text = [f"{v}f" if any(c in v for c in ".en") else f"{v}.0f" for v in flat]
    lines = ["  " + ", ".join(text[i:i + per_line]) for i in range(0, len(text), per_line)]
    return ",\n".join(lines)


def _macro(name: str) -> str:
    return re.sub(r"[^A-Z0-9]+", "_", name.upper())


def write_header(table: Any) -> str:
    """
    The C/C++ header text of ``table`` (see the module docstring).

    References
    ----------
    The layout of Cycles' ``cycles_precompute.cpp`` output.
    """

    description = table.description()
    prov = description["provenance"]
    # every macro carries the table's own prefix (its arrays' base name, TABLE_GGX_GLASS …) and the guard its grid,
    # so that headers of several tables compile in one translation unit, with -Werror too
    prefix = _macro(array_name(table)[:-len("_E")])
    guard = _macro(f"VIRTSPEC_{prefix}_{table.engine}_ALBEDO_H")
    order = description["order"]
    lines = [
        "/* Certified directional-albedo table made by virtspec-mi (a virtual spectrophotometer).",
        f" *   model:        {description['model_description']}, distribution {table.distribution}",
        f" *   G and F:      {prov.get('bsdf_model', 'Mitsuba ' + str(prov.get('bsdf')))}",
        f" *   measured:     Mitsuba {prov.get('mitsuba')} ({prov.get('variant')}), virtspec-mi {prov.get('virtspec_mi')},"
        f" {prov.get('created')}",
        f" *   grid:         engine convention '{table.engine}'; memory order {' '.join(order)} (last index fastest)",
        f" *   certificate:  {description['certificate']}",
        f" *   epsilon = {table.epsilon:g}, delta = {table.delta:g}, bound = {table.bound}, rays = {table.rays:,},"
        f" seed = {prov.get('seed')}",
        " *   E = (reflected + transmitted rays) / rays of a collimated beam at theta_i = acos(mu);",
        " *   Eavg = the same under a cosine-weighted diffuse beam (2 * integral of E(mu) mu dmu, no quadrature).",
        " */",
        f"#ifndef {guard}",
        f"#define {guard}",
        "",
        f"#define {prefix}_EPSILON {table.epsilon!r}",
        f"#define {prefix}_DELTA {table.delta!r}",
        f"#define {prefix}_RAYS {table.rays}ULL",
        "",
    ]
    sides = ("outside", "inside") if table.model == "glass" else ("outside",)
    values = table.layout()
    tolerance = table.layout(table.certified_epsilon())
    for s, side in enumerate(sides):
        block = values[s] if table.model == "glass" else values
        tol = tolerance[s] if table.model == "glass" else tolerance
        name = array_name(table, side=side)
        dims = " x ".join(f"{d} {n}" for d, n in zip(order[-block.ndim:], block.shape))
        lines += [f"/* {name}: {dims} */",
                  f"#define {_macro(name)}_SIZE {block.size}",
                  f"#define {_macro(name)}_EPSILON {float(np.nanmax(tol))!r}",
                  f"static const float {name}[{block.size}] = {{", _floats(block, block.shape[-1]), "};", ""]
        if table.E_avg is not None:
            avg = table.E_avg[s] if table.model == "glass" else table.E_avg
            tol_avg = table.certified_epsilon(average=True)
            tol_avg = tol_avg[s] if table.model == "glass" else tol_avg
            name = array_name(table, average=True, side=side)
            dims = " x ".join(f"{d} {n}" for d, n in zip(description["average_order"][-avg.ndim:], avg.shape))
            lines += [f"/* {name}: {dims} */",
                      f"#define {_macro(name)}_SIZE {avg.size}",
                      f"#define {_macro(name)}_EPSILON {float(np.nanmax(tol_avg))!r}",
                      f"static const float {name}[{avg.size}] = {{", _floats(avg, avg.shape[-1]), "};", ""]
    lines += [f"#endif /* {guard} */", ""]
    return "\n".join(lines)


_NUMBER = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")


def _header_values(text: str, array: str | None) -> np.ndarray:
    text = re.sub(r"/\*.*?\*/", " ", text, flags=re.S)
    text = re.sub(r"//[^\n]*", " ", text)
    found = {m.group(1): m.group(2) for m in re.finditer(r"(\w+)\s*\[[^\]]*\]\s*=\s*\{(.*?)\}\s*;", text, flags=re.S)}
    if not found:
        raise ValueError("the header holds no array 'NAME[...] = { ... };'")
    if array is None or array not in found:
        if len(found) == 1 and array is None:
            array = next(iter(found))
        else:
            raise ValueError(f"array {array!r} is not in the header (it holds: {', '.join(found)}); name it with array=")
    return np.array([float(x) for x in _NUMBER.findall(found[array])], dtype=np.float64)


def _text(path: Path) -> str:
    """A published table's text (``ValueError`` naming the file for bytes that are not UTF-8 text)."""

    try:
        return path.read_text(encoding="utf-8")
    except UnicodeDecodeError as error:
        raise ValueError(f"published table {path} is not text (byte {error.start}: {error.reason}); give a .npy, "
                         ".nc, .csv/.txt of numbers or a C/C++ header") from None


_DECIMAL_COMMA = re.compile(r"[-+]?\d+,\d+(?:[eE][-+]?\d+)?")


def _text_values(path: Path) -> np.ndarray:
    """
    Every number of a ``.csv`` / ``.txt`` table (fields separated by commas, semicolons, tabs
    or spaces; ``#`` comments): a line holding anything else — a header row, a word — or a
    number written with a decimal comma (``0,52`` between semicolons or tabs) is refused
    naming the line, never read as numbers (a header's ``alpha0.1`` is no cell).
    """

    values: list[float] = []
    for number, raw in enumerate(_text(path).splitlines(), 1):
        line = raw.split("#", 1)[0].strip()
        if not line:
            continue
        if ";" in line or "\t" in line:
            fields = [f.strip() for f in re.split(r"[;\t]", line) if f.strip()]
            comma = next((f for f in fields if _DECIMAL_COMMA.fullmatch(f)), None)
            if comma is not None:
                raise ValueError(f"published table {path.name}, line {number}: {comma!r} is written with a decimal "
                                 "comma; write decimal points (0.52)")
        else:
            fields = [f for f in re.split(r"[,\s]+", line) if f]
        for field in fields:
            if _NUMBER.fullmatch(field) is None and field.lower() not in ("nan", "inf", "-inf", "+inf"):
                raise ValueError(f"published table {path.name}, line {number}: {field!r} is not a number (a header "
                                 "row? comment it out with #); the file holds the table's values only")
            values.append(float(field))
    return np.array(values, dtype=np.float64)


def _sample(values: Any) -> str:
    """What a sequence that is not numbers holds: its first non-number, shown short."""

    for value in np.asarray(values, dtype=object).ravel()[:1000]:
        if isinstance(value, (str, bytes)) or not np.isscalar(value):
            text = repr(value)
            return text if len(text) <= 40 else text[:37] + "..."
    return "values that are not numbers"


def read_table_values(published: Any, array: str | None = None, expected: int | None = None) -> np.ndarray:
    """
    The numbers of a published table, flat in the file's order.

    Parameters
    ----------
    published
        An array, or a path: ``.npy``, ``.nc`` (variable ``array``, default ``E``),
        ``.csv`` / ``.txt`` (every number, comments after ``#`` ignored), or a C/C++
        header (``.h``, ``.hpp``, ``.c``, ``.cpp``, ``.inc``) holding the array ``array``.
    array
        The array (header) or variable (NetCDF) to read.
    expected
        The number of values the table needs; another count raises ``ValueError``.
    """

    if isinstance(published, np.ndarray) or isinstance(published, (list, tuple)):
        try:
            values = np.asarray(published, dtype=np.float64).ravel()
        except (TypeError, ValueError):
            raise ValueError(f"published must be an array of numbers (one per cell), a file of one, or a table's .nc "
                             f"(got a {type(published).__name__} holding {_sample(published)})") from None
    elif isinstance(published, (str, os.PathLike)):
        path = Path(published)
        if not path.is_file():
            raise ValueError(f"published table {path} is not a file")
        suffix = path.suffix.lower()
        if suffix == ".npy":
            try:
                values = np.load(path, allow_pickle=False).astype(np.float64).ravel()
            except (OSError, ValueError, TypeError, EOFError) as error:  # random bytes, a pickle, strings
                raise ValueError(f"published table {path} is not a .npy array of numbers ({error})") from None
        elif suffix == ".nc":
            from virtspec_mi.base.files import read_netcdf

            dataset = read_netcdf(path, "published table")
            name = array or "E"
            if name not in dataset:
                raise ValueError(f"variable {name!r} is not in {path.name} (it holds: {', '.join(dataset.data_vars)})")
            values = np.asarray(dataset[name].values, dtype=np.float64).ravel()
        elif suffix in (".csv", ".txt"):
            values = _text_values(path)
        elif suffix in (".h", ".hpp", ".c", ".cpp", ".cc", ".inc"):
            values = _header_values(_text(path), array)
        else:
            raise ValueError(f"published table must be .npy, .nc, .csv, .txt or a C/C++ header (got {path.name!r})")
    else:
        raise ValueError(f"published must be an array or a file path (got {type(published).__name__})")
    if expected is not None and values.size != expected:
        raise ValueError(f"the published table holds {values.size} values; this table has {expected} cells")
    if not np.all(np.isfinite(values)):
        raise ValueError("the published table holds values that are not finite numbers")
    return values
