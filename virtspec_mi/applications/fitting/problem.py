"""
A fit's inputs, checked: the specimen, its free parameters and the measured spectra
===================================================================================

:func:`fit_problem` turns what the user gives :func:`virtspec_mi.applications.fitting.fit`
into a :class:`FitProblem`, refusing bad input with a ``ValueError`` that names it:

- the **specimen**: a project BSDF plugin's name (``abm_b``, ``prospect_d`` …: the
  paper's instrument around it, :func:`virtspec_mi.runtime.scene.instrument_scene`), a shipped
  scene's name, an XML path, a scene dict, a loaded ``mi.Scene`` or a
  :class:`~virtspec_mi.runtime.scene.LoadedScene` — loaded once (:func:`virtspec_mi.runtime.scene.loaded`),
  and every forward reading of the fit takes that one loaded scene;
- the **free parameters**: name → (lowest, highest), each a number the specimen shows
  to ``mi.traverse`` (``Cab`` or ``specimen.Cab``; :mod:`virtspec_mi.engine.parameters`),
  both ends checked by the specimen itself (a bound outside the model's validity is
  refused with the plugin's own message) and against the parameter's bounds the
  specimen declares (the specimen protocol, :class:`~virtspec_mi.plugins.specimen.Specimen`:
  an unknown name is answered with each parameter's units and bounds);
- the **measured spectra**: reflectance and/or transmittance (:func:`~virtspec_mi.applications.comparison.read_measured`
  formats), each with its measurement uncertainty (a fit without one has no honest
  confidence set: refused), on one set of wavelengths inside the specimen's data range.

References
----------
Baranoski et al. (2001), Sect. 5 (comparisons with measured data).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Mapping, Sequence

import numpy as np

from virtspec_mi.base.checks import number
from virtspec_mi.base.surface import spoken
from virtspec_mi.applications.comparison import MeasuredSpectrum, read_measured
from virtspec_mi.engine.bench import Bench
from virtspec_mi.engine.parameters import PREFIX, apply_point, current_values, known_parameters, parameter_space
from virtspec_mi.plugins import specimen_rows
from virtspec_mi.plugins.specimen import specimen_of
from virtspec_mi.runtime.scene import LoadedScene, instrument_scene, loaded, scene_fingerprint

__all__ = ["FitProblem", "fit_problem", "describe", "FIT_QUANTITIES"]

FIT_QUANTITIES: tuple[str, ...] = ("reflectance", "transmittance")
"""What a fit matches: a measured reflectance, transmittance, or both."""

_MATCH_NM = 1e-6


@dataclass(frozen=True, eq=False)
class FitProblem:
    """A checked fit: the scene, the free parameters and their bounds, the measured spectra on the fit's wavelengths."""

    loaded: LoadedScene
    """The scene, loaded once: its bench, fingerprint and source (a path or dict given travels to Dask workers)."""
    names: tuple[str, ...]
    """The free parameters as the user named them."""
    keys: tuple[str, ...]
    """Their sweep names (``specimen.NAME``)."""
    bounds: np.ndarray
    """(n, 2): lowest and highest value of each free parameter."""
    wavelengths: np.ndarray
    measured: dict[str, np.ndarray]
    """quantity → measured values on :attr:`wavelengths`."""
    uncertainty: dict[str, np.ndarray]
    """quantity → the measurement's uncertainty (a half-width) on :attr:`wavelengths`."""
    specimen: str
    """The specimen in words (its plugin or scene name)."""
    fingerprints: frozenset[str]
    """
    Every fingerprint a reading of this scene may carry: the loaded scene's, and the
    ``mi.Scene``'s (what a fit's in-process readings recorded before the scene was loaded
    once: their tables still read).
    """
    start: tuple[float, ...]
    """The scene's own values of the free parameters (restored after the fit)."""

    @property
    def bench(self) -> Bench:
        """The emitter and specimen disks (the forward readings set the specimen's parameters)."""

        return self.loaded.bench

    @property
    def scene(self) -> Any:
        """The loaded ``mi.Scene``."""

        return self.loaded.bench.scene

    @property
    def fingerprint(self) -> str:
        """The scene's fingerprint as its readings record it (:func:`virtspec_mi.runtime.scene.scene_fingerprint`)."""

        return self.loaded.fingerprint

    @property
    def quantities(self) -> tuple[str, ...]:
        return tuple(self.measured)

    def normalised(self, values: Sequence[float]) -> np.ndarray:
        low, high = self.bounds.T
        return (np.asarray(values, dtype=np.float64) - low) / (high - low)

    def denormalised(self, x: Sequence[float]) -> np.ndarray:
        low, high = self.bounds.T
        return low + np.clip(np.asarray(x, dtype=np.float64), 0.0, 1.0) * (high - low)


def _specimen_scene(specimen: Any) -> tuple[Any, str]:
    if isinstance(specimen, LoadedScene):
        return specimen, str(specimen.source["scene"])
    if isinstance(specimen, str) and specimen in specimen_rows():  # a specimen plugin, an outside one too
        return instrument_scene({"type": specimen}), specimen
    if isinstance(specimen, str):
        return specimen, specimen
    return specimen, type(specimen).__name__


def _declared(own: Any, short: str) -> str:
    """A parameter as an error lists it: with its units and bounds when the specimen declares them."""

    declared = own.parameter(short.rpartition(".")[2])
    return short if declared is None else f"{short} {declared.describe().partition(' ')[2]}"


def _bounds(name: str, value: Any) -> tuple[float, float]:
    if isinstance(value, str) and ":" in value:
        value = value.split(":")
    if not isinstance(value, (tuple, list)) or len(value) != 2:
        raise ValueError(f"the bounds of free parameter {name!r} must be (lowest, highest) (got {value!r})")
    low, high = number(f"{name} lowest", value[0]), number(f"{name} highest", value[1])
    if not (math.isfinite(low) and math.isfinite(high) and low < high):
        raise ValueError(f"the bounds of free parameter {name!r} must be finite with lowest < highest "
                         f"(got {low:g}, {high:g})")
    return low, high


def _spectra(measured: Any, quantities: Sequence[str] | None) -> dict[str, MeasuredSpectrum]:
    if isinstance(measured, Mapping):
        chosen = dict(measured)
    else:
        given = tuple(quantities or ("reflectance",))
        chosen = {quantity: measured for quantity in given}
    if not chosen:
        raise ValueError("a fit needs a measured reflectance or transmittance spectrum")
    spectra = {}
    for quantity, source in chosen.items():
        if quantity not in FIT_QUANTITIES:
            raise ValueError(f"a fit matches {' or '.join(FIT_QUANTITIES)} spectra (got {quantity!r})")
        spectrum = read_measured(source, quantity)
        if spectrum.quantity != quantity:
            raise ValueError(f"the measured spectrum {spectrum.source} is a {spectrum.quantity}, given as {quantity}")
        spectra[quantity] = spectrum
    read = [(q, spectra[q]) for q in spectra if not isinstance(chosen[q], (tuple, list))]
    for k, (quantity, spectrum) in enumerate(read):  # one file's one column read as two quantities: refused
        for other, earlier in read[:k]:
            if str(chosen[quantity]) == str(chosen[other]) and np.array_equal(spectrum.values, earlier.values):
                raise ValueError(f"the measured file {spectrum.source} holds one value column: "
                                 f"it cannot be both the {other} and the {quantity}; give a file with a "
                                 f"reflectance and a transmittance column, or the transmittance on its own "
                                 f"(--transmittance FILE, measured={{'reflectance': ..., 'transmittance': ...}})")
    return spectra


def _on_wavelengths(spectrum: MeasuredSpectrum, wavelengths: np.ndarray, uncertainty: Any
                    ) -> tuple[np.ndarray, np.ndarray]:
    low, high = spectrum.wavelengths[0], spectrum.wavelengths[-1]
    if wavelengths.min() < low - _MATCH_NM or wavelengths.max() > high + _MATCH_NM:
        raise ValueError(f"the fit's wavelengths {wavelengths.min():g}-{wavelengths.max():g} nm reach outside the "
                         f"measured {spectrum.quantity} of {spectrum.source} ({low:g}-{high:g} nm): never extrapolated")
    if uncertainty is not None:
        spectrum = spectrum.with_uncertainty(uncertainty)
    if spectrum.uncertainty is None:
        raise ValueError(f"the measured {spectrum.quantity} of {spectrum.source} has no uncertainty: a fit states "
                         "which parameters are consistent with the measurement, which needs it (an uncertainty "
                         f"column, or {spoken('measurement_uncertainty=...', '--uncertainty U')})")
    values = np.interp(wavelengths, spectrum.wavelengths, spectrum.values)
    error = np.interp(wavelengths, spectrum.wavelengths, spectrum.uncertainty)
    if not np.all(error > 0):
        raise ValueError(f"the measurement uncertainty of {spectrum.source} must be > 0 at every fitted wavelength")
    return values, error


def fit_problem(measured: Any, specimen: Any, parameters: Mapping[str, Any], *,
                quantities: Sequence[str] | None = None, wavelengths: Any = None,
                measurement_uncertainty: Any = None, defines: dict[str, Any] | None = None) -> FitProblem:
    """The checked :class:`FitProblem` (see the module docstring); ``ValueError`` naming what is wrong."""

    if not isinstance(parameters, Mapping) or not parameters:
        raise ValueError("a fit needs free parameters: name -> (lowest, highest), e.g. {'Cab': (10, 80)}")
    given_scene, label = _specimen_scene(specimen)
    scene = loaded(given_scene, defines)  # once: every forward reading takes this one
    bench = scene.bench
    known = known_parameters(bench.scene)
    names = tuple(parameters)
    keys = tuple(name if name.startswith("specimen.") or name.startswith(PREFIX) else f"specimen.{name}"
                 for name in names)
    own = specimen_of(bench.bsdf)  # the specimen protocol: its parameters' bounds and units, its wavelength range
    for name, key in zip(names, keys):
        if key not in known and key not in known.values():
            shorts = sorted(k[len("specimen."):] for k in known)
            listed = ", ".join(_declared(own, short) for short in shorts) or "none"
            raise ValueError(f"the specimen {label} has no parameter {name!r} (its parameters: {listed})")
    bounds = np.array([_bounds(name, parameters[name]) for name in names])
    start = current_values(bench, [known.get(key, key) for key in keys])
    parameter_space(bench, {key: list(row) for key, row in zip(keys, bounds)})  # the specimen checks both ends
    apply_point(bench, [known.get(key, key) for key in keys], start)
    for name, key, (low, high) in zip(names, keys, bounds):
        declared = own.parameter(key.rpartition(".")[2])
        if declared is not None and not (declared.within(low) and declared.within(high)):
            raise ValueError(f"the bounds of free parameter {name!r} ({low:g}, {high:g}) must lie within the "
                             f"specimen {label}'s {declared.lowest:g} <= {declared.name} <= {declared.highest:g} "
                             f"({declared.units})")
    spectra = _spectra(measured, quantities)
    first = next(iter(spectra.values()))
    grid = first.wavelengths if wavelengths is None else np.unique(np.asarray(wavelengths, dtype=np.float64).ravel())
    data_range = own.wavelength_range
    if data_range is not None and (grid.min() < data_range[0] or grid.max() > data_range[1]):
        raise ValueError(f"the measured spectrum reaches {grid.min():g}-{grid.max():g} nm, outside the data range of "
                         f"the specimen {label} ({data_range[0]:g}-{data_range[1]:g} nm): give wavelengths= inside it")
    values, errors = {}, {}
    for quantity, spectrum in spectra.items():
        values[quantity], errors[quantity] = _on_wavelengths(spectrum, grid, measurement_uncertainty)
    return FitProblem(loaded=scene, names=names, keys=keys, bounds=bounds, wavelengths=grid, measured=values,
                      uncertainty=errors, specimen=label,
                      fingerprints=frozenset({scene.fingerprint, scene_fingerprint(bench.scene, bench)}),
                      start=tuple(start))


def describe(problem: FitProblem) -> str:
    """The specimen as results name it (its scene's source)."""

    return str(problem.loaded.source["scene"])
