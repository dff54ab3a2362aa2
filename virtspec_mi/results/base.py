"""
The result family: :class:`ResultBase`
======================================

Every result kind — the hemispherical reading (:class:`~virtspec_mi.results.readings.Result`),
the goniophotometer reading (:class:`~virtspec_mi.instruments.goniophotometer.result.GonioResult`) and the
integrating-sphere reading (:class:`~virtspec_mi.instruments.sphere.result.SphereResult`) — is an
immutable set of exact counts over labelled dimensions (xarray conventions) with
everything else derived from them. This module holds what they share, written once:

- **one Dataset**: a result *is* an ``xarray.Dataset`` (:attr:`ResultBase.data`): its exact
  counts as integer variables over labelled dims (``wavelength``, ``theta_i``, the
  parameter dims of a sweep, then the kind's own dims, e.g. the goniophotometer's
  ``theta_o`` and ``phi_o`` bins; a coordinate that is not a dim is a 0-d scalar label),
  what it was measured with (settings, geometry, scene, provenance) in its attributes.
  Everything a kind shows is derived from it. A kind's constructor checks its labels and
  shapes and stores them (:meth:`ResultBase._store`); :meth:`ResultBase.isel`,
  :meth:`ResultBase.sel`, :meth:`ResultBase.squeeze` and :meth:`ResultBase.as_grid` are
  xarray's selections of that Dataset, for every kind;
- **files**: one format tag per kind (``"virtspec-mi result 1"``, ``"virtspec-mi gonio 1"``,
  ``"virtspec-mi sphere 1"``: a word and a version; :mod:`virtspec_mi.results.formats`),
  carried in the JSON object (``format``) and in every dataset (attributes ``format`` and
  ``result_json``, the whole result as JSON); :meth:`ResultBase.write` /
  :meth:`ResultBase.read` through :mod:`virtspec_mi.results.io` (NetCDF, CSV, JSON, Zarr;
  atomic writes); every file read — and every dict given to :meth:`ResultBase.from_dict` —
  is checked by the rules of :mod:`virtspec_mi.results.integrity` (whole counts that add
  up as the kind says, :meth:`ResultBase._count_groups`; finite labels; shapes; tags;
  the checksum of :meth:`ResultBase.sealed_json`); every variable and coordinate of
  ``to_dataset()`` has its ``units`` and ``long_name`` (:func:`virtspec_mi.results.formats.annotate`);
- **tables, not methods**: what a kind shows besides its counts is declared in rows —
  ``DERIVED`` and ``COORDS`` (:mod:`virtspec_mi.results.variables`: how each variable is
  computed, its dims, units and long name) and ``FIGURES`` (:mod:`virtspec_mi.results.figures`);
  :meth:`ResultBase.to_dataset`, :meth:`ResultBase.csv_dataset`, the counts a file is
  checked against and :meth:`ResultBase.plot` are built from them here, for every kind;
- **spectra**: :meth:`ResultBase.spectrum` — one quantity over wavelength at one θi with
  its certified tolerance (:class:`Spectrum`) — is what ``to_sd``, ``colour``,
  :func:`virtspec_mi.comparison.compare` and the spectrum plots read, for every kind.

References
----------
xarray documentation, "Indexing and selecting data" (``sel``, ``isel``, ``method="nearest"``);
CF Conventions 1.11, Sect. 3 (``units``, ``long_name``).
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path
from typing import Any, ClassVar, Mapping

import numpy as np

from virtspec_mi.results.figures import Figure, chosen_figure, spectra
from virtspec_mi.results.formats import annotate, format_parts, tagged
from virtspec_mi.results.integrity import (CountRules, check_agreement, check_checksum, check_labels, check_result,
                                           check_shapes, finite_labels, parameters_of, read_file, sealed_text,
                                           source_of, whole_counts)
from virtspec_mi.results.variables import Coordinate, Variable

__all__ = [
    "ResultBase",
    "Spectrum",
    "NEAREST",
    "plain_data",
    "round_up",
    "span",
    "per_count",
    "KINDS",
]

NEAREST: str = "nearest"
"""The one inexact ``method`` of :meth:`ResultBase.sel`: the label closest to the one asked."""

_MATCH = {"rtol": 1e-9, "atol": 1e-12}  # labels this close are the same label
_GRID = ("wavelength", "theta_i")  # the dims every reading has, in this order, first


def plain_data(values: Any) -> Any:
    """An array as JSON-ready nested lists, NaN as ``None`` (JSON has no NaN)."""

    values = np.asarray(values)
    if values.dtype.kind == "f":
        return np.where(np.isnan(values), None, values).tolist()
    return values.tolist()


def round_up(value: float, digits: int = 3) -> float:
    """``value`` rounded *up* to ``digits`` significant digits (a printed tolerance never shrinks)."""

    if not np.isfinite(value) or value <= 0:
        return value
    scale = 10.0 ** (np.floor(np.log10(value)) - digits + 1)
    return float(np.ceil(value / scale * (1 - 1e-12)) * scale)


def per_count(counts: Any, function: Any) -> np.ndarray:
    """``function(n)`` of every count n (e.g. a rule's tolerance of N rays), computed once per distinct n."""

    counts = np.asarray(counts)
    unique, inverse = np.unique(counts, return_inverse=True)
    return np.array([function(int(n)) for n in unique], dtype=np.float64)[inverse].reshape(counts.shape)


def span(counts: Any) -> str:
    """``"1,000"`` or ``"1,000 to 2,000"``: the least and the most of some counts."""

    low, high = int(np.min(counts)), int(np.max(counts))
    return f"{low:,}" if low == high else f"{low:,} to {high:,}"


# -- spectra --------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class Spectrum:
    """
    One quantity of a result over wavelength at one θi, sorted by wavelength.

    Attributes
    ----------
    quantity : str
        The result's quantity (``reflectance``, a sphere's ``reading`` …).
    measures : str
        What it estimates: ``reflectance``, ``transmittance`` or ``absorptance`` (the
        column of a measured spectrum it compares with).
    wavelengths, values : ndarray
        nm, increasing; the values.
    tolerance : ndarray
        Each value is within ``tolerance`` of what it estimates — the expected fraction
        of the model (a reading's R, T, A), the ratio of the expected detector fractions
        (a sphere's reading) — with probability ≥ 1 − ``delta``; NaN: not certified.
    delta : float
        The failure probability of each point's tolerance.
    theta_i : float
        The angle of incidence (degrees).
    """

    quantity: str
    measures: str
    wavelengths: np.ndarray
    values: np.ndarray
    tolerance: np.ndarray
    delta: float
    theta_i: float

    @property
    def name(self) -> str:
        return f"{self.quantity} theta_i={self.theta_i:g}"


# -- the base class -------------------------------------------------------------------


class ResultBase:
    """
    What every result kind shares (see the module docstring): one ``xarray.Dataset``,
    :attr:`data`, and what is derived from it. A kind sets :attr:`FORMAT` (and
    :attr:`LEGACY`, tags it still reads), :attr:`KIND`, :attr:`KIND_DIMS`,
    :attr:`QUANTITIES`, :attr:`SHAPED_BY` and its tables (:attr:`VARIABLES`,
    :attr:`DERIVED`, :attr:`COORDS`, :attr:`FIGURES`), stores its counts in its
    constructor (:meth:`_store`, :meth:`_extend`) and writes what no table can say: its
    certificate (``_quantity``, ``_count_groups``), its ``summary`` and its JSON object
    (``as_dict``, ``_from_dict``: the format its files have had since format 1).
    """

    FORMAT: ClassVar[str]
    """The format tag of this kind's files: ``"virtspec-mi <word> <version>"``."""
    VARIABLES: ClassVar[dict[str, tuple[str, str]]] = {}
    """
    ``(units, long_name)`` of this kind's own dataset variables and coordinates, beside
    those every kind shares (:data:`virtspec_mi.results.formats.VARIABLES`); none by default.
    """
    LEGACY: ClassVar[tuple[str, ...]] = ()
    """Older tags of this kind that :meth:`from_tagged` still reads."""
    KIND: ClassVar[str]
    """The kind in words, for messages (``"goniophotometer reading"``)."""
    KIND_DIMS: ClassVar[tuple[str, ...]] = ()
    """The kind's own dims, after the readings' (e.g. bins): kept whole by :meth:`isel`, with the reason."""
    KIND_DIMS_REASON: ClassVar[str] = ""
    QUANTITIES: ClassVar[tuple[str, ...]] = ()
    """The quantities :meth:`spectrum` gives (the first is the default)."""
    SHAPED_BY: ClassVar[str] = "rays"
    """The stored variable that lies along every dim of the result: its dims are :attr:`dims`."""
    DERIVED: ClassVar[dict[str, Variable]] = {}
    """
    What this kind derives from its counts, by name (:class:`~virtspec_mi.results.variables.Variable`):
    the variables :meth:`to_dataset` adds to the stored ones, with their units and long names.
    """
    COORDS: ClassVar[dict[str, Coordinate]] = {}
    """Labels :meth:`to_dataset` adds beside the stored ones (:class:`~virtspec_mi.results.variables.Coordinate`)."""
    FIGURES: ClassVar[dict[str, Figure]] = {"spectra": spectra()}
    """What :meth:`plot` draws, by name (:class:`~virtspec_mi.results.figures.Figure`): the first is the default."""

    data: Any
    """
    The result itself: an ``xarray.Dataset`` of the exact counts over the labelled dims,
    with the settings and provenance in its attributes (``settings``, ``scene``,
    ``seconds``, ``version``, ``parameters``, ``source`` and the kind's own). Read-only:
    a selection is a new result.
    """

    # -- the stored Dataset -------------------------------------------------------------

    def _store(self, dims: tuple[str, ...], coords: Mapping[str, Any],
               arrays: Mapping[str, tuple[tuple[str, ...], Any]], attrs: Mapping[str, Any],
               checked: Mapping[str, tuple[tuple[str, ...], Any]] | None = None) -> None:
        """
        Check the labels and the shapes of ``arrays`` (name → (dims, values); ``checked``:
        the same arrays as the kind names them in messages, when it stores them otherwise)
        by the rules of :mod:`virtspec_mi.results.integrity`, then store them as
        :attr:`data`. ``ValueError`` naming the coordinate or the array.
        """

        import xarray as xr

        dims = tuple(dims)
        coords = dict(coords)
        check_labels(dims, coords, attrs.get("parameters"), self.KIND_DIMS)
        check_shapes(arrays if checked is None else checked, {d: len(np.atleast_1d(coords[d])) for d in dims})
        labels = {name: (_coord_dims(name, coords, dims), np.asarray(values)) for name, values in coords.items()}
        variables = {name: (array_dims, np.asarray(values)) for name, (array_dims, values) in arrays.items()}
        object.__setattr__(self, "data", xr.Dataset(variables, coords=labels, attrs=dict(attrs)))

    def _extend(self, reading: "ResultBase", arrays: Mapping[str, tuple[tuple[str, ...], Any]],
                coords: Mapping[str, Any], attrs: Mapping[str, Any]) -> None:
        """
        Store ``reading``'s Dataset with this kind's own ``arrays`` (name → (dims, values)),
        the labels of its own dims (``coords``) and its own ``attrs``: a kind that extends
        a reading of the same rays (a goniophotometer's bins, a gloss meter's receptor).
        ``ValueError`` naming an array of the wrong shape.
        """

        sizes = {**reading.sizes, **{name: len(np.atleast_1d(values)) for name, values in coords.items()}}
        check_shapes(arrays, sizes)
        data = reading.data.assign_coords({name: (name, np.asarray(values)) for name, values in coords.items()})
        data = data.assign({name: (dims, np.asarray(values)) for name, (dims, values) in arrays.items()})
        object.__setattr__(self, "data", data.assign_attrs(dict(attrs)))

    @classmethod
    def _of(cls, data: Any) -> Any:
        """The result of this kind whose stored Dataset is ``data`` (a selection of one already checked)."""

        result = cls.__new__(cls)
        object.__setattr__(result, "data", data)
        return result

    def __setattr__(self, name: str, value: Any) -> None:
        raise AttributeError(f"a {self.KIND} is read-only (its {name!r} cannot be set): select or build a new one")

    def __delattr__(self, name: str) -> None:
        raise AttributeError(f"a {self.KIND} is read-only (its {name!r} cannot be deleted)")

    @cached_property
    def dims(self) -> tuple[str, ...]:
        """The dims of the result, in order: those of its :attr:`SHAPED_BY` variable."""

        return tuple(str(d) for d in self.data[self.SHAPED_BY].dims)

    @cached_property
    def coords(self) -> dict[str, np.ndarray]:
        """Every label by name: 1-d along its dim (or along ``point``), 0-d for a scalar label."""

        return {str(name): np.asarray(value.values) for name, value in self.data.coords.items()}

    @property
    def settings(self) -> Any:
        """The settings used (:class:`~virtspec_mi.settings.Settings`; its ``theta_i`` is the first angle)."""

        return self.data.attrs["settings"]

    @property
    def parameters(self) -> dict | None:
        """The swept specimen parameters (``names``, ``keys``, ``values``, ``points``), or ``None``."""

        return self.data.attrs.get("parameters")

    @property
    def source(self) -> dict | None:
        """The scene measured, for people (:func:`virtspec_mi.scene.scene_source`): its ``scene`` name and
        ``defines``; ``None`` when not recorded (a result made outside the API, a file written before)."""

        return self.data.attrs.get("source")

    @property
    def seconds(self) -> float:
        """Time spent tracing, summed over the batches (and over interrupted and resumed runs)."""

        return float(self.data.attrs["seconds"])

    @property
    def scene(self) -> str:
        """Fingerprint of the scene (``sha256:…``), or ``""``."""

        return str(self.data.attrs["scene"])

    @property
    def version(self) -> str:
        """The virtspec-mi version that made the result."""

        return str(self.data.attrs["version"])

    def _labelled(self) -> dict[str, tuple[tuple[str, ...], np.ndarray]]:
        """Every stored array by name: ``(its dims, values)``."""

        return {str(name): (tuple(str(d) for d in v.dims), v.values) for name, v in self.data.data_vars.items()}

    # -- what each kind declares ------------------------------------------------------

    def _quantity(self, quantity: str) -> tuple[np.ndarray, np.ndarray, float]:
        """``(values, tolerance, delta)`` of a quantity over the readings' dims (see :class:`Spectrum`)."""

        raise NotImplementedError

    def __init_subclass__(cls, **keywords: Any) -> None:
        """A class that declares its own ``FORMAT`` is a result kind: registered in :data:`KINDS` by its word."""

        super().__init_subclass__(**keywords)
        if "FORMAT" in cls.__dict__:
            word = format_parts(cls.FORMAT)[0]
            known = KINDS.get(word)
            if known is not None and known.__qualname__ != cls.__qualname__:
                raise ValueError(f"result kind {cls.__qualname__}: the format word {word!r} is {known.__qualname__}'s")
            KINDS[word] = cls

    def rendered(self) -> np.ndarray:
        """
        What ``mi.render`` returns for a result of one θi (the scene's integrator): one row
        per wavelength, the quantities :attr:`QUANTITIES` names (a reading's R, T, A), as
        ``float32``.
        """

        reading = self.squeeze()
        return np.stack([np.asarray(reading._quantity(name)[0], dtype=np.float32)
                         for name in self.RENDERED], axis=1)

    RENDERED: ClassVar[tuple[str, ...]] = ("reflectance", "transmittance", "absorptance")
    """The quantities :meth:`rendered` returns, in its columns."""

    def plot(self, path: str | os.PathLike | None = None, quantity: str | None = None, *, figure: str | None = None,
             **options: Any) -> Any:
        """
        Draw one of the kind's figures (:attr:`FIGURES`): ``figure`` by name, else the first
        that shows ``quantity`` (``None``: the kind's first figure, of its first quantity),
        saved to ``path`` (``.png``/``.svg``) when given; ``options`` are the drawing's
        (``name=``, ``theta_i=``, ``wavelength=`` …). Returns the ``matplotlib.figure.Figure``.
        """

        if quantity is not None and not any(quantity in (item.quantities or ()) for item in self.FIGURES.values()):
            quantity = self.check_quantity(quantity)
        return chosen_figure(self.FIGURES, self.KIND, figure, quantity).draw(self, path, quantity, **options)

    def drawn_note(self, quantity: str | None = None) -> str:
        """
        What :meth:`plot` of ``quantity`` leaves out, for the reader (a figure of one
        label of several: which it drew and how to draw another), or ``""``.
        """

        return ""

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

        return _coord_dims(name, self.coords, self.dims)

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

    # -- spectra ----------------------------------------------------------------------

    def spectrum(self, quantity: str | None = None, theta_i: float | None = None) -> Spectrum:
        """
        One quantity over wavelength at one θi (``None``: the only one) with its certified
        tolerance, sorted by wavelength (:class:`Spectrum`); ``quantity`` one of
        :attr:`QUANTITIES` (default the first). A result with parameter dims: select one
        point first.
        """

        quantity = self.check_quantity(quantity)
        grid = self.as_grid()
        column = grid.angle_index(theta_i)
        values, tolerance, delta = grid._quantity(quantity)
        order = np.argsort(grid.coords["wavelength"], kind="stable")
        return Spectrum(quantity, self.spectrum_measures(quantity),
                        np.asarray(grid.coords["wavelength"], dtype=np.float64)[order],
                        np.asarray(values)[order, column], np.asarray(tolerance, dtype=np.float64)[order, column],
                        float(delta), float(np.atleast_1d(grid.coords["theta_i"])[column]))

    def spectrum_measures(self, quantity: str | None = None) -> str:
        """What a quantity estimates: ``reflectance``, ``transmittance`` or ``absorptance`` (a reading's own)."""

        return self.check_quantity(quantity)

    def check_quantity(self, quantity: str | None) -> str:
        """``quantity`` if it is one of :attr:`QUANTITIES` (``None``: the first); else ``ValueError`` naming them."""

        if quantity is None:
            return self.QUANTITIES[0]
        if quantity not in self.QUANTITIES:
            raise ValueError(f"quantity must be one of {', '.join(self.QUANTITIES)} (got {quantity!r})"
                             + ("" if not self._QUANTITY_NOTE else f": {self._QUANTITY_NOTE}"))
        return quantity

    _QUANTITY_NOTE: ClassVar[str] = ""

    def to_sd(self, quantity: str | None = None, theta_i: float | None = None) -> Any:
        """One quantity at one θi as a ``colour.SpectralDistribution`` (:mod:`virtspec_mi.results.colorimetry`)."""

        from virtspec_mi.results.colorimetry import spectral_distribution

        return spectral_distribution(self, quantity, theta_i)

    def colour(self, quantity: str | None = None, theta_i: float | None = None, **options: Any) -> Any:
        """
        CIE XYZ, L*a*b* and sRGB of one quantity at one θi (``illuminant=``, ``observer=``):
        with certified intervals from the rays spent where the readings allow it
        (:func:`virtspec_mi.applications.derived.colour.result_colour`).
        """

        from virtspec_mi.applications.derived.colour import result_colour

        return result_colour(self, quantity, theta_i, **options)

    def to_msds(self, theta_i: float | None = None) -> Any:
        """R, T and A at one θi as a ``colour.MultiSpectralDistributions`` (kinds that have all three)."""

        raise ValueError(f"a {self.KIND} has no reflectance, transmittance and absorptance triple: use "
                         f"to_sd(quantity) with one of {', '.join(self.QUANTITIES)}")

    # -- files ------------------------------------------------------------------------

    def write(self, path: str | os.PathLike, *, plain: bool = False) -> Path:
        """
        Write to ``.nc`` (NetCDF-4), ``.csv``, ``.json`` or ``.zarr`` by suffix
        (:mod:`virtspec_mi.results.io`); ``plain=True``: a ``.csv`` of columns and rows
        alone, for a spreadsheet (not read back as a result).
        """

        from virtspec_mi.results import io as results_io

        return results_io.write(self, path, plain=plain)

    @classmethod
    def read(cls, path: str | os.PathLike) -> Any:
        """
        A result of this kind from a file written by :meth:`write` (any kind:
        :func:`virtspec_mi.read_result`), checked by every rule of
        :mod:`virtspec_mi.results.integrity` (``ValueError`` naming the file and the field).
        """

        from virtspec_mi.results import io as results_io

        return read_file(path, results_io.read, lambda content: cls.from_tagged(*tagged(content)))

    @classmethod
    def from_dataset(cls, dataset: Any) -> Any:
        """The result of a dataset made by ``to_dataset`` (or read from a file), checked as a file is."""

        content = ("dataset", dataset)
        result = cls.from_tagged(*tagged(content))
        check_agreement(content, result)
        return result

    @classmethod
    def from_tagged(cls, tag: str, data: Any) -> Any:
        """The result of ``data`` carrying format ``tag`` (:func:`tagged`); ``ValueError`` if it is another kind's."""

        word, version = format_parts(cls.FORMAT)
        theirs, their_version = format_parts(tag)
        if theirs != word:
            raise ValueError(f"this file holds a {_kind_in_words(theirs)} (format {tag!r}), not a {cls.KIND}: "
                             "read it with virtspec_mi.read_result, which reads every kind")
        if their_version > version:
            raise ValueError(f"this {cls.KIND} was written in format {tag!r} by a newer virtspec-mi; this version "
                             f"reads up to {cls.FORMAT!r}: upgrade virtspec-mi")
        if tag != cls.FORMAT and tag not in cls.LEGACY:
            raise ValueError(f"format {tag!r} is not read by this version (it reads {cls.FORMAT!r} and "
                             f"{', '.join(map(repr, cls.LEGACY)) or 'no older one'})")
        return cls._from_plain(tag, data)

    @classmethod
    def _from_plain(cls, tag: str, data: Any) -> Any:
        return cls.from_dict(data)

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> Any:
        """
        The result of :meth:`as_dict` (a JSON object), checked by every rule of
        :mod:`virtspec_mi.results.integrity`: ``ValueError`` naming the field that is
        missing, of the wrong type or breaks a rule.
        """

        if not isinstance(data, Mapping):
            raise ValueError(f"a {cls.KIND} is a JSON object (got {type(data).__name__})")
        if data.get("format") != cls.FORMAT:
            raise ValueError(f"'format' must be {cls.FORMAT!r} for a {cls.KIND} (got {data.get('format')!r})")
        try:
            result = cls._from_dict(data)
        except KeyError as error:
            raise ValueError(f"lacks the field {error} of a {cls.KIND}") from None
        except (TypeError, AttributeError) as error:
            raise ValueError(f"a field of the {cls.KIND} has the wrong type ({' '.join(str(error).split())})") from None
        check_result(result)
        result._check_stored(data)
        check_checksum(data)
        return result

    @classmethod
    def _from_dict(cls, data: Mapping[str, Any]) -> Any:
        """The result of ``data`` (a kind's own fields; :meth:`from_dict` checks it)."""

        raise NotImplementedError

    def _count_groups(self) -> list[tuple[str, Mapping[str, np.ndarray], CountRules, tuple[str, ...]]]:
        """Every group of counts with how it adds up and its dims (:func:`~virtspec_mi.results.integrity.check_counts`)."""

        raise NotImplementedError

    def _count_variables(self) -> dict[str, tuple[tuple[str, ...], np.ndarray]]:
        """
        The exact counts of ``to_dataset()`` by name: ``(dims, int64 values)`` — the stored
        integer variables and the derived counts (what :func:`check_agreement` compares).
        """

        stored = {name: (dims, values) for name, (dims, values) in self._labelled().items() if values.dtype.kind in "iu"}
        derived = {name: (variable.dims_of(self), np.asarray(variable.values(self), dtype=np.int64))
                   for name, variable in self.DERIVED.items() if variable.count}
        return {**stored, **derived}

    def to_dataset(self) -> Any:
        """
        An ``xarray.Dataset``: the stored one (the exact counts over the labelled dims),
        every variable of the kind's :attr:`DERIVED` table and the labels of its
        :attr:`COORDS`, each with ``units`` and ``long_name``
        (:func:`~virtspec_mi.results.formats.annotate`); attributes: the kind's own (its
        settings and provenance as numbers and text), the format tag (``format``) and the
        whole result (``result_json``, from which :meth:`from_dataset` rebuilds it).
        """

        def derived(variable: Variable) -> tuple[tuple[str, ...], np.ndarray, dict[str, Any]]:
            values = np.asarray(variable.values(self), dtype=np.int64 if variable.count else np.float64)
            return variable.dims_of(self), values, dict(variable.attrs(self)) if variable.attrs else {}

        import xarray as xr

        stored = {name: (array.dims, array.values) for name, array in self.data.variables.items()}
        variables = {name: derived(variable) for name, variable in self.DERIVED.items()}  # what is read first
        variables.update({name: stored[name] for name in self.data.data_vars})
        coords = {**{name: stored[name] for name in self.data.coords},
                  **{name: (label.dims, np.asarray(label.values(self))) for name, label in self.COORDS.items()}}
        dataset = xr.Dataset(variables, coords=coords, attrs={**self._file_attrs(), **self._dataset_attrs()})
        return annotate(dataset, self._parameter_keys(), self.described())

    def described(self) -> dict[str, tuple[str, str]]:
        """
        ``(units, long_name)`` of this kind's own variables and coordinates: its stored ones
        (:attr:`VARIABLES`), its :attr:`DERIVED` and :attr:`COORDS` (beside those every kind
        shares, :data:`virtspec_mi.results.formats.VARIABLES`).
        """

        tables = {**self.DERIVED, **self.COORDS}
        return {**self.VARIABLES, **{name: (item.units, item.long_name) for name, item in tables.items()}}

    def _file_attrs(self) -> dict[str, Any]:
        """The attributes of this kind's dataset (numbers and text, for NetCDF) beside its format and result."""

        return {}

    def _check_stored(self, data: Mapping[str, Any]) -> None:
        """Derived counts a JSON object of this kind also holds agree with the result built from it (none: nothing)."""

    def sealed_json(self) -> str:
        """
        :meth:`as_dict` as JSON with its ``checksum`` (:func:`~virtspec_mi.results.integrity.sealed_text`):
        what a ``.json`` file, a dataset's ``result_json`` and ``virtspec … --json`` hold.
        """

        return sealed_text(self.as_dict())

    def csv_dataset(self) -> Any:
        """What a ``.csv`` file holds (one row per cell of it): ``to_dataset()`` without what no row holds."""

        left = [name for name, item in {**self.DERIVED, **self.COORDS}.items() if not item.csv]
        return self.to_dataset().drop_vars(left)

    def _dataset_attrs(self) -> dict[str, Any]:
        """
        The attributes every kind's dataset carries: its format tag, the whole result as
        JSON and, when recorded, the scene's name (``scene_name``) and ``-D`` defines
        (``defines``, JSON).
        """

        source = {} if self.source is None else {"scene_name": self.source["scene"],
                                                 "defines": json.dumps(self.source["defines"])}
        return {"format": self.FORMAT, **source, "result_json": self.sealed_json()}

    @property
    def specimen_label(self) -> str:
        """
        The specimen in words for titles: the scene's name, its ``-D`` defines and the
        parameter point a selection holds (``"soybean_abmb -D thickness=2e-4,
        specimen.N = 1.5"``); ``""`` when none is known.
        """

        parts = [] if self.source is None else [" ".join(
            [self.source["scene"], *(f"-D {k}={v}" for k, v in self.source["defines"].items())])]
        point = [f"{name} = {float(self.coords[name]):g}" for name in self.parameter_names
                 if name in self.coords and np.ndim(self.coords[name]) == 0]
        return ", ".join(parts + point)

    def as_dict(self) -> dict[str, Any]:
        raise NotImplementedError

    def _labels_as_dict(self) -> dict[str, Any]:
        """
        The labels as plain data: ``dims``, ``wavelengths``, ``theta_i`` and, when recorded,
        the scene's ``source`` (what :meth:`labels_from_dict` reads).
        """

        source = {} if self.source is None else {"source": self.source}
        return {"dims": list(self.dims), "wavelengths": plain_data(self.coords["wavelength"]),
                "theta_i": plain_data(self.coords["theta_i"]), **source}

    def _parameters_as_dict(self) -> dict[str, Any]:
        """The swept parameters and their coordinates as plain data (none: nothing)."""

        if self.parameters is None:
            return {}
        return {"parameters": self.parameters,
                "parameter_coords": {name: plain_data(self.coords[name]) for name in (*self.parameter_names, "point")
                                     if name in self.coords}}

    @staticmethod
    def labels_from_dict(data: dict[str, Any]) -> dict[str, Any]:
        """``dims``, ``coords``, ``parameters`` and ``source`` (constructor keywords) from a result's plain data."""

        extra = {name: whole_counts(value, name) if name == "point" else finite_labels(value, name)
                 for name, value in (data.get("parameter_coords") or {}).items()}
        parameters = data.get("parameters")
        dims = data["dims"]
        if not isinstance(dims, (list, tuple)) or not all(isinstance(d, str) for d in dims):
            raise ValueError(f"'dims' must be a list of names (got {dims!r})")
        return {"dims": tuple(dims),
                "coords": {"wavelength": finite_labels(data["wavelengths"], "wavelengths"),
                           "theta_i": finite_labels(data["theta_i"], "theta_i"), **extra},
                "parameters": parameters_of(parameters), "source": source_of(data.get("source"))}

    def _parameter_keys(self) -> dict[str, str] | None:
        """Swept parameter names → their ``mi.traverse`` keys (for :func:`annotate`), or ``None``."""

        if self.parameters is None:
            return None
        return dict(zip(self.parameters["names"], self.parameters["keys"]))

    def _repr_html_(self) -> str:
        """Jupyter: the one-line description, then xarray's HTML view of ``to_dataset()``."""

        import html

        dataset = self.to_dataset()
        dataset.attrs.pop("result_json", None)  # the whole result as JSON: for files, not for reading
        return f"<p><code>{html.escape(repr(self))}</code></p>" + dataset._repr_html_()


KINDS: dict[str, type[ResultBase]] = {}
"""
Every result kind by the word of its format tag (``"result"``, ``"gonio"``, ``"sphere"``,
an instrument's own, e.g. ``"gloss"``): a class that declares its ``FORMAT`` registers
itself here when it is defined (:meth:`ResultBase.__init_subclass__`), so a new kind is
one class, wherever it lives (beside its instrument).
"""


def _kind_in_words(word: str) -> str:
    """A kind for messages: ``"goniophotometer reading (GonioResult)"``; the word itself if unknown."""

    kind = KINDS.get(word)
    return word if kind is None else f"{kind.KIND} (virtspec_mi.{kind.__name__})"


def _coord_dims(name: str, coords: dict[str, np.ndarray], dims: tuple[str, ...]) -> tuple[str, ...]:
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
    theta = data.coords["theta_i"].values if "theta_i" in data.coords else None
    return data.assign_attrs(settings=settings.updated(
        wavelengths=tuple(float(w) for w in np.atleast_1d(data.coords["wavelength"].values)),
        theta_i=None if theta is None else float(np.atleast_1d(theta)[0])))
