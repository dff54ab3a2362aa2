"""
Simulated against measured spectra: :func:`compare`
===================================================

The paper's first application: a virtual measurement of a material model set against
a real measurement of the material. :func:`compare` takes a result of any kind (or a
result file) and a measured spectrum and reports, over their common wavelengths:

- the residuals (simulated − measured), their RMSE, mean and largest absolute value;
- how many points lie within the **combined tolerance**: the result's
  certified tolerance μ' (each simulated point is within μ' of the model's true value
  with probability ≥ 1 − δ: a reading's ``certified_mu``; for a sphere reading the
  half-width covering its certified interval) plus the measurement's own uncertainty
  when known. If
  the model is the measured material, each point is within its tolerance with
  probability ≥ 1 − δ (less the measurement's own risk); a share well below that
  flags a model that differs from the measured material;
- ΔE2000 between the colours of both spectra under an illuminant (CIE D65 by
  default), through :func:`virtspec_mi.colorimetry.cie.colorimetry` on the common
  wavelengths (refused, with the reason, when they cover too little of the
  colour-matching weight, e.g. a sparse spectrum).

What is compared is one quantity of the result over wavelength at one θi
(:meth:`~virtspec_mi.results.base.ResultBase.spectrum`): a hemispherical reading's or a
goniophotometer reading's reflectance, transmittance or absorptance; a sphere reading's
``reading`` (default), ``corrected`` or ``hemispherical`` value, against a measured
spectrum of what it measures (its reflectance or transmittance column). A result with
parameter dims is compared at one parameter point (select it first:
:meth:`~virtspec_mi.results.labels.Labelled.sel`).

The measured spectrum is linearly interpolated onto the result's wavelengths inside
the measured range only; result wavelengths outside it are left out (and listed),
never extrapolated. :func:`read_measured` reads it from

- a colour-science CSV spectral file (a header ``wavelength,<name>,…``; the column
  named after the quantity, e.g. ``reflectance``, else the only one);
- a plain CSV (or whitespace-separated ``.txt``) of ``wavelength,value`` rows, with an
  optional third column of per-point measurement uncertainty (with a header, an
  uncertainty column is named ``uncertainty`` or ``<quantity>_uncertainty``);
- a NetCDF (xarray) file with a variable named after the quantity (or its only
  variable) over one wavelength dimension, and optionally ``<quantity>_uncertainty``;
- a virtspec-mi result file of any kind (another simulation: its certified tolerance
  is the uncertainty).

Wavelengths are in nm (values below 100 are refused with the hint "micrometres? multiply by
1000") and values fractions in [0, 1] (percentages are refused with a hint). A measured
value outside [0, 1] by more than its own measurement uncertainty (none given: at all) is
refused, naming the file, the column and the wavelength: a reflectance below 0 or above 1
is no reflectance, and compared as one it would count against (or for) the model.

References
----------
Baranoski et al. (2001), Sect. 5 (comparisons with measured data), eq. (23);
CIE 142-2001 / CIE 015:2018 (CIEDE2000); colour-science ``colour.delta_E``.
"""

from __future__ import annotations

import math
import re
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any, ClassVar

import numpy as np

from virtspec_mi.base.checks import NANOMETRE_FLOOR, check_nanometres, number
from virtspec_mi.kernel.counts import QUANTITIES
from virtspec_mi.results.base import ResultBase
from virtspec_mi.colorimetry.cie import DEFAULT_ILLUMINANT, DEFAULT_OBSERVER, Colour, colorimetry
from virtspec_mi.applications.base import Application
from virtspec_mi.applications.comparison.result import Comparison, _range

__all__ = ["MeasuredSpectrum", "Comparison", "read_measured", "compare", "MEASURED_SUFFIXES",
           "ComparisonApplication"]

MEASURED_SUFFIXES: tuple[str, ...] = (".csv", ".txt", ".nc", ".json")
"""Files :func:`read_measured` reads (``.json``: a virtspec-mi result file)."""

_PERCENT = 1.5  # measured values above this are taken for percentages
_MATCH_NM = 1e-6  # wavelengths closer than this are the same


@dataclass(frozen=True, eq=False)
class MeasuredSpectrum:
    """
    A measured spectrum, sorted by wavelength.

    Attributes
    ----------
    wavelengths : ndarray
        Distinct wavelengths in nm, increasing.
    values : ndarray
        The measured quantity (a fraction) at each wavelength.
    uncertainty : ndarray or None
        Per-point measurement uncertainty (same unit), ``None`` when not known.
    quantity : str
        What was measured (``reflectance``, ``transmittance`` or ``absorptance``).
    source : str
        Where it came from (a file name, a spectrum's name).
    note : str
        Empty, or what was done while reading (points without a value skipped).
    """

    wavelengths: np.ndarray
    values: np.ndarray
    uncertainty: np.ndarray | None
    quantity: str
    source: str
    note: str = ""

    @classmethod
    def of(cls, wavelengths: Any, values: Any, uncertainty: Any = None, *, quantity: str = "reflectance",
           source: str = "measured", note: str = "", column: str = "", fractions: bool = True) -> "MeasuredSpectrum":
        """
        A checked spectrum from arrays (any order; sorted here); ``ValueError`` naming the
        problem — and, for a value a fraction cannot take (``fractions``: a measured
        reflectance, transmittance or absorptance lies in [0, 1], up to its own
        measurement uncertainty), the ``source``, the ``column`` and the wavelength.
        """

        wavelengths = np.asarray(wavelengths, dtype=np.float64).ravel()
        values = np.asarray(values, dtype=np.float64).ravel()
        if len(wavelengths) != len(values):
            raise ValueError(f"measured wavelengths and values must have one length "
                             f"(got {len(wavelengths)} and {len(values)})")
        if not len(wavelengths):
            raise ValueError(f"measured spectrum {source} holds no points")
        if not np.all(np.isfinite(wavelengths) & (wavelengths > 0)):
            raise ValueError(f"measured wavelengths must be finite and > 0 nm ({source})")
        check_nanometres(wavelengths, "measured wavelengths", source)
        if not np.all(np.isfinite(values)):
            raise ValueError(f"measured values must be finite ({source})")
        if fractions and values.max() > _PERCENT:
            raise ValueError(f"measured values must be fractions in [0, 1] (got up to {values.max():g} in {source}: "
                             "percentages? divide by 100)")
        order = np.argsort(wavelengths, kind="stable")
        wavelengths, values = wavelengths[order], values[order]
        if np.any(np.diff(wavelengths) < _MATCH_NM):
            raise ValueError(f"measured wavelengths must be distinct (repeated in {source})")
        if uncertainty is not None:
            uncertainty = _check_uncertainty(uncertainty, len(order), source)[order]
        if fractions:
            _check_fractions(wavelengths, values, uncertainty, quantity, source, column)
        return cls(wavelengths, values, uncertainty, quantity, source, note)

    def with_uncertainty(self, uncertainty: Any) -> "MeasuredSpectrum":
        """The same spectrum with ``uncertainty`` (a number, or one per point) in place of its own."""

        values = _check_uncertainty(uncertainty, len(self.wavelengths), self.source)
        return MeasuredSpectrum(self.wavelengths, self.values, values, self.quantity, self.source, self.note)


def _check_fractions(wavelengths: np.ndarray, values: np.ndarray, uncertainty: np.ndarray | None, quantity: str,
                     source: str, column: str) -> None:
    """
    A measured fraction lies in [0, 1] up to its own uncertainty (none given: exactly);
    ``ValueError`` naming the source, the column and the first wavelength beyond.
    """

    slack = np.zeros_like(values) if uncertainty is None else uncertainty
    for bad, side in ((values < -slack, "below 0"), (values > 1 + slack, "above 1")):
        if np.any(bad):
            k = int(np.flatnonzero(bad)[0])
            where = f"{source}, column {column!r}" if column else source
            allowed = "" if uncertainty is None else f" by more than its uncertainty {uncertainty[k]:g}"
            raise ValueError(
                f"measured {quantity} must lie in [0, 1] ({where}: {values[k]:g} at {wavelengths[k]:g} nm is {side}"
                f"{allowed}; {int(bad.sum())} such point{'s' if bad.sum() > 1 else ''}): a {quantity} is a fraction — "
                "give the measurement's uncertainty if these are measurement noise, or correct the data")


def _check_uncertainty(uncertainty: Any, size: int, source: str) -> np.ndarray:
    refusal = f"measurement_uncertainty must be a number or one value per measured point (got {uncertainty!r})"
    if isinstance(uncertainty, (bool, np.bool_, str)):
        raise ValueError(refusal)
    try:
        values = np.asarray(uncertainty, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError(refusal) from None
    if values.ndim == 0:
        values = np.full(size, float(values))
    if values.shape != (size,):
        raise ValueError(f"measurement_uncertainty must be a number or one value per measured point "
                         f"({size} in {source}; got shape {values.shape})")
    if not np.all(np.isfinite(values) & (values >= 0)):
        raise ValueError(f"measurement_uncertainty must be finite and >= 0 ({source})")
    return values


# -- reading measured spectra --------------------------------------------------------


def read_measured(source: Any, quantity: str = "reflectance", theta_i: float | None = None) -> MeasuredSpectrum:
    """
    A measured spectrum of ``quantity`` from a file (see the module docstring for the
    formats), a ``colour.SpectralDistribution``, a ``(wavelengths, values[, uncertainty])``
    tuple, a :class:`MeasuredSpectrum` or a result of any kind (at ``theta_i``; its
    certified tolerance becomes the uncertainty).
    """

    check_quantity(quantity)
    if isinstance(source, MeasuredSpectrum):
        return source
    if isinstance(source, ResultBase) and source.QUANTITIES:
        return _from_result(source, quantity, theta_i, "result")
    if isinstance(source, (str, os.PathLike)):
        return _read_file(Path(source), quantity, theta_i)
    if hasattr(source, "wavelengths") and hasattr(source, "values"):  # colour.SpectralDistribution
        name = str(getattr(source, "name", "") or "measured")
        return MeasuredSpectrum.of(source.wavelengths, source.values, quantity=quantity, source=name)
    if isinstance(source, (tuple, list)) and len(source) in (2, 3):
        return MeasuredSpectrum.of(*source, quantity=quantity)
    raise ValueError("measured must be a file path, a colour.SpectralDistribution, a (wavelengths, values"
                     f"[, uncertainty]) tuple or a result (got {type(source).__name__})")


def _read_file(path: Path, quantity: str, theta_i: float | None) -> MeasuredSpectrum:
    suffix = path.suffix.lower()
    if suffix not in MEASURED_SUFFIXES:
        raise ValueError(f"measured must end in one of {', '.join(MEASURED_SUFFIXES)} (got {path.name!r})")
    if not path.is_file():
        raise ValueError(f"measured file not found: {path}")
    if suffix == ".json" or (suffix == ".csv" and _is_result_csv(path)):
        from virtspec_mi.runtime.reading import read_result

        return _from_result(read_result(path), quantity, theta_i, path.name)
    if suffix == ".nc":
        return _read_netcdf(path, quantity, theta_i)
    return _read_table(path, quantity)


def _is_result_csv(path: Path) -> bool:
    from virtspec_mi.results.io import is_result_csv

    return is_result_csv(path)


def _from_result(result: ResultBase, quantity: str, theta_i: float | None, source: str) -> MeasuredSpectrum:
    """The spectrum of another result of what ``quantity`` names (its first quantity that measures it)."""

    mine = [q for q in result.QUANTITIES if result.spectrum_measures(q) == quantity]
    if not mine:
        raise ValueError(f"measured result {source} holds no {quantity} (a {result.KIND} of "
                         f"{result.spectrum_measures(result.QUANTITIES[0])})")
    spectrum = result.spectrum(mine[0], theta_i)
    if np.any(np.isnan(spectrum.tolerance)):
        raise ValueError(f"measured result {source} is not certified (NaN certified_mu): no uncertainty to use")
    return MeasuredSpectrum.of(spectrum.wavelengths, spectrum.values, spectrum.tolerance, quantity=quantity,
                               source=source, fractions=False)  # a reading (a sphere's ratio may pass 1): its rules


_DECIMAL_COMMA = re.compile(r"[-+]?\d*,\d+(?:[eE][-+]?\d+)?")


def _split(line: str) -> list[str]:
    """
    A row's fields: separated by ``;`` or a tab where the row has one (then a decimal comma,
    ``0,52``, is read as the number it writes: the CSV of a spreadsheet in many locales),
    else by ``,``, else by white space.
    """

    separator = ";" if ";" in line else "\t" if "\t" in line else "," if "," in line else None
    fields = [field.strip().strip('"').strip("'") for field in line.split(separator)]
    if separator in (";", "\t"):
        fields = [field.replace(",", ".") if _DECIMAL_COMMA.fullmatch(field) else field for field in fields]
    return fields


def _check_rows(path: Path, lines: list[int], texts: list[list[str]], table: np.ndarray, header: bool) -> None:
    """
    Refuse rows read as something else: numbers written with decimal commas in a comma-separated file (``400,0,52``:
    three fields, none with a point, the second 0 or 1), and a first row of numbers that is a header (its
    wavelength not in nm like the others').
    """

    if not header and all("." not in field for row in texts for field in row) \
            and all(len(row) == 3 and row[1] in ("0", "1") for row in texts):
        raise ValueError(f"measured file {path.name}: its numbers look written with decimal commas in a comma-"
                         f"separated file (line {lines[0]}: {','.join(texts[0])!r}); separate the columns with ';' "
                         "or write decimal points")
    wavelengths = table[:, 0]
    if len(wavelengths) > 1 and wavelengths.max() >= NANOMETRE_FLOOR:
        stray = np.nonzero(wavelengths < NANOMETRE_FLOOR)[0]
        if stray.size:
            k = int(stray[0])
            raise ValueError(f"measured file {path.name}, line {lines[k]}: {','.join(texts[k])!r} is not a row of "
                             f"a wavelength in nm like the others (a header row of numbers?); name the columns "
                             "(wavelength,reflectance) or comment the line out with #")


def _numbers(fields: list[str]) -> list[float] | None:
    try:
        return [float(field) if field else math.nan for field in fields]
    except ValueError:
        return None


def _read_table(path: Path, quantity: str) -> MeasuredSpectrum:
    """A colour-science CSV spectral file, or plain ``wavelength,value[,uncertainty]`` rows."""

    header: list[str] | None = None
    rows: list[list[float]] = []
    lines: list[int] = []
    texts: list[list[str]] = []
    for number, line in enumerate(path.read_text().splitlines(), 1):
        line = line.strip()
        if not line or line.startswith("#"):
            continue
        fields = _split(line)
        values = _numbers(fields)
        if values is None and header is None and not rows:
            header = [field.lower() for field in fields]
            continue
        if values is None:
            raise ValueError(f"measured file {path.name}, line {number}: expected numbers (got {line!r})")
        rows.append(values)
        lines.append(number)
        texts.append(fields)
    width = len(header) if header is not None else (len(rows[0]) if rows else 0)
    if not rows:
        raise ValueError(f"measured file {path.name} holds no rows of numbers")
    if any(len(row) != width for row in rows):
        raise ValueError(f"measured file {path.name}: every row must have {width} columns")
    table = np.array(rows, dtype=np.float64)
    _check_rows(path, lines, texts, table, header is not None)
    value, uncertainty = _columns(header, width, quantity, path.name)
    keep = ~np.isnan(table[:, value])
    note = "" if keep.all() else f"{int((~keep).sum())} rows without a {quantity} value skipped"
    return MeasuredSpectrum.of(table[keep, 0], table[keep, value],
                               None if uncertainty is None else table[keep, uncertainty],
                               quantity=quantity, source=path.name, note=note,
                               column=header[value] if header is not None else f"column {value + 1}")


def _columns(header: list[str] | None, width: int, quantity: str, name: str) -> tuple[int, int | None]:
    """Indices of the value column and of the uncertainty column (or ``None``)."""

    if header is None:
        if width not in (2, 3):
            raise ValueError(f"measured file {name}: plain rows must be wavelength,value[,uncertainty] "
                             f"(got {width} columns; give a header naming them)")
        return 1, 2 if width == 3 else None
    named = {field: k for k, field in enumerate(header) if k}
    uncertainty = named.get(f"{quantity}_uncertainty", named.get("uncertainty"))
    candidates = [k for field, k in named.items() if "uncertainty" not in field]
    if quantity in named:
        return named[quantity], uncertainty
    if len(candidates) == 1:
        return candidates[0], uncertainty
    raise ValueError(f"quantity must name a column of {name} ({', '.join(header[1:])}; got {quantity!r})")


def _read_netcdf(path: Path, quantity: str, theta_i: float | None) -> MeasuredSpectrum:
    import xarray as xr

    try:
        with xr.open_dataset(path) as dataset:
            dataset = dataset.load()
    except (OSError, ValueError) as error:
        raise ValueError(f"could not read NetCDF {path.name}: {error}") from None
    if "result_json" in dataset.attrs or "gonio_json" in dataset.attrs:  # a virtspec-mi result file: its rules
        from virtspec_mi.runtime.reading import read_result

        return _from_result(read_result(path), quantity, theta_i, path.name)
    names = [name for name in dataset.data_vars if "uncertainty" not in str(name)]
    if quantity in dataset.data_vars:
        name = quantity
    elif len(names) == 1:
        name = names[0]
    else:
        raise ValueError(f"quantity must name a variable of {path.name} ({', '.join(map(str, names))}; "
                         f"got {quantity!r})")
    values = dataset[name].squeeze()
    if values.ndim != 1 or values.dims[0] not in dataset.coords:
        raise ValueError(f"{name} of {path.name} must be one-dimensional over a wavelength coordinate "
                         f"(got dims {values.dims})")
    wavelengths = dataset[values.dims[0]].values
    uncertainty = next((dataset[u].squeeze().values for u in (f"{name}_uncertainty", "uncertainty")
                        if u in dataset.data_vars), None)
    keep = ~np.isnan(values.values)
    return MeasuredSpectrum.of(wavelengths[keep], values.values[keep],
                               None if uncertainty is None else uncertainty[keep], quantity=quantity,
                               source=path.name, column=str(name))


# -- the comparison ------------------------------------------------------------------


def compare(
    result: ResultBase | str | os.PathLike,
    measured: Any,
    *,
    quantity: str | None = None,
    theta_i: float | None = None,
    measurement_uncertainty: Any = None,
    illuminant: str = DEFAULT_ILLUMINANT,
    observer: str = DEFAULT_OBSERVER,
) -> Comparison:
    """
    Compare a result with a measured spectrum over their common wavelengths.

    Parameters
    ----------
    result
        A result of any kind (a reading or a sweep, a goniophotometer reading, a sphere
        reading) or a result file (``.nc``, ``.csv``, ``.json``, ``.zarr``; also
        ``virtspec measure --json`` output). A parameter sweep: select one point first.
    measured
        A measured spectrum: a file (colour-science CSV, plain ``wavelength,value[,
        uncertainty]`` CSV, NetCDF, a result file), a ``colour.SpectralDistribution``, a
        ``(wavelengths, values[, uncertainty])`` tuple or a :class:`MeasuredSpectrum`.
    quantity
        The result's quantity (its ``QUANTITIES``; default the first): ``reflectance``,
        ``transmittance`` or ``absorptance`` of a reading (the measured column of that
        name), or a sphere reading's ``reading``, ``corrected`` or ``hemispherical`` (the
        measured column of what the sphere measures).
    theta_i
        The result's angle to use (needed for a sweep over several angles).
    measurement_uncertainty
        A number or one value per measured point, added to the certified tolerance;
        overrides an uncertainty column of the file. Default: the file's, else none.
    illuminant, observer
        For ΔE2000 (names of ``colour.SDS_ILLUMINANTS`` and ``colour.MSDS_CMFS``).

    Raises
    ------
    ValueError
        Bad input, or no result wavelength inside the measured range (nothing to compare).
    """

    result, result_name = _result_of(result)
    quantity = result.check_quantity(quantity)
    theta_i = None if theta_i is None else number("theta_i", theta_i)  # one of the result's angles: checked there
    _check_colour_names(illuminant, observer)
    simulation = result.spectrum(quantity, theta_i)
    spectrum = read_measured(measured, simulation.measures, theta_i)
    if measurement_uncertainty is not None:
        spectrum = spectrum.with_uncertainty(measurement_uncertainty)
    wavelengths = simulation.wavelengths
    low, high = spectrum.wavelengths[0], spectrum.wavelengths[-1]
    inside = (wavelengths >= low - _MATCH_NM) & (wavelengths <= high + _MATCH_NM)
    if not inside.any():
        raise ValueError(f"the result's wavelengths ({_range(wavelengths)} nm) lie outside the measured range "
                         f"{_range(spectrum.wavelengths)} nm of {spectrum.source}: nothing to compare")
    compared = wavelengths[inside]
    at = np.clip(compared, low, high)
    measured_values = np.interp(at, spectrum.wavelengths, spectrum.values)
    uncertainty = (np.zeros(len(compared)) if spectrum.uncertainty is None
                   else np.interp(at, spectrum.wavelengths, spectrum.uncertainty))
    nearest = np.min(np.abs(compared[:, None] - spectrum.wavelengths[None, :]), axis=1)
    simulated = simulation.values[inside]
    delta_e, note, colours = _delta_e(compared, simulated, measured_values, simulation.measures, illuminant, observer)
    return Comparison(
        quantity=quantity, theta_i=simulation.theta_i, wavelengths=compared, simulated=simulated,
        measured=measured_values, certified_mu=simulation.tolerance[inside],
        measurement_uncertainty=uncertainty, left_out=wavelengths[~inside],
        interpolated=int(np.sum(nearest > _MATCH_NM)), delta_E=delta_e, delta_E_note=note,
        simulated_colour=colours[0], measured_colour=colours[1], illuminant=illuminant, observer=observer,
        result=result, spectrum=spectrum, result_name=result_name)


def _delta_e(wavelengths: np.ndarray, simulated: np.ndarray, measured: np.ndarray, quantity: str, illuminant: str,
             observer: str) -> tuple[float, str, tuple[Colour | None, Colour | None]]:
    """ΔE2000 of the two spectra on the same wavelengths, or NaN and the reason."""

    import colour

    if quantity == "absorptance":
        return math.nan, "not computed: colour is for reflectance or transmittance spectra", (None, None)
    if len(wavelengths) < 2:
        return math.nan, "not computed: colorimetry needs at least two wavelengths (1 compared)", (None, None)
    try:
        with colour.utilities.suppress_warnings(colour_runtime_warnings=True):
            colours = tuple(colorimetry(colour.SpectralDistribution(values, wavelengths), illuminant, observer)
                            for values in (simulated, measured))
    except ValueError as error:
        return math.nan, f"not computed: {error}", (None, None)
    delta_e = float(colour.delta_E(colours[0].Lab, colours[1].Lab, method="CIE 2000"))
    return delta_e, "", colours  # type: ignore[return-value]


# -- helpers -------------------------------------------------------------------------


def check_quantity(quantity: str) -> None:
    if quantity not in QUANTITIES:
        raise ValueError(f"quantity must be one of {', '.join(QUANTITIES)} (got {quantity!r})")


def _check_colour_names(illuminant: str, observer: str) -> None:
    import colour

    if illuminant not in colour.SDS_ILLUMINANTS:
        raise ValueError(f"illuminant must be a name of colour.SDS_ILLUMINANTS, e.g. D65, A, D50 (got {illuminant!r})")
    if observer not in colour.MSDS_CMFS:
        raise ValueError(f"observer must be a name of colour.MSDS_CMFS, e.g. {DEFAULT_OBSERVER!r} (got {observer!r})")


def _result_of(result: Any) -> tuple[ResultBase, str]:
    if isinstance(result, ResultBase) and result.QUANTITIES:
        return result, "result"
    if isinstance(result, ResultBase):
        raise ValueError(f"result must be a reading with a spectrum (a Result, GonioResult or SphereResult; got a "
                         f"{result.KIND})")
    if isinstance(result, (str, os.PathLike)):
        from virtspec_mi.runtime.reading import read_result

        return _result_of(read_result(result))[0], Path(result).name
    raise ValueError("result must be a virtspec-mi result (a Result, GonioResult or SphereResult) or a result file "
                     f"(got {type(result).__name__})")


class ComparisonApplication(Application):
    """Simulated against measured spectra: ``vm.compare``, ``virtspec compare``."""

    name: ClassVar[str] = "comparison"
    summary: ClassVar[str] = "a simulated spectrum against a measured one: residuals, combined tolerance, Delta E 2000"
    results: ClassVar[tuple[type, ...]] = (Comparison,)
