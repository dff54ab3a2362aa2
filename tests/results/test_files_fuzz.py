"""
Property-based tests (Hypothesis) of reading result files: issue 22, item 1.

Valid files of every result kind (a hemispherical parameter sweep, a hemispherical
reading, a goniophotometer reading, a sphere sweep) in every format (NetCDF, CSV, JSON —
also what ``virtspec measure --json`` prints —, Zarr) are mutated the ways a hand, a
script or a damaged disk changes a file: a count up or down, to a fraction, text, NaN,
an infinity, a negative number or null; a field or variable dropped, added, reshaped or
swapped with another; a coordinate unsorted, repeated or NaN; the format tag or version
changed; the file truncated. Reading it back must give either a one-line ``ValueError``
(or ``FileNotFoundError``) naming the file — never a ``KeyError``, ``IndexError``,
``TypeError`` or ``RecursionError`` — or a result identical to the original
(``as_dict()``-equal). Derandomized with fixed example counts: the same examples on every
run (a few seconds).
"""

from __future__ import annotations

import json
import math
import os
import shutil
import tempfile
from pathlib import Path
from typing import Any, Callable

import numpy as np
import pytest

hypothesis = pytest.importorskip("hypothesis")
from hypothesis import HealthCheck, event, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

import virtspec_mi as vm  # noqa: E402
from result_kinds import gonio_from_counts, hemispherical_grid, sphere_grid  # noqa: E402
from virtspec_mi.kernel.counts import Counts  # noqa: E402

PROFILE = dict(derandomize=True, deadline=None, database=None,
               suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture,
                                      HealthCheck.data_too_large])
EXAMPLES = {".json": 40, ".csv": 25, ".nc": 10, ".zarr": 10}  # NetCDF and Zarr: one test
SCRATCH = "/dev/shm" if os.access("/dev/shm", os.W_OK) else None  # memory, where there is one: no disk waits


def scratch() -> tempfile.TemporaryDirectory:
    return tempfile.TemporaryDirectory(dir=SCRATCH)

# What a count may become: off by one either way, far above, negative, a fraction, text, NaN, infinite, null, a bool.
COUNT_CHANGES: list[Callable[[Any], Any]] = [
    lambda v: v + 1, lambda v: v - 1, lambda v: v + 10**6, lambda v: -1, lambda v: v + 0.5, lambda v: str(v),
    lambda v: math.nan, lambda v: math.inf, lambda v: None, lambda v: True, lambda v: 10**400, lambda v: "1e400",
]
TAGS = ["virtspec-mi result 2", "virtspec-mi gonio 9", "virtspec-mi sphere 0", "virtspec-mi result", "nonsense", 1,
        None, "virtspec-mi weird 1"]


@pytest.fixture(scope="module")
def originals() -> Any:
    """Every kind, written in every format: name -> (result, suffix -> path)."""

    grid = hemispherical_grid()
    kinds = {"sweep": grid, "reading": grid.sel(theta_i=30, **{"specimen.thickness": 2e-4}),
             "gonio": gonio_from_counts(), "sphere": sphere_grid()}
    folder = Path(tempfile.mkdtemp(dir=SCRATCH))
    out = {}
    for name, result in kinds.items():
        out[name] = (result, {suffix: result.write(folder / f"{name}{suffix}") for suffix in EXAMPLES})
    yield out
    shutil.rmtree(folder)


def _canonical(result: Any) -> str:
    return json.dumps(result.as_dict(), sort_keys=True, default=str)


def _event(text: str) -> None:
    """Hypothesis's ``event`` (the statistics of ``--hypothesis-show-statistics``), outside a Hypothesis test nothing."""

    try:
        event(text)
    except hypothesis.errors.InvalidArgument:
        pass


def check_outcome(path: Path, original: Any, sealed: bool = True) -> str:
    """
    Read ``path``: a one-line error naming it, or the original result exactly — or, for a
    file whose checksum was dropped (read by the rules alone: a hand-made file), a result
    whose counts add up (:func:`assert_sound`). Returns which.
    """

    try:
        back = vm.read_result(path)
    except (ValueError, FileNotFoundError) as error:
        message = str(error)
        assert str(path) in message, message
        assert "\n" not in message, message
        _event(f"refused: {message.split(': ', 2)[-1][:40]}")
        return "refused"
    if _canonical(back) == _canonical(original):
        _event("read back identical")
        return "identical"
    assert not sealed, "a changed file was read back as a different result"
    assert_sound(back)
    _event("another valid result (no checksum)")
    return "sound"


def assert_sound(result: Any) -> None:
    """What every result read from a file satisfies (an oracle written apart from the reader's rules)."""

    if isinstance(result, vm.GonioResult):
        assert_sound(result.result)
        assert result.bin_counts.dtype == np.int64 and np.all(result.bin_counts >= 0)
        upper = result.bins.theta_centres < 90
        assert np.all(result.bin_counts[..., upper, :].sum(axis=(-2, -1)) <= result.result.reflected)
        assert np.all(result.bin_counts[..., ~upper, :].sum(axis=(-2, -1)) <= result.result.transmitted)
        return
    assert np.all(np.isfinite(np.atleast_1d(result.wavelengths)))
    angles = np.atleast_1d(result.coords["theta_i"])
    assert np.all((angles >= 0) & (angles <= 90))
    if isinstance(result, vm.SphereResult):
        for named in result.counts.values():
            assert all(v.dtype == np.int64 and np.all(v >= 0) for v in named.values())
            fates = sum(named[k] for k in ("detected", "absorbed_wall", "absorbed_specimen", "absorbed_other",
                                           "capped", "invalid_directions")) + sum(
                v for k, v in named.items() if k.startswith("lost_"))
            assert np.array_equal(fates, named["rays"]) and np.all(named["rays"] >= 1)
            assert np.all(named["hemispherical_reflected"] + named["hemispherical_transmitted"] <= named["rays"])
        assert np.all((result.wall_reflectance >= 0) & (result.wall_reflectance <= 1))
        return
    for counts in (result.counts, result.pilot):
        if counts is None:
            continue
        parts = [getattr(counts, n) for n in Counts.names() if n != "largest_weight"]
        assert all(p.dtype == np.int64 and p.shape == result.shape and np.all(p >= 0) for p in parts)
        assert np.all(counts.rays >= 1)
        assert np.all(counts.reflected + counts.transmitted + counts.capped + counts.invalid_directions
                      <= counts.rays)
        assert np.all(counts.specular_reflected <= counts.reflected)
        assert np.all(counts.regular_transmitted <= counts.transmitted)


# -- mutations of JSON documents (a .json file, a result_json attribute, a CSV header, a Zarr table's attribute) --


def _leaves(tree: Any, path: tuple = ()) -> list[tuple]:
    """Paths to every leaf (scalars, and every element of lists) and to every list and object."""

    out = [path]
    if isinstance(tree, dict):
        for key, value in tree.items():
            out += _leaves(value, (*path, key))
    elif isinstance(tree, list):
        for k, value in enumerate(tree):
            out += _leaves(value, (*path, k))
    return out


def _get(tree: Any, path: tuple) -> Any:
    for key in path:
        tree = tree[key]
    return tree


def _set(tree: Any, path: tuple, value: Any) -> None:
    _get(tree, path[:-1])[path[-1]] = value


def mutate_document(data: st.DataObject, doc: dict) -> dict:
    """One mutation of a JSON document, in place (and returned)."""

    paths = _leaves(doc)
    counts = [p for p in paths if p and isinstance(_get(doc, p), int) and not isinstance(_get(doc, p), bool)]
    lists = [p for p in paths if p and isinstance(_get(doc, p), list)]
    objects = [p for p in paths if isinstance(_get(doc, p), dict)]
    labels = [p for p in lists if p[-1] in ("wavelengths", "theta_i", "theta_edges", "phi_edges")
              or (len(p) > 1 and p[-2] == "parameter_coords")]
    what = data.draw(st.sampled_from(["count", "count", "count", "drop", "add", "reshape", "label", "tag", "swap"]),
                     label="mutation")
    if what == "count" and counts:
        path = data.draw(st.sampled_from(counts), label="count")
        _set(doc, path, data.draw(st.sampled_from(COUNT_CHANGES))(_get(doc, path)))
    elif what == "drop":
        parent = data.draw(st.sampled_from(objects), label="object")
        if _get(doc, parent):
            del _get(doc, parent)[data.draw(st.sampled_from(sorted(_get(doc, parent))), label="key")]
    elif what == "add":
        parent = data.draw(st.sampled_from(objects), label="object")
        _get(doc, parent)[data.draw(st.sampled_from(["extra", "rays", "absorbed", "dims"]))] = data.draw(
            st.sampled_from([1, "x", None, [1, 2], {"a": []}]))
    elif what == "reshape" and lists:
        path = data.draw(st.sampled_from(lists), label="list")
        value = _get(doc, path)
        how = data.draw(st.sampled_from(["shorter", "nested", "flat", "longer"]))
        _set(doc, path, value[:-1] if how == "shorter" else [value] if how == "nested" else
             list(np.asarray(value, dtype=object).ravel()) if how == "flat" else value + value[:1])
    elif what == "label" and labels:
        path = data.draw(st.sampled_from(labels), label="labels")
        value = list(_get(doc, path))
        how = data.draw(st.sampled_from(["reverse", "nan", "repeat", "negative", "text"]))
        if value:
            if how == "reverse":
                value = value[::-1]
            elif how == "nan":
                value[0] = math.nan
            elif how == "repeat":
                value[-1] = value[0]
            elif how == "negative":
                value[0] = -1.0
            else:
                value[0] = "550"
        _set(doc, path, value)
    elif what == "tag":
        doc["format"] = data.draw(st.sampled_from(TAGS), label="tag")
    elif what == "swap" and len(objects):
        parent = _get(doc, data.draw(st.sampled_from(objects), label="object"))
        keys = sorted(parent)
        if len(keys) >= 2:
            a, b = data.draw(st.lists(st.sampled_from(keys), min_size=2, max_size=2, unique=True), label="keys")
            parent[a], parent[b] = parent[b], parent[a]
    return doc


def _dumps(doc: Any) -> str:
    return json.dumps(doc, default=str)


# -- mutations of datasets (NetCDF, Zarr) and of CSV rows ------------------------------------------------------------


def mutate_dataset(data: st.DataObject, dataset: Any) -> Any:
    """One mutation of a dataset's variables, coordinates or attributes (a new dataset)."""

    names = sorted(map(str, dataset.data_vars))
    integers = [n for n in names if dataset[n].dtype.kind in "iu"]
    what = data.draw(st.sampled_from(["count", "count", "drop", "add", "reshape", "coordinate", "attribute", "swap"]),
                     label="dataset mutation")
    if what == "count" and integers:
        name = data.draw(st.sampled_from(integers), label="variable")
        values = dataset[name].values.astype(object)
        index = tuple(data.draw(st.integers(0, n - 1)) for n in values.shape)
        new = data.draw(st.sampled_from(COUNT_CHANGES[:7]))(values[index])
        values = values.astype(np.float64)
        values[index] = float(new) if not isinstance(new, str) else math.nan
        return dataset.assign({name: (dataset[name].dims, values)})
    if what == "drop":
        return dataset.drop_vars(data.draw(st.sampled_from(names), label="variable"))
    if what == "add":
        return dataset.assign(extra=(dataset[names[0]].dims, np.zeros(dataset[names[0]].shape)))
    if what == "reshape":
        name = data.draw(st.sampled_from(names), label="variable")
        values = dataset[name].values
        return dataset.drop_vars(name).assign({name: (("flat",), values.ravel())})
    if what == "coordinate":
        numeric = [str(c) for c in dataset.coords if dataset[c].ndim == 1 and dataset[c].dtype.kind == "f"]
        if numeric:
            name = data.draw(st.sampled_from(numeric), label="coordinate")
            values = dataset[name].values.copy()
            if data.draw(st.booleans()):
                values[0] = math.nan
            else:
                values = values[::-1]
            return dataset.assign_coords({name: (dataset[name].dims, values)})
        return dataset
    if what == "attribute":
        attrs = dict(dataset.attrs)
        key = data.draw(st.sampled_from(sorted(attrs)), label="attribute")
        if key in ("result_json", "virtspec_table"):
            attrs[key] = _dumps(mutate_document(data, json.loads(attrs[key])))
        else:
            attrs[key] = data.draw(st.sampled_from(["virtspec-mi result 2", "", 7]))
        out = dataset.copy()
        out.attrs = attrs
        return out
    if what == "swap":
        same = {}
        for n in names:
            same.setdefault((dataset[n].dims, dataset[n].dtype.kind), []).append(n)
        groups = [g for g in same.values() if len(g) >= 2]
        if groups:
            group = data.draw(st.sampled_from(groups), label="group")
            a, b = data.draw(st.lists(st.sampled_from(group), min_size=2, max_size=2, unique=True), label="pair")
            return dataset.assign({a: dataset[b], b: dataset[a]})
    return dataset


def truncate(data: st.DataObject, path: Path) -> None:
    """Cut a file (or, in a store, one of its files) short."""

    files = sorted(p for p in path.rglob("*") if p.is_file()) if path.is_dir() else [path]
    target = data.draw(st.sampled_from(files), label="file")
    size = target.stat().st_size
    target.write_bytes(target.read_bytes()[: data.draw(st.integers(0, max(size - 1, 0)), label="length")])


# -- one test per format ---------------------------------------------------------------------------------------------

NAMES = ["sweep", "reading", "gonio", "sphere"]


@pytest.mark.parametrize("name", NAMES)
@settings(max_examples=EXAMPLES[".json"], **PROFILE)
@given(data=st.data())
def test_a_mutated_json_file_is_refused_or_identical(originals, name, data):
    result, paths = originals[name]
    with scratch() as folder:
        path = Path(folder) / "mutated.json"
        dropped = False
        if data.draw(st.integers(0, 9), label="truncate?") == 0:
            shutil.copy(paths[".json"], path)
            truncate(data, path)
        else:
            doc = json.loads(paths[".json"].read_text())
            for _ in range(data.draw(st.integers(1, 2), label="mutations")):
                mutate_document(data, doc)
            if data.draw(st.booleans(), label="checksum dropped"):  # the rules alone (hand-made, older files)
                doc.pop("checksum", None)
            dropped = "checksum" not in doc
            path.write_text(_dumps(doc))
        check_outcome(path, result, sealed=not dropped)


@pytest.mark.parametrize("name", NAMES)
@settings(max_examples=EXAMPLES[".csv"], **PROFILE)
@given(data=st.data())
def test_a_mutated_csv_file_is_refused_or_identical(originals, name, data):
    import io

    import pandas as pd

    result, paths = originals[name]
    head, _, body = paths[".csv"].read_text().partition("\n")
    prefix = "# virtspec-mi result "
    with scratch() as folder:
        path = Path(folder) / "mutated.csv"
        where = data.draw(st.sampled_from(["header", "rows", "rows", "truncate"]), label="where")
        if where == "truncate":
            path.write_text(head + "\n" + body)
            truncate(data, path)
        elif where == "header":
            attrs = json.loads(head[len(prefix):])
            attrs["result_json"] = _dumps(mutate_document(data, json.loads(attrs["result_json"])))
            path.write_text(prefix + _dumps(attrs) + "\n" + body)
        else:
            frame = pd.read_csv(io.StringIO(body), keep_default_na=False, dtype=str)
            how = data.draw(st.sampled_from(["cell", "cell", "drop column", "swap columns", "drop row"]), label="how")
            column = data.draw(st.sampled_from(list(frame.columns)), label="column")
            if how == "cell":
                row = data.draw(st.integers(0, len(frame) - 1), label="row")
                frame.loc[row, column] = data.draw(st.sampled_from(["", "nan", "-1", "0.5", "abc", "1e400",
                                                                    str(frame.loc[row, column]) + "1"]))
            elif how == "drop column":
                frame = frame.drop(columns=[column])
            elif how == "swap columns":
                other = data.draw(st.sampled_from(list(frame.columns)), label="other")
                frame[[column, other]] = frame[[other, column]].to_numpy()
            else:
                frame = frame.drop(index=data.draw(st.integers(0, len(frame) - 1), label="row"))
            path.write_text(head + "\n" + frame.to_csv(index=False))
        check_outcome(path, result)


@pytest.mark.parametrize("suffix", [".nc", ".zarr"])
@pytest.mark.parametrize("name", NAMES)
@settings(max_examples=EXAMPLES[".nc"], **PROFILE)
@given(data=st.data())
def test_a_mutated_netcdf_file_or_zarr_store_is_refused_or_identical(originals, name, suffix, data):
    result, paths = originals[name]
    with scratch() as folder:
        path = mutated_dataset_file(data, paths[suffix], Path(folder) / f"mutated{suffix}")
        check_outcome(path, result)


def mutated_dataset_file(data: st.DataObject, source: Path, path: Path) -> Path:
    """A copy of the NetCDF file or Zarr store ``source`` at ``path``: truncated, or a mutation of its dataset."""

    import xarray as xr

    zarr = path.suffix == ".zarr"
    (shutil.copytree if zarr else shutil.copy)(source, path)
    if data.draw(st.integers(0, 3 if zarr else 5), label="truncate?") == 0:
        truncate(data, path)
        return path
    with (xr.open_zarr(path, consolidated=False, chunks=None) if zarr else xr.open_dataset(path)) as dataset:
        before = dataset.load()
    after = mutate_dataset(data, before)
    if zarr:
        write_changes(path, before, after)
    else:
        path.unlink()
        after.to_netcdf(path)
    return path


def write_changes(path: Path, before: Any, after: Any) -> None:
    """Make the store at ``path`` (holding ``before``) hold ``after``: only the arrays and attributes that changed."""

    import zarr

    group = zarr.open_group(str(path), mode="r+")
    for name in before.variables:
        if name not in after.variables:
            del group[str(name)]
    for name in after.variables:
        if name not in before.variables or not after[name].variable.identical(before[name].variable):
            if str(name) in group:
                del group[str(name)]
            group.create_array(str(name), data=np.asarray(after[name].values),
                               dimension_names=[str(d) for d in after[name].dims])
    if after.attrs != before.attrs:
        group.attrs.put(dict(after.attrs))


@pytest.mark.parametrize("name", NAMES)
def test_every_original_reads_back_identical(originals, name):
    result, paths = originals[name]
    for path in paths.values():
        assert check_outcome(path, result) == "identical"
