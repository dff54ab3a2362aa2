"""
The result family: :class:`ResultBase`
======================================

Every result kind (the applications' records too: :mod:`virtspec_mi.results.records`) —
the hemispherical reading (:class:`~virtspec_mi.results.readings.Result`),
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
  shapes and stores them (:meth:`ResultBase._store`); ``isel``, ``sel``, ``squeeze`` and
  ``as_grid`` are xarray's selections of that Dataset, for every kind
  (:class:`~virtspec_mi.results.labels.Labelled`, the labels every kind shares);
- **files**: one format tag per kind (``"virtspec-mi result 1"``, ``"virtspec-mi gonio 1"``,
  ``"virtspec-mi sphere 1"``: a word and a version; :mod:`virtspec_mi.results.formats`),
  carried in the JSON object (``format``) and in every dataset (attributes ``format`` and
  ``result_json``, the whole result as JSON); :meth:`ResultBase.write` /
  :meth:`ResultBase.read` through :mod:`virtspec_mi.results.io` (NetCDF, CSV, JSON, Zarr;
  atomic writes; a kind's own ``EXPORTS``, read through the result file they accompany,
  ``COMPANIONS``: :func:`holder`); every file read — and every dict given to :meth:`ResultBase.from_dict` —
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
  :func:`virtspec_mi.applications.comparison.compare` and the spectrum plots read, for every kind.

References
----------
xarray documentation, "Indexing and selecting data" (``sel``, ``isel``, ``method="nearest"``);
CF Conventions 1.11, Sect. 3 (``units``, ``long_name``).
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, ClassVar, Mapping

import numpy as np

from virtspec_mi.results.figures import Figure, chosen_figure, spectra
from virtspec_mi.results.formats import annotate, format_parts, tagged
from virtspec_mi.results.labels import NEAREST, Labelled, dims_of_coordinate
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
    "stored",
    "attribute",
    "KINDS",
    "holder",
]


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


def stored(name: str, doc: str) -> property:
    """A read-only property of a result: its stored variable ``name`` (the values of :attr:`ResultBase.data`'s)."""

    return property(lambda self: self.data.variables[name].values, doc=doc)


def attribute(name: str, doc: str, kind: Any = None) -> property:
    """A read-only property of a result: the attribute ``name`` of its Dataset (as ``kind(value)`` if given)."""

    return property(lambda self: self.data.attrs[name] if kind is None else kind(self.data.attrs[name]), doc=doc)


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


class ResultBase(Labelled):
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
    QUANTITIES: ClassVar[tuple[str, ...]] = ()
    """The quantities :meth:`spectrum` gives (the first is the default)."""
    DERIVED: ClassVar[dict[str, Variable]] = {}
    """
    What this kind derives from its counts, by name (:class:`~virtspec_mi.results.variables.Variable`):
    the variables :meth:`to_dataset` adds to the stored ones, with their units and long names.
    """
    COORDS: ClassVar[dict[str, Coordinate]] = {}
    """Labels :meth:`to_dataset` adds beside the stored ones (:class:`~virtspec_mi.results.variables.Coordinate`)."""
    FIGURES: ClassVar[dict[str, Figure]] = {"spectra": spectra()}
    """What :meth:`plot` draws, by name (:class:`~virtspec_mi.results.figures.Figure`): the first is the default."""
    SUFFIXES: ClassVar[tuple[str, ...]] = (".nc", ".csv", ".json", ".zarr")
    """The result files of this kind :meth:`write` writes and :func:`virtspec_mi.read_result` reads back."""
    EXPORTS: ClassVar[dict[str, Callable[..., Path]]] = {}
    """
    This kind's own files for other programs, by suffix: ``write(result, path, **options)`` → the path (an
    albedo table's ``.npy`` and C header, a Klems XML file); :meth:`write` writes them too.
    """
    COMPANIONS: ClassVar[dict[str, Callable[[Path], Path]]] = {}
    """
    Exports that a result file accompanies, by suffix: the path of that file (a Klems XML's ``.nc`` sidecar,
    an albedo table's ``.npy`` and its ``.json``); :func:`virtspec_mi.read_result` of the export reads it.
    """

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
        labels = {name: (dims_of_coordinate(name, coords, dims), np.asarray(values))
                  for name, values in coords.items()}
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

    def __setattr__(self, name: str, value: Any) -> None:
        raise AttributeError(f"a {self.KIND} is read-only (its {name!r} cannot be set): select or build a new one")

    def __delattr__(self, name: str) -> None:
        raise AttributeError(f"a {self.KIND} is read-only (its {name!r} cannot be deleted)")

    settings = attribute("settings", "The settings used (:class:`~virtspec_mi.settings.Settings`; its ``theta_i`` "
                                     "is the first angle).")

    @property
    def parameters(self) -> dict | None:
        """The swept specimen parameters (``names``, ``keys``, ``values``, ``points``), or ``None``."""

        return self.data.attrs.get("parameters")

    @property
    def source(self) -> dict | None:
        """The scene measured, for people (:func:`virtspec_mi.runtime.scene.scene_source`): its ``scene`` name and
        ``defines``; ``None`` when not recorded (a result made outside the API, a file written before)."""

        return self.data.attrs.get("source")

    seconds = attribute("seconds", "Time spent tracing, summed over the batches (and over interrupted and resumed "
                                   "runs).", float)
    scene = attribute("scene", "Fingerprint of the scene (``sha256:…``), or ``\"\"``.", str)
    version = attribute("version", "The virtspec-mi version that made the result.", str)

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
        """One quantity at one θi as a ``colour.SpectralDistribution`` (:mod:`virtspec_mi.colorimetry.cie`)."""

        from virtspec_mi.colorimetry.cie import spectral_distribution

        return spectral_distribution(self, quantity, theta_i)

    def colour(self, quantity: str | None = None, theta_i: float | None = None, **options: Any) -> Any:
        """
        CIE XYZ, L*a*b* and sRGB of one quantity at one θi (``illuminant=``, ``observer=``):
        with certified intervals from the rays spent where the readings allow it
        (:func:`virtspec_mi.colorimetry.certified.result_colour`).
        """

        from virtspec_mi.colorimetry.certified import result_colour

        return result_colour(self, quantity, theta_i, **options)

    def to_msds(self, theta_i: float | None = None) -> Any:
        """R, T and A at one θi as a ``colour.MultiSpectralDistributions`` (kinds that have all three)."""

        raise ValueError(f"a {self.KIND} has no reflectance, transmittance and absorptance triple: use "
                         f"to_sd(quantity) with one of {', '.join(self.QUANTITIES)}")

    # -- files ------------------------------------------------------------------------

    def write(self, path: str | os.PathLike, *, plain: bool = False, **options: Any) -> Path:
        """
        Write to ``.nc`` (NetCDF-4), ``.csv``, ``.json`` or ``.zarr`` by suffix — those of
        the kind's :attr:`SUFFIXES` — (:mod:`virtspec_mi.results.io`), or to one of the
        kind's :attr:`EXPORTS` (``options`` are the export's); ``plain=True``: a ``.csv``
        of columns and rows alone, for a spreadsheet (not read back as a result).
        """

        from virtspec_mi.results import io as results_io

        export = self.EXPORTS.get(Path(path).suffix.lower())
        if export is not None:
            return export(self, Path(path), **options)
        if options:
            raise TypeError(f"{', '.join(options)}: not an option of a {self.KIND}'s {Path(path).suffix} file")
        return results_io.write(self, path, plain=plain)

    @classmethod
    def read(cls, path: str | os.PathLike) -> Any:
        """
        A result of this kind from a file written by :meth:`write` (any kind:
        :func:`virtspec_mi.read_result`), checked by every rule of
        :mod:`virtspec_mi.results.integrity` (``ValueError`` naming the file and the field).
        """

        from virtspec_mi.results import io as results_io

        return read_file(holder(path), results_io.read, lambda content: cls.from_tagged(*tagged(content)))

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
        result._check()
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

    def _check(self) -> None:
        """Rules 2 to 4 of :mod:`virtspec_mi.results.integrity` for this result (a reading's labels, shapes, counts)."""

        check_result(self)

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


def holder(path: str | os.PathLike) -> Path:
    """
    The file that holds the result of ``path``: itself, or the result file an export
    accompanies when it is there (a kind's :attr:`ResultBase.COMPANIONS`, e.g. a Klems XML
    file's ``.nc`` sidecar); any other file of such a suffix (a scene's XML) is read as
    itself, and refused by its suffix.
    """

    path = Path(path)
    for kind in KINDS.values():
        companion = kind.COMPANIONS.get(path.suffix.lower())
        if companion is not None and companion(path).exists():
            return companion(path)
    return path


def _kind_in_words(word: str) -> str:
    """A kind for messages: ``"goniophotometer reading (GonioResult)"``; the word itself if unknown."""

    kind = KINDS.get(word)
    return word if kind is None else f"{kind.KIND} (virtspec_mi.{kind.__name__})"
