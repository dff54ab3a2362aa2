"""
Sweep results as files: xarray / NetCDF, CSV, JSON and colour-science CSV spectra
=================================================================================

- :func:`to_dataset` / :func:`from_dataset`: a :class:`~virtspec_mi.sweeps.SweepResult`
  as an ``xarray.Dataset`` with dims ``wavelength`` (nm) and ``theta_i`` (degrees):
  variables ``reflectance``, ``transmittance``, ``absorptance`` (float64) and the exact
  counts ``reflected``, ``transmitted``, ``absorbed``, ``weight_violations``,
  ``capped`` and ``rays`` (int64), and each quantity's Clopper–Pearson interval at the
  sweep's δ (``reflectance_lower`` / ``reflectance_upper`` …, derived from the counts;
  also CSV columns and JSON keys); attributes hold every setting (μ, δ, bound, beam,
  sampling, seed, φi), the geometry (r₁, r₂, D), the scene fingerprint, the package
  version, the seconds, ``wavelength_independent`` and the whole settings as JSON.
- :func:`write_sweep` / :func:`read_sweep` by suffix: ``.nc`` (NetCDF-4 through
  ``netCDF4``), ``.csv`` (one row per reading, one ``# virtspec-mi sweep {json}``
  header line with the attributes) and ``.json`` (one object, 2-D lists indexed
  [wavelength][theta_i]). Each round-trips exactly.
- :func:`write_spectra_csv` / :func:`read_spectra_csv`: reflectance, transmittance
  and absorptance at one θi in colour-science's CSV spectral format
  (``colour.write_sds_to_csv_file``).

References
----------
Baranoski et al. (2001), eq. (2); colour-science ``colour.io`` CSV spectral files.
"""

from __future__ import annotations

import csv
import io
import json
import os
from pathlib import Path
from typing import Any

import numpy as np

__all__ = [
    "SUFFIXES",
    "to_dataset",
    "from_dataset",
    "result_format",
    "csv_text",
    "write_sweep",
    "read_sweep",
    "write_spectra_csv",
    "read_spectra_csv",
]

SUFFIXES: tuple[str, ...] = (".nc", ".csv", ".json")
"""Result file formats understood by :func:`write_sweep` and :func:`read_sweep`."""

_COUNTS = ("reflected", "transmitted", "absorbed", "weight_violations", "capped", "rays")
_QUANTITIES = ("reflectance", "transmittance", "absorptance")
_BOUNDS = ("lower", "upper")  # Clopper–Pearson interval columns: <quantity>_lower, <quantity>_upper


def _intervals(result: Any) -> dict[str, np.ndarray]:
    """Each quantity's Clopper–Pearson bounds per reading, by column name (derived, never read back)."""

    return {f"{q}_{end}": values for q in _QUANTITIES for end, values in zip(_BOUNDS, result.interval(q))}
_CSV_HEADER = "# virtspec-mi sweep "


def _metadata(result: Any) -> dict[str, Any]:
    """Plain-data attributes of a sweep (all settings, geometry, provenance)."""

    from dataclasses import asdict

    s = result.settings
    return {
        "mu": s.mu,
        "delta": s.delta,
        "bound": s.bound,
        "beam": s.beam,
        "sampling": s.sampling,
        "seed": s.seed,
        "phi_i": s.phi_i,
        "emitter_radius": result.geometry.emitter_radius,
        "specimen_radius": result.geometry.specimen_radius,
        "distance": result.geometry.distance,
        "seconds": result.seconds,
        "scene": result.scene,
        "wavelength_independent": int(result.wavelength_independent),
        "version": result.version,
        "settings_json": json.dumps(asdict(s)),
    }


def _result(meta: dict[str, Any], wavelengths: Any, theta_i: Any, counts: dict[str, np.ndarray]) -> Any:
    from virtspec_mi.geometry import InstrumentGeometry
    from virtspec_mi.settings import Settings
    from virtspec_mi.sweeps import SweepResult

    try:
        settings = Settings(**json.loads(meta["settings_json"]))
        geometry = InstrumentGeometry(float(meta["emitter_radius"]), float(meta["specimen_radius"]),
                                      float(meta["distance"]))
        return SweepResult(
            wavelengths=np.asarray(wavelengths, dtype=np.float64),
            theta_i=np.asarray(theta_i, dtype=np.float64),
            **{name: np.asarray(counts[name], dtype=np.int64)
               for name in ("reflected", "transmitted", "weight_violations", "capped", "rays")},
            seconds=float(meta["seconds"]),
            settings=settings,
            geometry=geometry,
            scene=str(meta["scene"]),
            wavelength_independent=bool(int(meta["wavelength_independent"])),
            version=str(meta["version"]),
        )
    except (KeyError, TypeError, ValueError) as error:
        raise ValueError(f"not a virtspec-mi sweep file (missing or bad {error})") from None


def to_dataset(result: Any) -> Any:
    """A sweep as an ``xarray.Dataset`` over (wavelength, theta_i) with all settings as attributes."""

    import xarray as xr

    dims = ("wavelength", "theta_i")
    variables = {name: (dims, np.asarray(result.quantity(name), dtype=np.float64)) for name in _QUANTITIES}
    variables.update({name: (dims, np.asarray(values, dtype=np.float64)) for name, values in _intervals(result).items()})
    variables.update({name: (dims, np.asarray(getattr(result, name), dtype=np.int64)) for name in _COUNTS})
    dataset = xr.Dataset(
        variables,
        coords={"wavelength": ("wavelength", np.asarray(result.wavelengths, dtype=np.float64)),
                "theta_i": ("theta_i", np.asarray(result.theta_i, dtype=np.float64))},
        attrs=_metadata(result),
    )
    dataset["wavelength"].attrs["units"] = "nm"
    dataset["theta_i"].attrs["units"] = "degree"
    for name in _QUANTITIES:
        dataset[name].attrs["certified_tolerance_mu"] = result.settings.mu
        for end in _BOUNDS:
            dataset[f"{name}_{end}"].attrs["clopper_pearson_delta"] = result.interval_delta
    return dataset


def from_dataset(dataset: Any) -> Any:
    """The :class:`~virtspec_mi.sweeps.SweepResult` of a dataset written by :func:`to_dataset`."""

    counts = {name: dataset[name].values for name in _COUNTS if name in dataset}
    return _result(dict(dataset.attrs), dataset["wavelength"].values, dataset["theta_i"].values, counts)


def write_sweep(result: Any, path: str | os.PathLike) -> Path:
    """Write a sweep to ``path``; the suffix picks the format (``.nc``, ``.csv``, ``.json``)."""

    path = Path(path)
    suffix = result_format(path)
    if suffix == ".nc":
        to_dataset(result).to_netcdf(path, engine="netcdf4")
    elif suffix == ".json":
        data = {**_metadata(result), "wavelength": result.wavelengths.tolist(), "theta_i": result.theta_i.tolist()}
        data.update({name: result.quantity(name).tolist() for name in _QUANTITIES})
        data.update({name: values.tolist() for name, values in _intervals(result).items()})
        data.update({name: getattr(result, name).tolist() for name in _COUNTS})
        path.write_text(json.dumps(data, indent=1))
    else:
        path.write_text(csv_text(result))
    return path


def csv_text(result: Any) -> str:
    """The CSV form of a sweep: the attribute header line, then one row per (wavelength, θi)."""

    buffer = io.StringIO()
    buffer.write(_CSV_HEADER + json.dumps(_metadata(result)) + "\n")
    writer = csv.writer(buffer, lineterminator="\n")
    intervals = _intervals(result)
    writer.writerow(["wavelength", "theta_i", *_QUANTITIES, *intervals, *_COUNTS])
    for i, wavelength in enumerate(result.wavelengths):
        for j, theta in enumerate(result.theta_i):
            writer.writerow([repr(float(wavelength)), repr(float(theta)),
                             *(repr(float(result.quantity(q)[i, j])) for q in _QUANTITIES),
                             *(repr(float(values[i, j])) for values in intervals.values()),
                             *(int(getattr(result, c)[i, j]) for c in _COUNTS)])
    return buffer.getvalue()


def read_sweep(path: str | os.PathLike) -> Any:
    """Read a sweep written by :func:`write_sweep` (``.nc``, ``.csv`` or ``.json``)."""

    path = Path(path)
    suffix = result_format(path)
    if not path.is_file():
        raise ValueError(f"sweep file not found: {path}")
    if suffix == ".nc":
        import xarray as xr

        try:
            with xr.open_dataset(path, engine="netcdf4") as dataset:
                return from_dataset(dataset.load())
        except OSError as error:
            raise ValueError(f"could not read NetCDF sweep {path}: {error}") from None
    text = path.read_text()
    if suffix == ".json":
        try:
            data = json.loads(text)
        except json.JSONDecodeError as error:
            raise ValueError(f"sweep file {path} is not valid JSON: {error}") from None
        if not isinstance(data, dict):
            raise ValueError(f"not a virtspec-mi sweep file: {path}")
        return _result(data, data.get("wavelength"), data.get("theta_i"),
                       {name: data.get(name) for name in _COUNTS})
    lines = text.splitlines()
    if not lines or not lines[0].startswith(_CSV_HEADER):
        raise ValueError(f"not a virtspec-mi sweep CSV (first line must start with {_CSV_HEADER.strip()!r}): {path}")
    meta = json.loads(lines[0][len(_CSV_HEADER):])
    rows = list(csv.DictReader(lines[1:]))
    wavelengths = list(dict.fromkeys(float(row["wavelength"]) for row in rows))
    angles = list(dict.fromkeys(float(row["theta_i"]) for row in rows))
    counts = {name: np.zeros((len(wavelengths), len(angles)), dtype=np.int64) for name in _COUNTS}
    for row in rows:
        i, j = wavelengths.index(float(row["wavelength"])), angles.index(float(row["theta_i"]))
        for name in _COUNTS:
            counts[name][i, j] = int(row[name])
    return _result(meta, wavelengths, angles, counts)


def write_spectra_csv(result: Any, path: str | os.PathLike, theta_i: float | None = None) -> Path:
    """R, T and A at one θi in colour-science's CSV spectral format (wavelength column + one per quantity)."""

    import colour

    msds = result.to_msds(theta_i)
    sds = {label: colour.SpectralDistribution(msds.values[:, k], msds.wavelengths, name=label)
           for k, label in enumerate(msds.labels)}
    colour.write_sds_to_csv_file(sds, str(path))
    return Path(path)


def read_spectra_csv(path: str | os.PathLike) -> dict[str, Any]:
    """The spectra of a colour-science CSV spectral file, by column name (``colour.SpectralDistribution``)."""

    import colour

    path = Path(path)
    if not path.is_file():
        raise ValueError(f"spectra file not found: {path}")
    try:
        return dict(colour.read_sds_from_csv_file(str(path)))
    except (ValueError, KeyError, IndexError) as error:
        raise ValueError(f"could not read colour-science CSV spectra {path}: {error}") from None


def result_format(path: str | os.PathLike) -> str:
    """The result format of ``path`` by its suffix (``.nc``, ``.csv``, ``.json``), else ``ValueError``."""

    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in SUFFIXES:
        raise ValueError(f"out must end in one of {', '.join(SUFFIXES)} (got {path.name!r})")
    return suffix
