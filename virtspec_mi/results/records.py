"""
Results that are records: :class:`Record`
=========================================

The applications answer with results of their own — a certified target
(:class:`~virtspec_mi.applications.targets.result.DerivedResult`), a fit
(:class:`~virtspec_mi.applications.fitting.result.FitResult`), an albedo table and its
comparison with a published one (:class:`~virtspec_mi.applications.tables.table.AlbedoTable`,
:class:`~virtspec_mi.applications.tables.table.TableComparison`), Klems matrices
(:class:`~virtspec_mi.applications.klems.matrices.KlemsMeasurement`), a simulated against
a measured spectrum (:class:`~virtspec_mi.applications.comparison.Comparison`). Each is a
kind of the one result family (:class:`~virtspec_mi.results.base.ResultBase`): a format
tag registered in :data:`~virtspec_mi.results.base.KINDS` (so :func:`virtspec_mi.read_result`
reads its files), one ``xarray.Dataset`` (:attr:`Record.data`: its arrays over labelled
dims, its settings in the attributes), the tables of what it derives (``VARIABLES``,
``DERIVED``, ``COORDS``: units and long names of every variable), ``FIGURES``, the
integrity rules of its counts (``_count_groups``, :func:`check_record`), written by the
one writer (:mod:`virtspec_mi.results.io`: ``.nc`` and ``.json``; a kind's own ``EXPORTS``
such as a C header) and read back by its tag.

What a record is not is a reading: it has no wavelength × θi grid to select or spectrum
to give (those are :class:`~virtspec_mi.results.labels.Labelled`'s). Its content is a
record of fields (a frozen dataclass, built as cheaply as one: a result is built many
times in a fit); :attr:`Record.data` is built from them on first use (:meth:`Record._stored`),
and every file holds the fields as plain data (``as_dict``, the ``result_json`` of a
NetCDF file), from which ``_from_dict`` rebuilds them.

References
----------
xarray / NetCDF conventions; CF Conventions 1.11, Sect. 3 (``units``, ``long_name``).
"""

from __future__ import annotations

from functools import cached_property
from typing import Any, ClassVar, Mapping

import numpy as np

from virtspec_mi.results.base import ResultBase
from virtspec_mi.results.integrity import CountRules, agree_values, check_counts

__all__ = ["Record", "check_record", "plain_floats", "RecordedData"]


def plain_floats(values: Any) -> Any:
    """An array of floats as nested lists, non-finite values as ``None`` (JSON has neither NaN nor infinity)."""

    array = np.asarray(values, dtype=np.float64)
    if array.ndim == 0:
        return float(array) if np.isfinite(array) else None
    return [None if not np.isfinite(v) else float(v) for v in array.ravel()] if array.ndim == 1 else \
        [plain_floats(row) for row in array]


def check_record(result: "Record") -> None:
    """
    Rule 4 of :mod:`virtspec_mi.results.integrity` for a record: every group of counts it
    declares (``result._count_groups()``) adds up as the kind says; ``ValueError`` naming
    the group, the fields and the cell.
    """

    for group, counts, rules, dims in result._count_groups():
        def where(index: tuple[int, ...], dims: tuple[str, ...] = dims) -> str:
            return "cell " + ", ".join(f"{d}={i}" for d, i in zip(dims, index)) if index else "the record"

        check_counts(group, counts, rules, where)


def _plain(value: Any) -> Any:
    """A NetCDF attribute as Python's value (numpy's scalars and arrays as numbers and lists)."""

    return value.tolist() if isinstance(value, (np.ndarray, np.generic)) else value


def _same(theirs: Any, ours: Any) -> bool:
    """Whether a file's attribute is the result's: numbers by value (NaN is NaN), anything else as text."""

    theirs, ours = _plain(theirs), _plain(ours)
    numbers = (int, float)
    if isinstance(theirs, numbers) and isinstance(ours, numbers) and not isinstance(theirs, bool):
        return theirs == ours or (theirs != theirs and ours != ours)
    return str(theirs) == str(ours)


class RecordedData:
    """
    Plain data a record read from a file keeps as it was written (a target, a certified
    colour): ``as_dict()`` gives it back, its keys are attributes, ``describe()`` its
    description when it has one.
    """

    def __init__(self, data: Mapping[str, Any], description: str = "") -> None:
        self._data = dict(data)
        self._description = description

    def __getattr__(self, name: str) -> Any:
        try:
            return self.__dict__["_data"][name]
        except KeyError:
            raise AttributeError(name) from None

    def as_dict(self) -> dict[str, Any]:
        return dict(self._data)

    def describe(self) -> str:
        return self._description

    def __repr__(self) -> str:
        return f"<recorded {self._data.get('kind', 'data')}: {self._description or self._data}>"


class Record(ResultBase):
    """
    A result kind whose content is a record of fields (see the module docstring). A kind
    sets ``FORMAT``, ``KIND``, its tables and, as every kind, ``as_dict`` /
    ``_from_dict`` and ``_count_groups``; it builds its Dataset in :meth:`_stored` and
    names its NetCDF attributes in ``_file_attrs``. Its files: :attr:`SUFFIXES` (NetCDF
    and JSON) and its own :attr:`EXPORTS`.
    """

    SUFFIXES: ClassVar[tuple[str, ...]] = (".nc", ".json")
    FIGURES: ClassVar[dict[str, Any]] = {}
    QUANTITIES: ClassVar[tuple[str, ...]] = ()

    # a reading's labels and provenance are no record's: plain names that the record's own fields may take
    settings = parameters = source = None
    seconds = scene = version = None
    wavelengths = theta_i = phi_i = mu = delta = None

    @cached_property
    def data(self) -> Any:
        """The record as one ``xarray.Dataset`` (:meth:`_stored`), built on first use."""

        return self._stored()

    @cached_property
    def dims(self) -> tuple[str, ...]:
        """The dims of the record's Dataset."""

        return tuple(str(d) for d in self.data.dims)

    def _stored(self) -> Any:
        """The kind's Dataset: its arrays over labelled dims (counts as ``int64``), its settings as attributes."""

        raise NotImplementedError

    def __setattr__(self, name: str, value: Any) -> None:
        raise AttributeError(f"a {self.KIND} is read-only (its {name!r} cannot be set): build a new one")

    def _check(self) -> None:
        check_record(self)

    def _count_groups(self) -> list[tuple[str, Mapping[str, np.ndarray], CountRules, tuple[str, ...]]]:
        return []

    def _file_attrs(self) -> dict[str, Any]:
        """The NetCDF attributes: those of the record's Dataset (numbers and text)."""

        return dict(self.data.attrs)

    def _agreement(self, kind: str, content: Any) -> None:
        """
        Rule 6 of :mod:`virtspec_mi.results.integrity` for a record's NetCDF file: every
        variable, label and attribute of its Dataset that the file holds equals the one the
        result it holds gives (an edited value is refused, not shown as the result's).
        """

        if kind != "dataset":
            return
        shown = self.data
        for name, variable in shown.variables.items():
            if name in content.variables:
                theirs = content[name]
                if theirs.shape != variable.shape:
                    raise ValueError(f"variable {name!r} has shape {theirs.shape}; the result the file holds gives "
                                     f"{variable.shape}")
                agree_values(str(name), theirs.values, variable.values)
        for name, value in shown.attrs.items():
            if name in content.attrs and not _same(content.attrs[name], value):
                theirs = _plain(content.attrs[name])
                raise ValueError(f"the attribute {name!r} holds {str(theirs)[:60]!r} where the result the file holds "
                                 f"gives {str(_plain(value))[:60]!r} (the file was changed after it was written)")

    def _dataset_attrs(self) -> dict[str, Any]:
        return {"format": self.FORMAT, "result_json": self.sealed_json()}

    def spectrum(self, quantity: str | None = None, theta_i: float | None = None) -> Any:
        raise ValueError(f"a {self.KIND} is no reading: it has no spectrum of its own")

    def plot(self, path: Any = None, quantity: str | None = None, *, figure: str | None = None, **options: Any) -> Any:
        if not self.FIGURES:
            raise ValueError(f"a {self.KIND} draws no figure")
        return super().plot(path, quantity, figure=figure, **options)

    def _repr_html_(self) -> str:
        import html

        dataset = self.to_dataset()
        dataset.attrs.pop("result_json", None)
        return f"<p><code>{html.escape(repr(self))}</code></p>" + dataset._repr_html_()

    def __repr__(self) -> str:
        return f"<virtspec_mi {type(self).__name__}>"

    @classmethod
    def _from_plain(cls, tag: str, data: Any) -> Any:
        """A JSON object (:meth:`from_dict`), or a NetCDF dataset written before the result family (:meth:`_from_legacy`)."""

        if isinstance(data, dict):  # (a Dataset is a Mapping too)
            return cls.from_dict(data)
        result = cls._from_legacy(data)
        result._check()
        return result

    @classmethod
    def _from_legacy(cls, dataset: Any) -> Any:
        """The record of a NetCDF file its kind wrote before the result family (no ``result_json``)."""

        raise ValueError(f"a {cls.KIND}'s NetCDF file holds its result as JSON (result_json); this one does not")
