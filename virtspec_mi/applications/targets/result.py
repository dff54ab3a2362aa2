"""
The result of a target: certified derived quantities and the readings behind them
=================================================================================

A :class:`DerivedResult` holds what :func:`~.measure.take_target` certified — each
quantity (:class:`~.targets.Value`) with its interval, all of them together with
probability ≥ 1 − δ — the rays spent (the pilot's apart), the tolerance each linear
functional was certified to, and the per-wavelength readings
(:attr:`DerivedResult.readings`, a hemispherical
:class:`~virtspec_mi.results.readings.Result`), which carry no joint per-wavelength
certificate of their own. :meth:`DerivedResult.summary`, :meth:`DerivedResult.as_dict`
(JSON) and :meth:`DerivedResult.to_dataset` (xarray: one variable per quantity with
``units``, ``long_name`` and its ``<name>_lower`` / ``<name>_upper`` bounds, and the
readings over ``wavelength``) show it.

References
----------
Hoeffding (1963), Theorem 2.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from typing import Any

import numpy as np

from virtspec_mi.applications.targets.targets import Target, Value

__all__ = ["DerivedResult", "DerivedSweep", "FORMAT"]

FORMAT: str = "virtspec-mi derived 1"
"""The ``format`` of :meth:`DerivedResult.as_dict`."""


@dataclass(frozen=True, eq=False)
class DerivedResult:
    """
    Certified derived quantities (see the module docstring).

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
    """

    target: Target
    values: tuple[Value, ...]
    readings: Any
    rays: int
    pilot_rays: int
    delta: float
    statements: int
    functional_tolerances: tuple[float, ...]
    colour: Any = None
    met: bool = True
    seconds: float = 0.0

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
                 f"{'s' if self.statements > 1 else ''}, Hoeffding 1963, each at delta/{self.statements})"
                 + ("" if self.met else "  -- NOT MET: the rays spent certify less than asked (see the intervals)"),
                 f"rays: {self.rays:,} on {len(wavelengths)} wavelengths {wavelengths.min():g}-{wavelengths.max():g} "
                 f"nm (N_k proportional to |w_k|, {int(np.min(readings.rays)):,}-{int(np.max(readings.rays)):,} "
                 f"each)" + (f" + {self.pilot_rays:,} pilot rays (sizing only)" if self.pilot_rays else "")
                 + f", {self.seconds:.3g} s"]
        for v in self.values:
            lines.append(f"  {v.name:<12} = {v.value:11.6f}   in [{v.lower:.6f}, {v.upper:.6f}]   {v.long_name}")
        lines.append("the per-wavelength readings (result.readings) are the rays spent: they carry no joint "
                     "per-wavelength certificate of their own")
        return "\n".join(lines)

    def __repr__(self) -> str:
        head = ", ".join(f"{v.name} = {v.value:.5g} [{v.lower:.5g}, {v.upper:.5g}]" for v in self.values[:3])
        return f"<virtspec_mi DerivedResult {head}{', ...' if len(self.values) > 3 else ''}; {self.total_rays:,} rays>"

    def as_dict(self) -> dict[str, Any]:
        """Plain data (JSON-ready), format :data:`FORMAT`; the readings as their own ``as_dict()``."""

        return {"format": FORMAT, "target": self.target.as_dict(), "description": self.target.describe(),
                "delta": self.delta, "statements": self.statements, "met": bool(self.met),
                "rays": int(self.rays), "pilot_rays": int(self.pilot_rays), "seconds": float(self.seconds),
                "functional_tolerances": list(self.functional_tolerances),
                "values": {v.name: {"value": v.value, "lower": v.lower, "upper": v.upper, "units": v.units,
                                    "long_name": v.long_name} for v in self.values},
                **({} if self.colour is None else {"colour": self.colour.as_dict()}),
                "readings_note": "the rays spent per wavelength; no joint per-wavelength certificate of their own",
                "readings": self.readings.as_dict()}

    def plot(self, path: Any = None) -> Any:
        """A colour swatch with its certified ΔE₀₀ radius, or the values with error bars (:mod:`virtspec_mi.applications.targets.plot`)."""

        from virtspec_mi.applications.targets.plot import plot_derived

        return plot_derived(self, path)

    def to_json(self) -> str:
        return json.dumps(self.as_dict())

    def to_dataset(self) -> Any:
        """An ``xarray.Dataset``: each quantity with its bounds (attrs ``units``, ``long_name``) and the readings."""

        import xarray as xr

        readings = self.readings.to_dataset()
        data = {}
        for v in self.values:
            data[v.name] = xr.Variable((), v.value, {"units": v.units, "long_name": v.long_name,
                                                     "ancillary_variables": f"{v.name}_lower {v.name}_upper"})
            data[f"{v.name}_lower"] = xr.Variable((), v.lower, {"units": v.units,
                                                               "long_name": f"certified lower bound of {v.name}"})
            data[f"{v.name}_upper"] = xr.Variable((), v.upper, {"units": v.units,
                                                               "long_name": f"certified upper bound of {v.name}"})
        derived = xr.Dataset(data, attrs={"target": self.target.describe(), "delta": self.delta,
                                          "rays": self.rays, "pilot_rays": self.pilot_rays, "met": int(self.met),
                                          "readings_note": "per-wavelength readings: the rays spent, no joint "
                                                           "per-wavelength certificate"})
        return xr.merge([derived, readings], combine_attrs="override")


@dataclass(frozen=True, eq=False)
class DerivedSweep:
    """
    One target certified at several incidence angles (``vm.sweep(scene, theta_i=...,
    target=...)``): one :class:`DerivedResult` per θi, each certified at its own δ (a
    statement about all angles at once holds at δ × the number of angles, a union bound).
    """

    theta_i: tuple[float, ...]
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
        return {"format": FORMAT, "theta_i": list(self.theta_i), "results": [r.as_dict() for r in self.results]}

    def to_dataset(self) -> Any:
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
        data["rays"] = xr.Variable(("theta_i",), np.array([r.total_rays for r in self.results]),
                                   {"units": "1", "long_name": "rays traced (pilots included)"})
        return xr.Dataset(data, coords={"theta_i": ("theta_i", np.asarray(self.theta_i),
                                                    {"units": "degree", "long_name": "incidence angle"})},
                          attrs={"target": first.target.describe(), "delta_each": first.delta})
