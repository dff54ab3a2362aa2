"""
The result of a target: certified derived quantities and the readings behind them
=================================================================================

A :class:`DerivedResult` holds what :func:`~virtspec_mi.applications.targets.measure.take_target` certified — each
quantity (:class:`~.targets.Value`) with its interval, all of them together with
probability ≥ 1 − δ — the rays spent (the pilot's apart), the tolerance each linear
functional was certified to, and the per-wavelength readings
(:attr:`DerivedResult.readings`, a hemispherical
:class:`~virtspec_mi.results.readings.Result`), which carry no joint per-wavelength
certificate of their own. :meth:`DerivedResult.summary`, :meth:`DerivedResult.as_dict`
(JSON) and :meth:`DerivedResult.to_dataset` (xarray: one variable per quantity with
``units``, ``long_name`` and its ``<name>_lower`` / ``<name>_upper`` bounds, and the
readings over ``wavelength``) show it. Both kinds are results of the one family
(:class:`~virtspec_mi.results.records.Record`: format ``"virtspec-mi derived 1"`` and
``"virtspec-mi derived sweep 1"``), written by the one writer (``.json``, ``.nc``) and read
back by :func:`virtspec_mi.read_result`; a target read from a file is its record
(:class:`~virtspec_mi.results.records.RecordedData`: ``as_dict()``, ``describe()``).

References
----------
Hoeffding (1963), Theorem 2.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from typing import Any, ClassVar, Mapping

import numpy as np

from virtspec_mi.applications.targets.targets import Target, Value
from virtspec_mi.base.surface import spoken
from virtspec_mi.results.figures import Figure
from virtspec_mi.results.integrity import (CountRules, check_checksum, check_result, field_value, optional_numbers,
                                           whole_counts)
from virtspec_mi.results.readings import Result
from virtspec_mi.results.records import Record, RecordedData

__all__ = ["DerivedResult", "DerivedSweep", "FORMAT", "SWEEP_FORMAT"]

FORMAT: str = "virtspec-mi derived 1"
"""The format tag of a :class:`DerivedResult` (its :meth:`DerivedResult.as_dict`, its files)."""
SWEEP_FORMAT: str = "virtspec-mi derived sweep 1"
"""
The format tag of a :class:`DerivedSweep`. Earlier releases wrote a sweep's JSON with
:data:`FORMAT` and a ``results`` list: read as a sweep all the same.
"""
_SPENT = CountRules(None)
"""A target's ray counts: whole numbers (the estimates' rays are the readings' N summed: :meth:`DerivedResult._check`)."""


def _plot(result: Any, path: Any, quantity: Any, **options: Any) -> Any:
    from virtspec_mi.applications.targets.plot import plot_derived

    return plot_derived(result, path)


def _readings(data: Mapping[str, Any]) -> Result:
    """
    A target's readings from their JSON object, checked by every rule of a reading's but
    the one of the settings' μ: their rays follow the target's weights (Nₖ ∝ |wₖ|), not the
    μ their settings state (their wavelengths and θi are checked against the settings').
    """

    if data.get("format") != Result.FORMAT:
        raise ValueError(f"'readings' must be a hemispherical reading (format {Result.FORMAT!r})")
    readings = Result._from_dict(data)
    check_result(readings, sized=False)
    readings._check_stored(data)
    check_checksum(data)
    return readings


def _quantities(values: Any, dims: tuple[str, ...] = ()) -> dict[str, tuple[str, str]]:
    """``(units, long_name)`` of each quantity's variable and its bounds."""

    table = {}
    for v in values:
        table[v.name] = (v.units, v.long_name)
        table[f"{v.name}_lower"] = (v.units, f"certified lower bound of {v.name}")
        table[f"{v.name}_upper"] = (v.units, f"certified upper bound of {v.name}")
    return table


_ROUTE_WORDS: dict[str, tuple[str, Any]] = {
    "betting": ("N_k in proportion to |w_k| sigma_k",
                lambda batches: f"betting confidence sequence, stopped after batch {len(batches)} of rays "
                                f"{', '.join(f'{b:,}' for b in batches)}"),
    "two-stage": ("each ray's wavelength drawn with probability |w_k|/sum|w|",
                  lambda batches: "pooled two-stage exact rule, a pilot then one batch per functional"),
}
"""How a summary names each route's allocation and certificate (its ``bound``; any other: Hoeffding's)."""
_HOEFFDING_WORDS: tuple[str, Any] = ("N_k proportional to |w_k|", lambda batches: "Hoeffding 1963")


@dataclass(frozen=True, eq=False)
class DerivedResult(Record):
    """
    Certified derived quantities (see the module docstring); a result kind (format
    ``"virtspec-mi derived 1"``): its Dataset has one variable per quantity with its bounds,
    the tolerance of each functional, and the readings over ``wavelength``.

    Attributes
    ----------
    target : Target
        What was asked for.
    values : tuple of Value
        The quantities and their intervals (certified together at :attr:`delta`).
    readings : Result
        The per-wavelength readings of the rays spent (no joint per-wavelength certificate).
    rays : int
        Rays spent on the estimates (the readings' N summed).
    pilot_rays : int
        Rays a pilot spent to size them (0 for a linear target).
    delta : float
        δ of the joint statement (each of the :attr:`statements` functionals at δ/statements).
    statements : int
        The linear functionals certified together.
    functional_tolerances : tuple of float
        The Hoeffding tolerance each functional's rays give (in its own units).
    colour : CertifiedColour or None
        A colour target's colour.
    met : bool
        Whether the certified values meet the tolerance asked for.
    seconds : float
        Wall time of the whole measurement (pilot, sizing, tracing, certificate).
    bound : str
        The certificate: ``"betting"`` (a betting confidence sequence over batches,
        :mod:`.sequential`), ``"two-stage"`` (pooled two-stage readings, :mod:`.pooled`) or
        ``"hoeffding"`` (one batch, Hoeffding 1963).
    batches : tuple of int
        The rays of each batch, in order (betting: the last is the stopping time;
        two-stage: each functional's second batch).
    """

    FORMAT: ClassVar[str] = FORMAT
    KIND: ClassVar[str] = "certified target"
    VARIABLES: ClassVar[dict[str, tuple[str, str]]] = {
        "functional_tolerance": ("as the functional", "Hoeffding tolerance of the functional's rays"),
        "functional": ("1", "linear functional certified")}
    FIGURES: ClassVar[dict[str, Figure]] = {
        "values": Figure(_plot, "a colour as a swatch with its certified dE00 radius; other values with their "
                                "certified intervals")}

    target: Target
    values: tuple[Value, ...]
    readings: Any
    rays: int
    pilot_rays: int
    delta: float = field()
    statements: int
    functional_tolerances: tuple[float, ...]
    colour: Any = None
    met: bool = True
    seconds: float = 0.0
    bound: str = "hoeffding"
    batches: tuple[int, ...] = ()

    def __getitem__(self, name: str) -> Value:
        for value in self.values:
            if value.name == name:
                return value
        raise KeyError(f"{name!r}: the quantities are {', '.join(v.name for v in self.values)}")

    @property
    def total_rays(self) -> int:
        """Every ray traced: the pilot's and the estimates'."""

        return self.rays + self.pilot_rays

    def summary(self) -> str:
        readings = self.readings
        wavelengths = np.atleast_1d(readings.coords["wavelength"])
        lines = [f"target: {self.target.describe()}",
                 f"certified together at delta = {self.delta:g} ({self.statements} linear functional"
                 f"{'s' if self.statements > 1 else ''}, {self._bound_words}, each at delta/{self.statements})"
                 + ("" if self.met else "  -- NOT MET: the rays spent certify less than asked (see the intervals)"),
                 f"rays: {self.rays:,} on {len(wavelengths)} wavelengths {wavelengths.min():g}-{wavelengths.max():g} "
                 f"nm ({self._allocation_words}, {int(np.min(readings.rays)):,}-{int(np.max(readings.rays)):,} "
                 f"each)" + (f" + {self.pilot_rays:,} pilot rays (sizing only)" if self.pilot_rays else "")
                 + f", {self.seconds:.3g} s"]
        for v in self.values:
            lines.append(f"  {v.name:<12} = {v.value:11.6f}   in [{v.lower:.6f}, {v.upper:.6f}]   {v.long_name}")
        lines.append(f"the per-wavelength readings ({spoken('result.readings', 'in --json')}) are the rays spent: "
                     "they carry no joint per-wavelength certificate of their own")
        return "\n".join(lines)

    @property
    def _allocation_words(self) -> str:
        return _ROUTE_WORDS.get(self.bound, _HOEFFDING_WORDS)[0]

    @property
    def _bound_words(self) -> str:
        return _ROUTE_WORDS.get(self.bound, _HOEFFDING_WORDS)[1](self.batches)

    def __repr__(self) -> str:
        head = ", ".join(f"{v.name} = {v.value:.5g} [{v.lower:.5g}, {v.upper:.5g}]" for v in self.values[:3])
        return f"<virtspec_mi DerivedResult {head}{', ...' if len(self.values) > 3 else ''}; {self.total_rays:,} rays>"

    def as_dict(self) -> dict[str, Any]:
        """Plain data (JSON-ready), format :data:`FORMAT`; the readings as their own ``as_dict()``."""

        return {"format": FORMAT, "target": self.target.as_dict(), "description": self.target.describe(),
                "delta": self.delta, "statements": self.statements, "met": bool(self.met),
                "rays": int(self.rays), "pilot_rays": int(self.pilot_rays), "seconds": float(self.seconds),
                "bound": self.bound, "batches": [int(b) for b in self.batches],
                "functional_tolerances": list(self.functional_tolerances),
                "values": {v.name: {"value": v.value, "lower": v.lower, "upper": v.upper, "units": v.units,
                                    "long_name": v.long_name} for v in self.values},
                **({} if self.colour is None else {"colour": self.colour.as_dict()}),
                "readings_note": "the rays spent per wavelength; no joint per-wavelength certificate of their own",
                "readings": self.readings.as_dict()}

    def plot(self, path: Any = None) -> Any:
        """
        A colour swatch with its certified ΔE₀₀ radius, or the values with error bars
        (:mod:`~virtspec_mi.applications.targets.plot`).
        """

        from virtspec_mi.applications.targets.plot import plot_derived

        return plot_derived(self, path)

    def to_json(self) -> str:
        return json.dumps(self.as_dict())

    def _stored(self) -> Any:
        """Each quantity with its bounds, each functional's tolerance, and the readings (with what they derive)."""

        import xarray as xr

        readings = self.readings.to_dataset()
        readings.attrs = {}
        data: dict[str, Any] = {}
        for v in self.values:
            data[v.name] = ((), v.value, {"ancillary_variables": f"{v.name}_lower {v.name}_upper"})
            data[f"{v.name}_lower"], data[f"{v.name}_upper"] = ((), v.lower), ((), v.upper)
        data["functional_tolerance"] = (("functional",), np.asarray(self.functional_tolerances, dtype=np.float64))
        derived = xr.Dataset(data, attrs={"target": self.target.describe(), "delta": self.delta,
                                          "statements": int(self.statements), "rays": int(self.rays),
                                          "pilot_rays": int(self.pilot_rays), "met": int(self.met),
                                          "seconds": float(self.seconds),
                                          "readings_note": "per-wavelength readings: the rays spent, no joint "
                                                           "per-wavelength certificate"})
        return xr.merge([derived, readings], combine_attrs="override")

    def described(self) -> dict[str, tuple[str, str]]:
        return {**self.readings.described(), **super().described(), **_quantities(self.values)}

    def _parameter_keys(self) -> dict[str, str] | None:
        return self.readings._parameter_keys()

    @classmethod
    def _from_plain(cls, tag: str, data: Any) -> Any:
        if isinstance(data, dict) and "results" in data:  # a sweep's JSON of an earlier release: this tag, its results
            return DerivedSweep.from_dict({**data, "format": SWEEP_FORMAT})
        return super()._from_plain(tag, data)

    @classmethod
    def _from_dict(cls, data: Mapping[str, Any]) -> "DerivedResult":
        values = tuple(Value(name, *(float(v) if v is not None else float("nan")
                                     for v in (item["value"], item["lower"], item["upper"])),
                             field_value(item, "units", "text"), field_value(item, "long_name", "text"))
                       for name, item in field_value(data, "values", "object").items())
        colour = data.get("colour")
        return cls(RecordedData(field_value(data, "target", "object"), field_value(data, "description", "text")),
                   values, _readings(field_value(data, "readings", "object")),
                   int(whole_counts(data["rays"], "rays")), int(whole_counts(data["pilot_rays"], "pilot_rays")),
                   float(data["delta"]), int(whole_counts(data["statements"], "statements")),
                   tuple(optional_numbers(data["functional_tolerances"], "functional_tolerances").tolist()),
                   None if colour is None else RecordedData(colour), field_value(data, "met", "flag"),
                   float(field_value(data, "seconds", "seconds")),
                   field_value(data, "bound", "text") if "bound" in data else "hoeffding",
                   tuple(int(b) for b in whole_counts(data.get("batches", []), "batches")))

    def _check(self) -> None:
        """The estimates' rays are the readings' N summed; every value lies within its certified interval."""

        if int(self.rays) != int(np.sum(self.readings.rays)):
            raise ValueError(f"'rays' holds {int(self.rays):,}; the readings' rays add up to "
                             f"{int(np.sum(self.readings.rays)):,}")
        for v in self.values:
            if not v.lower <= v.value <= v.upper and not np.isnan([v.lower, v.value, v.upper]).any():
                raise ValueError(f"the value of {v.name!r} ({v.value:g}) lies outside its interval "
                                 f"[{v.lower:g}, {v.upper:g}]")


@dataclass(frozen=True, eq=False)
class DerivedSweep(Record):
    """
    One target certified at several incidence angles (``vm.sweep(scene, theta_i=...,
    target=...)``): one :class:`DerivedResult` per θi, each certified at its own δ (a
    statement about all angles at once holds at δ × the number of angles, a union bound).
    A result kind (format ``"virtspec-mi derived sweep 1"``): its Dataset has each quantity
    and its bounds over ``theta_i`` and the rays of each angle.
    """

    FORMAT: ClassVar[str] = SWEEP_FORMAT
    KIND: ClassVar[str] = "certified target over theta_i"
    VARIABLES: ClassVar[dict[str, tuple[str, str]]] = {"rays": ("1", "rays traced (pilots included)"),
                                                       "theta_i": ("degree", "incidence angle")}

    theta_i: tuple[float, ...] = field()
    results: tuple[DerivedResult, ...]

    def __getitem__(self, index: int) -> DerivedResult:
        return self.results[index]

    def __len__(self) -> int:
        return len(self.results)

    @property
    def total_rays(self) -> int:
        return sum(r.total_rays for r in self.results)

    def summary(self) -> str:
        parts = []
        for theta, result in zip(self.theta_i, self.results):
            parts.append(f"theta_i = {theta:g} deg\n" + result.summary())
        return "\n\n".join(parts)

    def as_dict(self) -> dict[str, Any]:
        return {"format": SWEEP_FORMAT, "theta_i": list(self.theta_i), "results": [r.as_dict() for r in self.results]}

    @classmethod
    def _from_dict(cls, data: Mapping[str, Any]) -> "DerivedSweep":
        results = data["results"]
        if not isinstance(results, list):
            raise ValueError("'results' must be a list of certified targets")
        return cls(tuple(optional_numbers(data["theta_i"], "theta_i").tolist()),
                   tuple(DerivedResult.from_dict(item) for item in results))

    def _check(self) -> None:
        if len(self.theta_i) != len(self.results):
            raise ValueError(f"'theta_i' holds {len(self.theta_i)} angles and 'results' {len(self.results)} targets")

    def described(self) -> dict[str, tuple[str, str]]:
        return {**super().described(), **_quantities(self.results[0].values)}

    def _stored(self) -> Any:
        """The quantities and their bounds over ``theta_i`` (xarray; the readings left out: see each result's)."""

        import xarray as xr

        first = self.results[0]
        data = {}
        for k, v in enumerate(first.values):
            for suffix, field_name in (("", "value"), ("_lower", "lower"), ("_upper", "upper")):
                values = [getattr(r.values[k], field_name) for r in self.results]
                long_name = v.long_name if not suffix else f"certified {field_name} bound of {v.name}"
                data[v.name + suffix] = xr.Variable(("theta_i",), np.asarray(values, dtype=np.float64),
                                                    {"units": v.units, "long_name": long_name})
        data["rays"] = xr.Variable(("theta_i",), np.array([r.total_rays for r in self.results], dtype=np.int64))
        return xr.Dataset(data, coords={"theta_i": ("theta_i", np.asarray(self.theta_i, dtype=np.float64))},
                          attrs={"target": first.target.describe(), "delta_each": first.delta})
