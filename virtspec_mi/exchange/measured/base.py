"""
What a reader of a measured-spectra file returns, and the one set of rules that settles it
==========================================================================================

A format's reader (:class:`MeasuredFormat`) turns a file into :class:`RawSpectra`: the
numbers it holds and what its header *tells* — the quantity (reflectance or
transmittance), the scale of the values (a fraction in [0, 1] or a percentage), the
wavelength unit (nm, µm or wavenumbers in cm⁻¹), and either the ratios themselves or a
radiance (or DN) pair, target and reference, to be ratioed. :func:`settle` then applies
the same rules to every format and returns :class:`Samples` (wavelengths in nm, values
as fractions, one row per labelled sample):

- the **quantity** is the file's when it tells one; else the one the user states
  (``quantity=`` of :class:`MeasuredFile`; ``--measured-quantity``); a file that tells
  neither is refused naming that option, and a statement that contradicts the file is
  refused as a mislabelled file;
- the **scale** is the file's when it tells one (``%`` in a column name, a reflectance
  scale factor …), else the user's (``scale=``: ``fraction`` or ``percent``), else
  fractions — values above 1.5 are then refused with the hint to state ``scale="percent"``;
- the **wavelengths** are converted to nm from the unit the file tells (µm × 1000,
  cm⁻¹ → 10⁷/ν̃) and sorted; a file that tells none is taken in nm (values that all
  lie below 100 are refused as micrometres by :func:`virtspec_mi.base.checks.check_nanometres`);
- a **pair** is ratioed (target / reference) channel by channel; channels whose reference
  is not positive are left out, and the note says how many.

Every refusal is a ``ValueError`` whose message starts with the file's name (:func:`refuse`).

References
----------
ASD Inc. (2017), *ASD File Format*, version 8, revision B; Spectra Vista Corporation,
*SVC HR-1024i / HR-768i User Manual*, Appendix (the ``.sig`` file); Spectral Evolution,
*DARWin SP User Manual* (the ``.sed`` file); McDonald, R.S. and Wilks, P.A. (1988),
JCAMP-DX: A Standard Form for Exchange of Infrared Spectra in Computer Readable Form,
Applied Spectroscopy 42(1):151–162; Harris Geospatial, *ENVI Header Files* (the ``.hdr``
keywords); EcoSIS, *Spectral data submission* (one column or one row per spectrum).
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

import numpy as np

from virtspec_mi.base.checks import check_nanometres

__all__ = ["RawSpectra", "Samples", "MeasuredFormat", "MeasuredFile", "settle", "refuse", "MEASURED_QUANTITIES",
           "SCALES", "UNITS", "text_lines", "number_rows"]

MEASURED_QUANTITIES: tuple[str, ...] = ("reflectance", "transmittance")
"""What a measured file may hold (a factor of either; absorptance is derived, not measured)."""

SCALES: dict[str, float] = {"fraction": 1.0, "percent": 0.01}
"""A scale's name → the factor that makes a fraction of its values."""

UNITS: tuple[str, ...] = ("nm", "um", "cm-1")
"""Wavelength units a reader may tell: nanometres, micrometres, wavenumbers in cm⁻¹."""

_PERCENT = 1.5  # values above this, scale untold, are taken for percentages and refused


def refuse(path: str | os.PathLike, what: str) -> ValueError:
    """The one form of a reader's refusal: ``measured file NAME: WHAT``."""

    return ValueError(f"measured file {Path(path).name}: {what}")


@dataclass(frozen=True, eq=False)
class RawSpectra:
    """
    What a reader found in a file, before the rules of :func:`settle`.

    Attributes
    ----------
    wavelengths : ndarray
        (n,) in ``unit``, any order.
    labels : tuple of str
        One label per spectrum (k of them).
    values : ndarray or None
        (k, n) the ratios the file holds (in ``scale``), or ``None`` when it holds a pair.
    target, reference : ndarray or None
        (k, n) the pair to ratio (target / reference) when ``values`` is ``None``.
    quantity : str or None
        ``reflectance`` or ``transmittance`` when the file tells it, else ``None``.
    scale : str or None
        ``fraction`` or ``percent`` when the file tells it, else ``None``.
    unit : str or None
        ``nm``, ``um`` or ``cm-1`` when the file tells it, else ``None`` (taken for nm).
    told : str
        Where the file tells its quantity (a header line), for the messages.
    metadata : tuple of dict
        Per spectrum: what else the file says of it (names, times, metadata columns).
    note : str
        What the reader did (a splice correction, skipped entries), or empty.
    """

    wavelengths: np.ndarray
    labels: tuple[str, ...]
    values: np.ndarray | None = None
    target: np.ndarray | None = None
    reference: np.ndarray | None = None
    quantity: str | None = None
    scale: str | None = None
    unit: str | None = None
    told: str = ""
    metadata: tuple[dict[str, Any], ...] = ()
    note: str = ""


@dataclass(frozen=True, eq=False)
class Samples:
    """
    Measured spectra of one file, settled: every sample on the same wavelengths.

    Attributes
    ----------
    wavelengths : ndarray
        (n,) in nm, increasing.
    values : ndarray
        (k, n) fractions (NaN: the sample has no value there).
    labels : tuple of str
        The samples' labels (distinct).
    quantity : str
        ``reflectance`` or ``transmittance``.
    source : str
        The file's name.
    format : str
        The format's name (a row of :data:`virtspec_mi.exchange.measured.FORMATS`).
    metadata : tuple of dict
        Per sample, what the file says of it.
    note : str
        What was done while reading (empty: nothing).
    """

    wavelengths: np.ndarray
    values: np.ndarray
    labels: tuple[str, ...]
    quantity: str
    source: str
    format: str
    metadata: tuple[dict[str, Any], ...] = ()
    note: str = ""

    def __len__(self) -> int:
        return len(self.labels)

    def index(self, sample: str | int | None) -> int:
        """The row of ``sample`` (a label or a 0-based index; ``None``: the only one); ``ValueError`` naming them."""

        shown = ", ".join(self.labels[:8]) + (f", ... ({len(self.labels)} in all)" if len(self.labels) > 8 else "")
        if sample is None:
            if len(self.labels) == 1:
                return 0
            raise ValueError(f"measured file {self.source} holds {len(self.labels)} spectra ({shown}): choose one "
                             "with sample=LABEL or INDEX (--sample)")
        if isinstance(sample, (int, np.integer)) and not isinstance(sample, bool):
            if 0 <= int(sample) < len(self.labels):
                return int(sample)
            raise ValueError(f"sample must satisfy 0 <= sample < {len(self.labels)} in {self.source} "
                             f"(got {sample})")
        if str(sample) in self.labels:
            return self.labels.index(str(sample))
        if isinstance(sample, str) and sample.isdigit() and int(sample) < len(self.labels):
            return int(sample)
        raise ValueError(f"sample must be a label of {self.source} ({shown}) or an index (got {sample!r})")

    def spectrum(self, sample: str | int | None = None) -> tuple[np.ndarray, np.ndarray, str]:
        """(wavelengths, values, label) of one sample, its points without a value left out."""

        row = self.index(sample)
        keep = np.isfinite(self.values[row])
        return self.wavelengths[keep], self.values[row, keep], self.labels[row]


@dataclass(frozen=True)
class MeasuredFormat:
    """
    One row of the table of measured-file formats (built in, or an outside package's
    entry point of the group ``virtspec_mi.measured_formats``, whose value is such a row).

    Attributes
    ----------
    name : str
        The format's name (``asd``, ``jcamp`` …), as ``format=`` takes it.
    suffixes : tuple of str
        File-name endings it reads, lower case with the dot (``(".asd",)``).
    read : callable
        ``read(path: Path, splice: bool) -> RawSpectra``; ``ValueError`` from :func:`refuse`
        for a bad file.
    description : str
        The format in words, and the library that reads it (with its licence) or the
        published document the reader follows.
    claims : callable or None
        ``claims(path) -> bool`` when the format shares its suffix with others (a CSV
        table of many spectra): whether this file is one of its; ``None``: every file with
        one of ``suffixes``.
    splice : bool
        Whether the format has detector splices to correct (ASD).
    """

    name: str
    suffixes: tuple[str, ...]
    read: Callable[[Path, bool], RawSpectra]
    description: str
    claims: Callable[[Path], bool] | None = None
    splice: bool = False

    def reads(self, path: Path) -> bool:
        """Whether this format reads ``path`` (its suffix, and its ``claims``)."""

        if path.suffix.lower() not in self.suffixes:
            return False
        return self.claims is None or bool(self.claims(path))


@dataclass(frozen=True)
class MeasuredFile:
    """
    A measured file and how to read it: what :func:`virtspec_mi.applications.comparison.read_measured`,
    :func:`virtspec_mi.compare` and :func:`virtspec_mi.fit` take in place of a path when a
    file needs to be told something.

    Attributes
    ----------
    path : str or PathLike
        The file (for ENVI, the ``.sli`` or its ``.hdr``).
    sample : str, int or None
        The spectrum of a file of many (its label, or its 0-based index); ``None``: the
        only one (a file of many is then refused, naming them).
    quantity : str or None
        What the file holds when it does not tell (``reflectance``, ``transmittance``).
    scale : str or None
        ``fraction`` or ``percent`` when the file does not tell.
    splice : bool
        Apply ASD's detector splice correction (ASD files only; default ``False``).
    format : str or None
        The format's name when the suffix does not tell it.
    """

    path: str | os.PathLike
    sample: str | int | None = None
    quantity: str | None = None
    scale: str | None = None
    splice: bool = False
    format: str | None = None

    def __post_init__(self) -> None:
        if self.quantity is not None and self.quantity not in MEASURED_QUANTITIES:
            raise ValueError(f"measured_quantity must be one of {', '.join(MEASURED_QUANTITIES)} "
                             f"(got {self.quantity!r})")
        if self.scale is not None and self.scale not in SCALES:
            raise ValueError(f"measured_scale must be one of {', '.join(SCALES)} (got {self.scale!r})")
        if not isinstance(self.splice, (bool, np.bool_)):
            raise ValueError(f"splice must be True or False (got {self.splice!r})")


def _wavelengths_nm(path: Path, wavelengths: np.ndarray, unit: str | None) -> np.ndarray:
    if unit not in (None, *UNITS):
        raise refuse(path, f"its wavelength unit {unit!r} is none of {', '.join(UNITS)}")
    if not np.all(np.isfinite(wavelengths) & (wavelengths > 0)):
        raise refuse(path, "its wavelengths must be finite and > 0")
    if unit == "um":
        return wavelengths * 1000.0
    if unit == "cm-1":
        return 1e7 / wavelengths
    check_nanometres(wavelengths, "measured wavelengths", path.name)
    return wavelengths


def _quantity(path: Path, raw: RawSpectra, stated: str | None) -> str:
    if raw.quantity is not None and raw.quantity not in MEASURED_QUANTITIES:
        raise refuse(path, f"it holds {raw.quantity} ({raw.told}): a measured file must hold "
                           f"{' or '.join(MEASURED_QUANTITIES)}")
    if raw.quantity is not None and stated is not None and stated != raw.quantity:
        raise refuse(path, f"it holds {raw.quantity} ({raw.told}), stated measured_quantity={stated!r}: "
                           "a mislabelled file? (leave measured_quantity out, or correct the file)")
    quantity = raw.quantity or stated
    if quantity is None:
        raise refuse(path, "it does not tell whether it holds reflectance or transmittance: state it with "
                           "measured_quantity='reflectance' or 'transmittance' (--measured-quantity)")
    return quantity


def _ratios(path: Path, raw: RawSpectra, stated_scale: str | None) -> tuple[np.ndarray, str]:
    if raw.values is None:
        if raw.target is None or raw.reference is None:
            raise refuse(path, "its reader returned neither ratios nor a target/reference pair")
        target, reference = (np.asarray(a, dtype=np.float64) for a in (raw.target, raw.reference))
        if target.shape != reference.shape:
            raise refuse(path, f"its target and reference differ in shape ({target.shape}, {reference.shape})")
        dark = ~(reference > 0)
        with np.errstate(divide="ignore", invalid="ignore"):
            ratio = np.where(dark, np.nan, target / np.where(dark, 1.0, reference))
        note = "ratioed target / reference channel by channel"
        if dark.any():
            note += f"; {int(dark.sum())} channels with a reference <= 0 left out"
        return ratio, note
    values = np.asarray(raw.values, dtype=np.float64)
    if raw.scale is not None and stated_scale is not None and raw.scale != stated_scale:
        raise refuse(path, f"its values are a {raw.scale} ({raw.told or 'its header'}), stated "
                           f"measured_scale={stated_scale!r}")
    scale = raw.scale or stated_scale
    if scale is None:
        top = np.nanmax(values) if np.isfinite(values).any() else 0.0
        if top > _PERCENT:
            raise refuse(path, f"its values reach {top:g} and it does not tell their scale: percentages? state "
                               "measured_scale='percent' (--measured-scale percent)")
        scale = "fraction"
    return values * SCALES[scale], ""


def settle(path: str | os.PathLike, raw: RawSpectra, format: str, *, quantity: str | None = None,
           scale: str | None = None) -> Samples:
    """
    The :class:`Samples` of ``raw`` by the rules of the module docstring; ``quantity`` and
    ``scale`` are what the user stated (``None``: nothing).
    """

    path = Path(path)
    wavelengths = np.asarray(raw.wavelengths, dtype=np.float64).ravel()
    labels = tuple(str(label) for label in raw.labels)
    if not len(wavelengths) or not labels:
        raise refuse(path, "it holds no spectrum")
    if len(set(labels)) != len(labels):
        seen: set[str] = set()
        labels = tuple(label if label not in seen and not seen.add(label) else f"{label}#{k}"  # type: ignore[func-returns-value]
                       for k, label in enumerate(labels))
    told_quantity = _quantity(path, raw, quantity)
    values, note = _ratios(path, raw, scale)
    values = np.atleast_2d(values)
    if values.shape != (len(labels), len(wavelengths)):
        raise refuse(path, f"it holds {values.shape[0]} spectra of {values.shape[-1]} values for "
                           f"{len(labels)} labels and {len(wavelengths)} wavelengths")
    nm = _wavelengths_nm(path, wavelengths, raw.unit)
    order = np.argsort(nm, kind="stable")
    nm, values = nm[order], values[:, order]
    if np.any(np.diff(nm) <= 0):
        raise refuse(path, "its wavelengths must be distinct (a wavelength repeated)")
    values = np.where(np.isfinite(values), values, np.nan)
    notes = "; ".join(text for text in (raw.note, note) if text)
    metadata = raw.metadata if len(raw.metadata) == len(labels) else tuple({} for _ in labels)
    return Samples(wavelengths=nm, values=values, labels=labels, quantity=told_quantity, source=path.name,
                   format=format, metadata=metadata, note=notes)


_NUMBER = re.compile(r"^[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?$")


def text_lines(path: Path) -> list[str]:
    """
    The lines of an instrument's text file (Latin-1: every byte reads); ``ValueError`` from
    :func:`refuse` when it cannot be read or its last line has no line end (cut short: a
    cut inside the last number would otherwise read as another number).
    """

    try:
        text = path.read_text(encoding="latin-1")
    except OSError as error:
        raise refuse(path, f"cannot be read ({error.strerror or error})") from None
    if text and not text.endswith(("\n", "\r")):
        raise refuse(path, f"truncated: its last line has no line end ({text.splitlines()[-1][-40:]!r}); an "
                           "instrument's software ends every line")
    return text.splitlines()


def number_rows(path: Path, lines: list[tuple[int, str]], width: int | None = None) -> np.ndarray:
    """A table of numbers from (line number, text) pairs; every row as wide as the first."""

    rows = []
    for number, text in lines:
        fields = text.replace(",", " ").split() if "\t" not in text else text.split("\t")
        fields = [field.strip() for field in fields if field.strip()]
        if not fields:
            continue
        if not all(_NUMBER.match(field) for field in fields):
            raise refuse(path, f"line {number}: expected numbers (got {text.strip()!r})")
        if width is None:
            width = len(fields)
        if len(fields) != width:
            raise refuse(path, f"line {number}: {len(fields)} columns, the rows before have {width} (truncated or "
                               "damaged?)")
        rows.append([float(field) for field in fields])
    if not rows:
        raise refuse(path, "it holds no rows of data")
    return np.array(rows, dtype=np.float64)
