"""
A simulated against a measured spectrum: :class:`Comparison`
============================================================

What :func:`virtspec_mi.applications.comparison.compare` returns: the compared points,
their residuals and combined tolerances, ΔE2000, and the result and measured spectrum
behind them. A result kind of the one family (:class:`~virtspec_mi.results.records.Record`,
format ``"virtspec-mi comparison 1"``): its files (``.json``, ``.nc``) hold the result
compared and the measured spectrum besides the figures, and reading one compares them
again — every figure the file states must be the one they give. ``virtspec compare
--json`` of an earlier release printed the figures alone (no format tag): read as the
figures they are (tagged ``"virtspec-mi comparison 0"``; nothing to draw).

References
----------
Baranoski et al. (2001), Sect. 5, eq. (23); CIE 142-2001 (CIEDE2000).
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field, replace
from typing import Any, ClassVar, Mapping

import numpy as np

from pathlib import Path

from virtspec_mi.applications.comparison.measured import _MATCH_NM, MeasuredSpectrum, read_measured
from virtspec_mi.base.checks import number
from virtspec_mi.colorimetry.cie import DEFAULT_ILLUMINANT, DEFAULT_OBSERVER, Colour, colorimetry
from virtspec_mi.results.base import ResultBase, plain_data, round_up
from virtspec_mi.results.figures import Figure
from virtspec_mi.results.integrity import field_value, finite_labels, optional_numbers
from virtspec_mi.results.records import Record, RecordedData

__all__ = ["Comparison", "compare"]


@dataclass(frozen=True, eq=False)
class Comparison(Record):
    """
    A result against a measured spectrum over their common wavelengths (sorted); a result
    kind (format ``"virtspec-mi comparison 1"``): its Dataset has the compared points over
    ``wavelength`` (simulated, measured, their tolerances, the residuals), the figures of
    the comparison as attributes; its files hold the result compared and the measured
    spectrum, from which it is rebuilt (and checked) as it is read.

    Attributes
    ----------
    quantity : str
        The result's quantity compared (``reflectance``, a sphere's ``reading`` …).
    theta_i : float
        The result's incidence angle used (degrees).
    wavelengths : ndarray
        The compared wavelengths: the result's, inside the measured range.
    simulated, measured : ndarray
        The result's values and the measured spectrum interpolated onto ``wavelengths``.
    certified_mu : ndarray
        The result's certified tolerance per point (NaN: not certified; :attr:`Spectrum.tolerance
        <virtspec_mi.results.base.Spectrum>`).
    measurement_uncertainty : ndarray
        The measurement's uncertainty per point (zeros when not given).
    left_out : ndarray
        Result wavelengths outside the measured range (not compared).
    interpolated : int
        Compared points that fall between measured wavelengths (linearly interpolated).
    delta_E : float
        ΔE2000 between the colours of both spectra (NaN: not computed, see ``delta_E_note``).
    delta_E_note : str
        Why ΔE2000 was not computed (empty when it was).
    simulated_colour, measured_colour : Colour or None
        The colours behind ``delta_E``.
    illuminant, observer : str
        The colorimetry's illuminant and observer.
    result : ResultBase
        The result compared (any kind).
    spectrum : virtspec_mi.applications.comparison.measured.MeasuredSpectrum
        The measured spectrum as read.
    result_name : str
        A name for the result (its file name, or ``"result"``).
    """

    FORMAT: ClassVar[str] = "virtspec-mi comparison 1"
    LEGACY: ClassVar[tuple[str, ...]] = ("virtspec-mi comparison 0",)
    KIND: ClassVar[str] = "comparison"
    VARIABLES: ClassVar[dict[str, tuple[str, str]]] = {
        "simulated": ("1", "the result's value"), "measured": ("1", "measured value, interpolated linearly"),
        "certified_mu": ("1", "the result's certified tolerance (NaN: not certified)"),
        "measurement_uncertainty": ("1", "measurement uncertainty"),
        "residuals": ("1", "simulated - measured"), "tolerance": ("1", "combined tolerance: certified mu' + u"),
        "within": ("1", "|residual| within the combined tolerance (1) or not (0)"),
        "left_out": ("nm", "result wavelength outside the measured range (not compared)")}
    FIGURES: ClassVar[dict[str, Figure]] = {
        "overlay": Figure(lambda result, path, quantity, **options: result.plot(path, **options),
                          "the simulated and measured spectra with their tolerances, and the residuals")}

    quantity: str
    theta_i: float = field()
    wavelengths: np.ndarray = field()
    simulated: np.ndarray
    measured: np.ndarray
    certified_mu: np.ndarray
    measurement_uncertainty: np.ndarray
    left_out: np.ndarray
    interpolated: int
    delta_E: float
    delta_E_note: str
    simulated_colour: Colour | None
    measured_colour: Colour | None
    illuminant: str
    observer: str
    result: ResultBase
    spectrum: Any = field()
    result_name: str = "result"
    recorded: dict | None = None
    """A comparison's JSON of an earlier release (which held neither the result nor the spectrum): its figures."""

    # -- statistics ----------------------------------------------------------------

    @property
    def residuals(self) -> np.ndarray:
        """Simulated − measured at each compared wavelength."""

        return self.simulated - self.measured

    @property
    def tolerance(self) -> np.ndarray:
        """The combined tolerance per point: certified μ' + measurement uncertainty (NaN: not certified)."""

        return self.certified_mu + self.measurement_uncertainty

    @property
    def certified(self) -> np.ndarray:
        """True at the compared points the result certifies."""

        return ~np.isnan(self.certified_mu)

    @property
    def within(self) -> np.ndarray:
        """True where |residual| ≤ the combined tolerance (False where not certified)."""

        tolerance = np.where(self.certified, self.tolerance, -np.inf)
        return np.abs(self.residuals) <= tolerance

    @property
    def points_within(self) -> int:
        return int(self.within.sum())

    @property
    def share_within(self) -> float:
        """Share of the certified compared points within their tolerance (NaN when none is certified)."""

        certified = int(self.certified.sum())
        return self.points_within / certified if certified else math.nan

    @property
    def rmse(self) -> float:
        return float(np.sqrt(np.mean(self.residuals ** 2)))

    @property
    def mean_absolute_difference(self) -> float:
        return float(np.mean(np.abs(self.residuals)))

    @property
    def largest_difference(self) -> tuple[float, float]:
        """(|residual|, wavelength) of the largest absolute residual."""

        k = int(np.argmax(np.abs(self.residuals)))
        return float(abs(self.residuals[k])), float(self.wavelengths[k])

    @property
    def interpolation_distance(self) -> float:
        """Largest distance (nm) from a compared wavelength to the nearest measured one (0: none interpolated)."""

        if self.result is None:
            return float(self.recorded["interpolation_distance"])
        gaps = np.abs(self.wavelengths[:, None] - self.spectrum.wavelengths[None, :]).min(axis=1)
        return float(gaps.max())

    @property
    def interval_delta(self) -> float:
        """δ of each certified point."""

        if self.result is None:
            return float(self.recorded["interval_delta"])
        return self.result.spectrum(self.quantity, self.theta_i).delta

    def simulated_spectrum(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The result's whole spectrum at θi, sorted: (wavelengths, values, certified_mu), left-out points included."""

        spectrum = self.result.spectrum(self.quantity, self.theta_i)
        return spectrum.wavelengths, spectrum.values, spectrum.tolerance

    # -- reports -------------------------------------------------------------------

    def summary(self) -> str:
        """Human-readable report: what was compared, the residuals, the tolerance and ΔE2000."""

        n, measured = len(self.wavelengths), self.spectrum
        if measured is None:  # read from an earlier release's figures: the measured range and points they state
            recorded = self.recorded
            measured = RecordedData({"source": recorded["measured_source"], "note": recorded["note"],
                                     "wavelengths": np.linspace(*recorded["measured_range"],
                                                                recorded["measured_points"])})
        total = n + len(self.left_out)
        lines = [
            f"{self.quantity} at theta_i = {self.theta_i:g} deg: {self.result_name} against {measured.source}",
            f"compared {n} of {total} wavelengths ({_range(self.wavelengths)} nm; measured "
            f"{_range(measured.wavelengths)} nm, {len(measured.wavelengths)} points; {self.interpolated} "
            "interpolated linearly)",
        ]
        if len(self.left_out):
            lines.append(f"left out (outside the measured range, never extrapolated): {_listed(self.left_out)} nm")
        largest, at = self.largest_difference
        lines.append(f"RMSE = {self.rmse:.5f}, mean |difference| = {self.mean_absolute_difference:.5f}, "
                     f"largest |difference| = {largest:.5f} at {at:g} nm")
        lines.append(self._tolerance_line())
        if self.delta_E_note:
            lines.append(f"Delta E 2000: {self.delta_E_note}")
        else:
            lines.append(f"Delta E 2000 = {self.delta_E:.3f} under {self.illuminant} ({self.observer}; "
                         f"Lab simulated {_triple(self.simulated_colour.Lab)}, measured "
                         f"{_triple(self.measured_colour.Lab)}; {self.simulated_colour.coverage:.1%} of the "
                         "colour-matching weight covered)")
        if self.interpolated:
            lines.append(f"note: {self.interpolated} compared points lie between measured wavelengths (up to "
                         f"{self.interpolation_distance:g} nm from one): the error of interpolating the measured "
                         "spectrum there is in the residuals, not in the tolerance")
        if measured.note:
            lines.append(f"note: {measured.note}")
        return "\n".join(lines)

    def _tolerance_line(self) -> str:
        certified = int(self.certified.sum())
        if not certified:
            return ("tolerance: the result is NOT CERTIFIED (weight violations or capped walks): no tolerance to "
                    "test the residuals against")
        largest_mu = round_up(float(np.nanmax(self.certified_mu)))
        largest_u = round_up(float(np.max(self.measurement_uncertainty)))
        uncertainty = (f" + measurement uncertainty (<= {largest_u:g})" if largest_u > 0
                       else " (no measurement uncertainty given)")
        text = (f"within the combined tolerance, certified mu' (<= {largest_mu:g}, "
                f"each point with probability >= {1 - self.interval_delta:g}){uncertainty}: "
                f"{self.points_within} of {certified} points ({self.share_within:.1%})")
        if certified < len(self.wavelengths):
            text += f"; {len(self.wavelengths) - certified} points NOT CERTIFIED, left out of the share"
        return text

    def as_dict(self) -> dict[str, Any]:
        """
        Every figure by name as plain data (JSON-ready; NaN as ``None``), the result compared
        (``compared``: its ``as_dict()``) and the measured spectrum (``spectrum``), from
        which :meth:`_from_dict` rebuilds the comparison.
        """

        if self.result is None:
            return dict(self.recorded)
        spectrum = self.spectrum
        return {"format": self.FORMAT, **self.figures(), "compared_result": self.result.as_dict(),
                "measured_spectrum": {
                    "wavelengths": spectrum.wavelengths.tolist(), "values": spectrum.values.tolist(),
                    "uncertainty": None if spectrum.uncertainty is None else spectrum.uncertainty.tolist(),
                    "quantity": spectrum.quantity, "source": spectrum.source, "note": spectrum.note}}

    def figures(self) -> dict[str, Any]:
        """Every figure of the comparison by name as plain data (what ``virtspec compare --json`` prints)."""

        plain = plain_data

        return {
            "quantity": self.quantity,
            "theta_i": self.theta_i,
            "result": self.result_name,
            "scene": self.result.scene,
            "measured_source": self.spectrum.source,
            "measured_range": [float(self.spectrum.wavelengths[0]), float(self.spectrum.wavelengths[-1])],
            "measured_points": len(self.spectrum.wavelengths),
            "wavelengths": plain(self.wavelengths),
            "simulated": plain(self.simulated),
            "measured": plain(self.measured),
            "residuals": plain(self.residuals),
            "certified_mu": plain(self.certified_mu),
            "measurement_uncertainty": plain(self.measurement_uncertainty),
            "tolerance": plain(self.tolerance),
            "within": plain(self.within),
            "compared": len(self.wavelengths),
            "interpolated": self.interpolated,
            "interpolation_distance": self.interpolation_distance,
            "left_out": plain(self.left_out),
            "interval_delta": self.interval_delta,
            "certified": bool(np.all(self.certified)),
            "points_within": self.points_within,
            "share_within": None if math.isnan(self.share_within) else self.share_within,
            "rmse": self.rmse,
            "mean_absolute_difference": self.mean_absolute_difference,
            "largest_difference": self.largest_difference[0],
            "delta_E_2000": None if math.isnan(self.delta_E) else self.delta_E,
            "delta_E_note": self.delta_E_note,
            "illuminant": self.illuminant,
            "observer": self.observer,
            "Lab_simulated": None if self.simulated_colour is None else plain(self.simulated_colour.Lab),
            "Lab_measured": None if self.measured_colour is None else plain(self.measured_colour.Lab),
            "note": self.spectrum.note,
        }

    # -- the result family ----------------------------------------------------------------

    def _stored(self) -> Any:
        import xarray as xr

        figures = self.figures()
        attrs = {name: ("" if value is None else value) for name, value in figures.items()
                 if isinstance(value, (str, int, float, bool)) or value is None}
        attrs = {name: (int(value) if isinstance(value, bool) else value) for name, value in attrs.items()}
        return xr.Dataset(
            {"simulated": ("wavelength", self.simulated), "measured": ("wavelength", self.measured),
             "certified_mu": ("wavelength", self.certified_mu),
             "measurement_uncertainty": ("wavelength", self.measurement_uncertainty),
             "residuals": ("wavelength", self.residuals), "tolerance": ("wavelength", self.tolerance),
             "within": ("wavelength", self.within.astype(np.int8)), "left_out": ("left", self.left_out)},
            coords={"wavelength": self.wavelengths}, attrs=attrs)

    @classmethod
    def _from_dict(cls, data: Mapping[str, Any]) -> "Comparison":
        from virtspec_mi.results.kinds import kind_of

        compared = field_value(data, "compared_result", "object")
        result = kind_of(str(compared.get("format"))).from_dict(compared)
        measured = field_value(data, "measured_spectrum", "object")
        uncertainty = measured["uncertainty"]
        spectrum = MeasuredSpectrum(finite_labels(measured["wavelengths"], "measured wavelengths"),
                                    finite_labels(measured["values"], "measured values"),
                                    None if uncertainty is None else finite_labels(uncertainty, "uncertainty"),
                                    field_value(measured, "quantity", "text"), field_value(measured, "source", "text"),
                                    field_value(measured, "note", "text"))
        again = compare(result, spectrum, quantity=field_value(data, "quantity", "text"),
                        theta_i=float(data["theta_i"]), illuminant=field_value(data, "illuminant", "text"),
                        observer=field_value(data, "observer", "text"))
        return replace(again, result_name=field_value(data, "result", "text"))

    def _check_stored(self, data: Mapping[str, Any]) -> None:
        """Every figure the file states is the one its result and measured spectrum give (an edit is refused)."""

        for name, ours in self.figures().items():
            if name in data and data[name] != ours:
                raise ValueError(f"{name!r} disagrees with the result and the measured spectrum the file holds "
                                 "(edited?)")

    @classmethod
    def _from_plain(cls, tag: str, data: Any) -> Any:
        if tag == "virtspec-mi comparison 0":  # `virtspec compare --json` of an earlier release: its figures
            return cls._recorded(data)
        return super()._from_plain(tag, data)

    @classmethod
    def _recorded(cls, data: Mapping[str, Any]) -> "Comparison":
        """A comparison's JSON of an earlier release: its figures (no result, no spectrum to draw or rebuild from)."""

        def numbers(name: str) -> np.ndarray:
            return optional_numbers(data[name], name)

        try:
            return cls(field_value(data, "quantity", "text"), float(data["theta_i"]), numbers("wavelengths"),
                       numbers("simulated"), numbers("measured"), numbers("certified_mu"),
                       numbers("measurement_uncertainty"), numbers("left_out"), int(data["interpolated"]),
                       float("nan") if data["delta_E_2000"] is None else float(data["delta_E_2000"]),
                       field_value(data, "delta_E_note", "text"), None, None, field_value(data, "illuminant", "text"),
                       field_value(data, "observer", "text"), None, None, field_value(data, "result", "text"),
                       dict(data))
        except KeyError as error:
            raise ValueError(f"lacks the field {error} of a comparison") from None

    def plot(self, path: str | os.PathLike | None = None, **options: Any) -> Any:
        """The overlay with a residual panel (:func:`virtspec_mi.results.plot.plot_comparison`)."""

        if self.result is None:
            raise ValueError("this comparison was read from a file of an earlier release, which holds its figures "
                             "but not the result and spectrum to draw: compare them again")
        from virtspec_mi.results.plot import plot_comparison

        return plot_comparison(self, path, **options)



def _range(wavelengths: np.ndarray) -> str:
    return f"{wavelengths.min():g}-{wavelengths.max():g}"


def _listed(values: np.ndarray, shown: int = 8) -> str:
    text = ", ".join(f"{v:g}" for v in values[:shown])
    return text + (f", ... ({len(values)} in all)" if len(values) > shown else "")


def _triple(values: np.ndarray) -> str:
    return "(" + ", ".join(f"{v:.2f}" for v in values) + ")"


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
        ``(wavelengths, values[, uncertainty])`` tuple or a
        :class:`~virtspec_mi.applications.comparison.measured.MeasuredSpectrum`.
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
