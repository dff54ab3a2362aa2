"""
Specimen parameters of a sweep: names, grids and points, applied through ``mi.traverse``
=========================================================================================

A parameter sweep varies the specimen's own parameters (a leaf's pigments and thickness,
a slab's μa, μs, g, a rough surface's α) besides wavelength and θi. This module names
them, lays their values out and sets them on a loaded scene.

Names
-----
A parameter is named by its ``mi.traverse`` key under the specimen's BSDF, which Mitsuba
writes ``specimen.bsdf.NAME`` (``specimen.bsdf.alpha.value`` for a texture's value),
or by the short form ``specimen.NAME`` (``specimen.thickness``, ``specimen.alpha``):
``specimen.`` + the rest of the key, without ``bsdf.`` and a final ``.value``. Both
resolve to the same key; the result labels its dimension with the name as given. Every
number the specimen's BSDF shows to ``mi.traverse`` can be swept: the project's plugins
(``abm_b``/``abm_u``: ``thickness``, ``mesophyll_fraction``, the six concentrations and
the aspect ratios; ``turbid_slab``: ``mu_a``, ``mu_s``, ``g``, the three indices given as
numbers and ``thickness``; ``simple_dielectric``: ``eta``) and Mitsuba's built-ins
(``roughconductor``'s ``alpha``, ``diffuse``'s ``reflectance`` …). A name that resolves
to nothing raises ``ValueError`` listing the known names (with a did-you-mean); a value
out of the plugin's range raises the plugin's own ``ValueError`` — checked for every
value before any ray is traced. Non-numeric choices (a leaf's ``side``, ``lookup``) are
not parameters: they change the kernel; load another scene (or use ``-D``) instead.

Layout
------
A **grid** (:attr:`ParameterSpace.points` false) is the outer product of each
parameter's values, in the order given: one result dimension per parameter. **Points**
are explicit parameter combinations (e.g. Latin-hypercube samples): equal-length lists,
one dimension ``point`` with each parameter as a coordinate along it. Either way point
p (the flat C-order index of the grid, or the list index) owns the readings
p·n_λ·n_θ … (p + 1)·n_λ·n_θ − 1 of the sweep (:mod:`virtspec_mi.engine.readings`).

Mitsuba built-ins are not range-checked by Mitsuba on update: their values are set as
given (a negative α is the user's to avoid).

References
----------
Mitsuba 3 ``mi.traverse`` / ``SceneParameters``; Baranoski et al. (2001), Sect. 5.
"""

from __future__ import annotations

import difflib
from dataclasses import dataclass
from typing import Any, Mapping, Sequence

import numpy as np

from virtspec_mi.base.checks import parse_values

__all__ = ["PREFIX", "ParameterSpace", "known_parameters", "short_name", "parameter_space", "apply_point",
           "current_values"]

PREFIX: str = "specimen.bsdf."
"""``mi.traverse`` prefix of the specimen BSDF's parameters."""

_SHORT = "specimen."


@dataclass(frozen=True)
class ParameterSpace:
    """
    The parameter values of a sweep (see the module docstring).

    Attributes
    ----------
    names : tuple of str
        The names as given: the result's dimensions (grid) or its coordinates along ``point``.
    keys : tuple of str
        The ``mi.traverse`` key of each name.
    values : tuple of ndarray
        A grid: each parameter's values; points: each parameter's value per point (one length).
    points : bool
        Explicit points rather than a grid.
    """

    names: tuple[str, ...]
    keys: tuple[str, ...]
    values: tuple[np.ndarray, ...]
    points: bool = False

    @property
    def dims(self) -> tuple[str, ...]:
        """The result dimensions the parameters add: their names, or ``("point",)``."""

        return ("point",) if self.points else self.names

    @property
    def shape(self) -> tuple[int, ...]:
        return (len(self.values[0]),) if self.points else tuple(len(v) for v in self.values)

    @property
    def size(self) -> int:
        """Number of parameter points (of the grid, or of the list)."""

        return int(np.prod(self.shape, dtype=np.int64))

    def point(self, index: int) -> tuple[float, ...]:
        """The value of every parameter (in :attr:`names` order) at flat point ``index``."""

        if self.points:
            return tuple(float(v[index]) for v in self.values)
        at = np.unravel_index(int(index), self.shape)
        return tuple(float(v[i]) for v, i in zip(self.values, at))

    def coords(self) -> dict[str, np.ndarray]:
        """Coordinates for a result: one per name (along its own dim, or along ``point``), and ``point``."""

        coords = {name: np.asarray(v, dtype=np.float64) for name, v in zip(self.names, self.values)}
        if self.points:
            coords["point"] = np.arange(len(self.values[0]), dtype=np.int64)
        return coords

    def as_dict(self) -> dict[str, Any]:
        """Plain data (JSON) of the space: what a checkpoint and a result file record."""

        return {"names": list(self.names), "keys": list(self.keys), "points": self.points,
                "values": [np.asarray(v, dtype=np.float64).tolist() for v in self.values]}

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> "ParameterSpace":
        return cls(tuple(data["names"]), tuple(data["keys"]),
                   tuple(np.asarray(v, dtype=np.float64) for v in data["values"]), bool(data["points"]))


def known_parameters(scene: Any) -> dict[str, str]:
    """The sweepable parameters of a loaded scene's specimen: short name → ``mi.traverse`` key."""

    import mitsuba as mi

    params = mi.traverse(scene)
    known = {}
    for key in params.keys():
        if key.startswith(PREFIX) and _is_number(params[key]):
            known[short_name(key)] = key
    return known


def short_name(key: str) -> str:
    """``specimen.bsdf.alpha.value`` → ``specimen.alpha`` (the short form of a key)."""

    rest = key[len(PREFIX):] if key.startswith(PREFIX) else key
    if rest.endswith(".value"):
        rest = rest[: -len(".value")]
    return _SHORT + rest


def _is_number(value: Any) -> bool:
    """A width-1 real value (a Dr.Jit scalar array or a Python number)."""

    import drjit as dr

    if isinstance(value, bool):
        return False
    if isinstance(value, (int, float)):
        return True
    try:
        return dr.is_array_v(value) and dr.depth_v(value) == 1 and dr.width(value) == 1 and \
            dr.type_v(value) in (dr.VarType.Float32, dr.VarType.Float64)
    except (TypeError, AttributeError):
        return False


def _resolve(name: Any, known: dict[str, str]) -> str:
    """The ``mi.traverse`` key of ``name`` (short or full), else ``ValueError`` listing the known names."""

    if not isinstance(name, str):
        raise ValueError(f"parameter names must be strings such as 'specimen.thickness' (got {name!r})")
    if name in known:
        return known[name]
    keys = set(known.values())
    for key in (name, name + ".value"):
        if key in keys:
            return key
    listed = ", ".join(sorted(known)) or "none (the specimen's BSDF exposes no numeric parameter)"
    close = difflib.get_close_matches(name, [*known, *keys], n=1, cutoff=0.6)
    hint = f"; did you mean {close[0]!r}?" if close else ""
    raise ValueError(f"parameter {name!r} is not a parameter of the specimen (known: {listed}){hint}")


def parameter_space(bench: Any, parameters: Mapping[str, Any], points: bool = False) -> ParameterSpace | None:
    """
    The :class:`ParameterSpace` of ``parameters`` (name → values: a number, a sequence or a
    string of numbers and ``start:stop:step`` ranges, stop included within rounding) on
    the bench's scene, every value checked by the specimen before any tracing;
    ``None`` for no parameters. A grid needs distinct values per parameter; points need
    equal-length lists.
    """

    if parameters is None or len(parameters) == 0:
        return None
    if not isinstance(parameters, Mapping):
        raise ValueError(f"parameters must be a dict of name -> values (got {type(parameters).__name__})")
    known = known_parameters(bench.scene)
    keys = [_resolve(name, known) for name in parameters]
    for key in set(keys):
        same = [name for name, k in zip(parameters, keys) if k == key]
        if len(same) > 1:
            raise ValueError(f"parameters {' and '.join(map(repr, same))} name the same parameter {key!r}")
    values = tuple(np.asarray(parse_values(name, value), dtype=np.float64) for name, value in parameters.items())
    names = tuple(parameters)
    if points:
        lengths = {len(v) for v in values}
        if len(lengths) != 1:
            raise ValueError("parameter points need one value per point for every parameter (got lists of "
                             + ", ".join(f"{name}: {len(v)}" for name, v in zip(names, values)) + ")")
    else:
        for name, v in zip(names, values):
            if len(np.unique(v)) != len(v):
                raise ValueError(f"the values of parameter {name!r} in a grid must be distinct (got repeated values)")
    space = ParameterSpace(names, tuple(keys), values, bool(points))
    _check_values(bench, space)
    return space


def _check_values(bench: Any, space: ParameterSpace) -> None:
    """Let the specimen check every value (grid: each value of each parameter; points: each point), then restore."""

    original = current_values(bench, space.keys)
    try:
        if space.points:
            for index in range(space.size):
                apply_point(bench, space.keys, space.point(index))
        else:
            for key, values in zip(space.keys, space.values):
                for value in values:
                    apply_point(bench, (key,), (float(value),))
                apply_point(bench, (key,), (original[space.keys.index(key)],))
    finally:
        apply_point(bench, space.keys, original)


def current_values(bench: Any, keys: Sequence[str]) -> tuple[float, ...]:
    """The values the scene's parameters ``keys`` hold now."""

    import mitsuba as mi

    params = mi.traverse(bench.scene)
    return tuple(_as_float(params[key]) for key in keys)


def _as_float(value: Any) -> float:
    return float(value) if isinstance(value, (int, float)) else float(value[0])


def apply_point(bench: Any, keys: Sequence[str], values: Sequence[float]) -> None:
    """
    Set the scene's parameters ``keys`` to ``values`` and let the nodes update
    (``SceneParameters.update``: the plugins' ``parameters_changed``, which range-check
    them). The values become data, not code: Dr.Jit reuses the compiled kernel.
    """

    import mitsuba as mi

    params = mi.traverse(bench.scene)
    for key, value in zip(keys, values):
        current = params[key]
        params[key] = value if isinstance(current, (int, float)) else type(current)(float(value))
    params.update()
