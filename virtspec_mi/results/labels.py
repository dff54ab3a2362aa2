"""
The labels of every result kind: :class:`Labelled`
==================================================

A result is one ``xarray.Dataset`` (:attr:`~virtspec_mi.results.base.ResultBase.data`)
over labelled dims — ``wavelength``, ``theta_i``, the parameter dims of a sweep, then the
kind's own (a goniophotometer's bins, a sphere's configurations). :class:`Labelled`
holds what every kind does with its labels, written once: the labels by name (``dims``,
``sizes``, ``coords``, the angles), and selection as xarray's — :meth:`Labelled.isel`,
:meth:`Labelled.sel` (exact labels, ``method="nearest"``, lists, slices of labels),
:meth:`Labelled.squeeze` and :meth:`Labelled.as_grid` — each a new result of the same
kind whose settings are restated for the readings it holds.

References
----------
xarray documentation, "Indexing and selecting data" (``sel``, ``isel``, ``method="nearest"``).
"""

from __future__ import annotations

from functools import cached_property
from typing import Any, ClassVar, Mapping

import numpy as np

__all__ = ["Labelled", "NEAREST", "dims_of_coordinate"]

NEAREST: str = "nearest"
"""The one inexact ``method`` of :meth:`Labelled.sel`: the label closest to the one asked."""

_MATCH = {"rtol": 1e-9, "atol": 1e-12}  # labels this close are the same label
_GRID = ("wavelength", "theta_i")  # the dims every reading has, in this order, first


class Labelled:
    """The labels and the selections of a result kind (see the module docstring); a kind's base."""

    data: Any
    KIND: ClassVar[str]
    KIND_DIMS: ClassVar[tuple[str, ...]] = ()
    """The kind's own dims, after the readings' (e.g. bins): kept whole by :meth:`isel`, with the reason."""
    KIND_DIMS_REASON: ClassVar[str] = ""
    SHAPED_BY: ClassVar[str] = "rays"
    """The stored variable that lies along every dim of the result: its dims are :attr:`dims`."""

    @classmethod
    def _of(cls, data: Any) -> Any:
        """The result of this kind whose stored Dataset is ``data`` (a selection of one already checked)."""

        result = cls.__new__(cls)
        object.__setattr__(result, "data", data)
        return result

    @cached_property
    def dims(self) -> tuple[str, ...]:
        """The dims of the result, in order: those of its :attr:`SHAPED_BY` variable."""

        return tuple(str(d) for d in self.data.variables[self.SHAPED_BY].dims)

    @cached_property
    def coords(self) -> dict[str, np.ndarray]:
        """Every label by name: 1-d along its dim (or along ``point``), 0-d for a scalar label."""

        return {str(name): np.asarray(self.data.variables[name].values) for name in self.data.coords}

    # -- labels -----------------------------------------------------------------------

    @property
    def wavelengths(self) -> np.ndarray:
        """Wavelengths in nm, in the order requested (a 0-d array once one is selected)."""

        return self.coords["wavelength"]

    @property
    def theta_i(self) -> Any:
        """Polar incidence in degrees: a float for a single reading, an array for a θi dim."""

        value = self.coords["theta_i"]
        return float(value) if np.ndim(value) == 0 else value

    @property
    def phi_i(self) -> float:
        """Azimuth of incidence in degrees (the settings')."""

        return float(self.settings.phi_i)

    @property
    def mu(self) -> float:
        """The tolerance asked for (the settings'; what the rays give is each kind's certificate)."""

        return float(self.settings.mu)

    @property
    def delta(self) -> float:
        """The failure probability δ asked for (the settings')."""

        return float(self.settings.delta)

    @property
    def shape(self) -> tuple[int, ...]:
        return tuple(len(self.coords[d]) for d in self.dims)

    @property
    def sizes(self) -> dict[str, int]:
        """Length of every dim, by name (as ``xarray.Dataset.sizes``)."""

        return dict(zip(self.dims, self.shape))

    @property
    def reading_dims(self) -> tuple[str, ...]:
        """The dims of the readings: :attr:`dims` without the kind's own (:attr:`KIND_DIMS`)."""

        return tuple(d for d in self.dims if d not in self.KIND_DIMS)

    @property
    def parameter_names(self) -> tuple[str, ...]:
        """Names of the swept specimen parameters (empty without parameters)."""

        return () if self.parameters is None else tuple(self.parameters["names"])

    def coord_dims(self, name: str) -> tuple[str, ...]:
        """The dims a coordinate lies along: its own, ``("point",)`` for a parameter of points, ``()`` if scalar."""

        return dims_of_coordinate(name, self.coords, self.dims)

    def angle_index(self, theta_i: float | None = None) -> int:
        """
        The index of ``theta_i`` among the result's angles (``None``: the only one);
        ``ValueError`` naming the angles otherwise.
        """

        angles = np.atleast_1d(np.asarray(self.coords["theta_i"], dtype=np.float64))
        if theta_i is None:
            if len(angles) != 1:
                raise ValueError(f"theta_i must be given for a result over several angles (one of {angles.tolist()})")
            return 0
        matches = np.flatnonzero(np.isclose(angles, float(theta_i), rtol=0, atol=1e-9))
        if not len(matches):
            raise ValueError(f"theta_i must be one of the result's angles {angles.tolist()} (got {theta_i:g})")
        return int(matches[0])

    # -- selection: written once for every kind ----------------------------------------

    def isel(self, indexers: Mapping[str, Any] | None = None, **more: Any) -> Any:
        """
        The readings at the given positions of each dim, as the same kind: an integer
        (the dim becomes a scalar coordinate), a list of integers or a slice (the dim
        stays, with those labels). ``ValueError`` naming the dim and the allowed range.
        """

        indexers = {**(indexers or {}), **more}
        keys = {}
        for dim, index in indexers.items():
            self._check_selectable(dim, self.dims)
            keys[dim] = _positions(dim, index, self.sizes[dim])
        return self._of(_restated(self.data.isel(keys)))

    def sel(self, labels: Mapping[str, Any] | None = None, method: str | None = None, **more: Any) -> Any:
        """
        The readings at the given labels of each dim, as the same kind (as ``xarray``'s
        ``sel``): a number (the dim becomes a scalar coordinate), a list of numbers, or a
        ``slice(start, stop)`` of labels (both ends included). ``method="nearest"`` takes
        the nearest label to each number asked; without it a label must match (to within
        1e-9 relative). A scalar coordinate (e.g. the θi of a single reading) may be
        given its own label (nearest: any), which selects everything. E.g.
        ``sel(theta_i=8)``, ``sel(wavelength=[450, 550], method="nearest")``,
        ``sel(wavelength=slice(400, 700))``, ``sel(**{"specimen.thickness": 2e-4})``.
        """

        labels = {**(labels or {}), **more}
        if method not in (None, NEAREST):
            raise ValueError(f"method must be None or {NEAREST!r} (got {method!r})")
        indexers = {}
        for dim, label in labels.items():
            if dim not in self.dims and dim in self.coords and not self.coord_dims(dim):
                self._scalar_label(dim, label, method)
                continue
            self._check_selectable(dim, self.dims)
            values = np.asarray(self.coords[dim], dtype=np.float64)
            if isinstance(label, slice):
                if method is not None:
                    raise ValueError(f"method={method!r} does not apply to a slice of {dim} labels")
                indexers[dim] = _label_slice(dim, values, label)
            elif np.ndim(label) == 0:
                indexers[dim] = _label_position(dim, values, label, method)
            else:
                indexers[dim] = [_label_position(dim, values, item, method) for item in np.asarray(label).ravel()]
        return self.isel(indexers)

    def squeeze(self, *dims: str) -> Any:
        """
        The same result without the given dims of length one (they become scalar
        labels); no dims given: ``theta_i`` (a one-angle grid becomes a single reading).
        """

        dims = dims or ("theta_i",)
        return self.isel({d: 0 for d in dims if d in self.dims and self.sizes[d] == 1})

    def as_grid(self) -> Any:
        """
        The same result with ``wavelength`` and ``theta_i`` as its first dims (a scalar
        label becomes a dim of one): what spectra, colours, comparisons and plots read.
        A result with parameter dims raises ``ValueError``: select one parameter point
        first (:meth:`sel`, :meth:`isel`).
        """

        extra = [d for d in self.reading_dims if d not in _GRID]
        if extra:
            name = extra[0]
            example = "isel(point=0)" if name == "point" else \
                f"sel(**{{{name!r}: {float(np.asarray(self.coords[name])[0]):g}}})"
            line = "point=0" if name == "point" else f"{name}={float(np.asarray(self.coords[name])[0]):g}"
            raise ValueError(f"this result also has the dims {', '.join(extra)} (a parameter sweep): select one "
                             f"parameter point first, e.g. result.{example} (on the command line: --sel {line})")
        result = self
        for name in _GRID:
            if name not in result.dims:
                result = result._expanded(name)
        return result

    def _expanded(self, name: str) -> Any:
        """The scalar coordinate ``name`` as a dim of one, at its place in ``(wavelength, theta_i, …)``."""

        at = sum(1 for d in _GRID[:_GRID.index(name)] if d in self.dims)
        return self._of(self.data.expand_dims(name, axis=at))

    def _check_selectable(self, dim: str, dims: tuple[str, ...]) -> None:
        if dim in self.KIND_DIMS:
            raise ValueError(f"{dim!r} is a dim a {self.KIND} keeps whole: {self.KIND_DIMS_REASON}")
        if dim not in dims:
            scalar = [f"{n} = {float(v):g}" for n, v in self.coords.items() if np.ndim(v) == 0 and n not in dims]
            raise ValueError(f"{dim!r} is not a dim of this result (dims: {', '.join(dims) or 'none'}"
                             + (f"; scalar labels: {', '.join(scalar)}" if scalar else "") + ")")

    def _scalar_label(self, name: str, label: Any, method: str | None) -> None:
        """A label given for a scalar coordinate: its own (or, nearest, any number) selects everything."""

        own = float(np.asarray(self.coords[name]))
        if isinstance(label, slice) or np.ndim(label) != 0:
            raise ValueError(f"{name} is a scalar label of this result ({name} = {own:g}): give one number")
        if method is None and not np.isclose(own, _number(name, label), **_MATCH):
            raise ValueError(f"{name} must be the result's label {own:g} (got {label!r}; method='nearest' takes it)")


def dims_of_coordinate(name: str, coords: Mapping[str, Any], dims: tuple[str, ...]) -> tuple[str, ...]:
    """The dims a coordinate lies along: its own, ``("point",)`` for a parameter of points, ``()`` if scalar."""

    if name in dims:
        return (name,)
    return ("point",) if np.ndim(coords[name]) == 1 and "point" in dims else ()


def _number(dim: str, label: Any) -> float:
    try:
        return float(label)
    except (TypeError, ValueError):
        raise ValueError(f"a label of {dim} must be a number (got {label!r})") from None


def _positions(dim: str, index: Any, size: int) -> Any:
    """An integer (or integers) in [0, size) from an ``isel`` indexer: an integer, integers or a slice."""

    def one(value: Any) -> int:
        if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)) or not -size <= value < size:
            raise ValueError(f"the index of {dim!r} must be an integer in [{-size}, {size}) (got {value!r})")
        return int(value) % size

    if isinstance(index, slice):
        positions = np.arange(size)[index]
    elif np.ndim(index) == 0:
        return one(index)
    else:
        positions = np.array([one(v) for v in list(index)], dtype=np.int64)
    if not len(positions):
        raise ValueError(f"the selection of {dim!r} holds no label (got {index!r})")
    return positions


def _label_position(dim: str, values: np.ndarray, label: Any, method: str | None) -> int:
    wanted = _number(dim, label)
    matches = np.flatnonzero(np.isclose(values, wanted, **_MATCH))
    if len(matches):
        return int(matches[0])
    if method == NEAREST:
        return int(np.argmin(np.abs(values - wanted)))
    raise ValueError(f"{dim} must be one of the result's labels {values.tolist()} (got {label!r}; "
                     "method='nearest' takes the nearest)")


def _label_slice(dim: str, values: np.ndarray, label: slice) -> np.ndarray:
    if label.step is not None:
        raise ValueError(f"a slice of {dim} labels takes no step (got {label!r})")
    ascending = bool(np.all(np.diff(values) >= 0))
    if not ascending and not np.all(np.diff(values) <= 0):
        raise ValueError(f"a slice of {dim} labels needs them sorted (got {values.tolist()}): give a list")
    low, high = (label.start, label.stop) if ascending else (label.stop, label.start)
    keep = np.ones(len(values), dtype=bool)
    if low is not None:
        keep &= values >= _number(dim, low) - np.abs(_number(dim, low)) * _MATCH["rtol"] - _MATCH["atol"]
    if high is not None:
        keep &= values <= _number(dim, high) + np.abs(_number(dim, high)) * _MATCH["rtol"] + _MATCH["atol"]
    positions = np.flatnonzero(keep)
    if not len(positions):
        raise ValueError(f"the slice {label.start!r}..{label.stop!r} of {dim} holds none of the result's labels "
                         f"{values.tolist()}")
    return positions


def _restated(data: Any) -> Any:
    """A selection's settings restated for its readings: its wavelengths, its first θi (rule of
    :func:`~virtspec_mi.results.integrity.check_settings`)."""

    settings = data.attrs.get("settings")
    if not hasattr(settings, "updated") or "wavelength" not in data.coords:
        return data
    theta = data.variables["theta_i"].values if "theta_i" in data.coords else None
    data.attrs = {**data.attrs, "settings": settings.updated(  # a dict of its own: the selection's, not the source's
        wavelengths=tuple(float(w) for w in np.atleast_1d(data.variables["wavelength"].values)),
        theta_i=None if theta is None else float(np.atleast_1d(theta)[0]))}
    return data
