"""
Spectral bands: a sensor's response applied to a spectrum
=========================================================

A band's value is the response-weighted mean of a spectrum,

    q_B = ∫ r(λ) q(λ) dλ / ∫ r(λ) dλ,

taken here on a wavelength grid by the trapezoid rule (weights wₖ ≥ 0, Σₖ wₖ = 1), so a
band is a :class:`~virtspec_mi.budgets.functionals.Functional` whose cost
is that of one reading (Σ|wₖ| = 1). The certificate is that of the quadrature on the
grid (:attr:`Band.step`); the grid is fine (1 nm by default) because more wavelengths
cost no more rays.

- :func:`band`: from a two-column file (wavelength in nm, response; ``#`` comments, comma
  or blank separated), a dict ``{wavelength: response}``, a pair of band edges
  ``(low, high)`` (a rectangular band) or a name of :data:`SENTINEL_2`.
- :data:`SENTINEL_2`: the Sentinel-2A MSI bands as **rectangular bands** from their
  published centre wavelengths and bandwidths (centre ± width/2) — an approximation of
  the measured spectral response functions, stated as such; pass the mission's response
  file to :func:`band` for the real one.

References
----------
ESA (2015). *Sentinel-2 User Handbook*, ESA Standard Document, Issue 1 Rev 2, Table 1
(Sentinel-2A MSI central wavelengths and bandwidths).
"""

from __future__ import annotations

import math

import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from virtspec_mi.budgets.functionals import Functional

__all__ = ["Band", "band", "SENTINEL_2", "quadrature_weights"]

SENTINEL_2: dict[str, tuple[float, float]] = {
    # name: (centre nm, bandwidth nm), Sentinel-2A MSI (Sentinel-2 User Handbook, Table 1)
    "B01": (442.7, 21.0), "B02": (492.4, 66.0), "B03": (559.8, 36.0), "B04": (664.6, 31.0),
    "B05": (704.1, 15.0), "B06": (740.5, 15.0), "B07": (782.8, 20.0), "B08": (832.8, 106.0),
    "B8A": (864.7, 21.0), "B09": (945.1, 20.0), "B11": (1613.7, 91.0), "B12": (2202.4, 175.0),
}
"""Sentinel-2A MSI bands, centre and bandwidth in nm: rectangular bands centre ± width/2 (an approximation)."""


@dataclass(frozen=True)
class Band:
    """A band: ``response`` r(λ) at ``wavelengths`` (nm, increasing); ``name``; ``source`` in words."""

    name: str
    wavelengths: np.ndarray
    response: np.ndarray
    source: str = ""

    @property
    def edges(self) -> tuple[float, float]:
        """The first and last wavelength of non-zero response."""

        used = self.wavelengths[self.response != 0]
        return float(used[0]), float(used[-1])

    def functional(self, quantity: str = "reflectance") -> Functional:
        """The band as a functional of ``quantity``: trapezoid weights of r, normalised to Σ = 1."""

        weights = quadrature_weights(self.wavelengths) * self.response
        used = weights != 0
        low, high = self.edges
        return Functional(f"band_{self.name}", self.wavelengths[used], weights[used] / weights.sum(), quantity, "1",
                          f"{quantity} in band {self.name} ({low:g}-{high:g} nm, {self.source})")


def quadrature_weights(wavelengths: np.ndarray) -> np.ndarray:
    """Trapezoid weights of ``wavelengths`` (nm, increasing; one wavelength: weight 1)."""

    grid = np.asarray(wavelengths, dtype=np.float64)
    if len(grid) == 1:
        return np.ones(1)
    gaps = np.diff(grid)
    return np.concatenate([[gaps[0] / 2], (gaps[:-1] + gaps[1:]) / 2, [gaps[-1] / 2]])


def _nm(what: str, value: Any) -> float:
    """A number of a band (a wavelength, an edge, a response): text, booleans and NaN refused, naming ``what``."""

    if isinstance(value, (str, bytes, bool, np.bool_)):
        raise ValueError(f"{what} must be a number (got {value!r}); a band is a Sentinel-2 name, edges (low, high) in "
                         "nm, a dict {wavelength nm: response} or a two-column file")
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{what} must be a number (got {value!r})") from None
    if not math.isfinite(number):
        raise ValueError(f"{what} must be a finite number (got {value!r})")
    return number


def band(response: Any, name: str | None = None, step: float = 1.0) -> Band:
    """
    A :class:`Band` from ``response``: a name of :data:`SENTINEL_2` (``"B04"``, or
    ``"S2A_B04"``), a pair of edges ``(low, high)`` in nm (rectangular, sampled every
    ``step`` nm, edges included; or written ``"650-680"``), a dict ``{wavelength nm: response}`` or the path of a
    two-column text file (wavelength nm, response).
    """

    if not step > 0:
        raise ValueError(f"step must be a positive number of nm (got {step!r})")
    if isinstance(response, str) and response.upper().removeprefix("S2A_").removeprefix("S2_") in SENTINEL_2:
        key = response.upper().removeprefix("S2A_").removeprefix("S2_")
        centre, width = SENTINEL_2[key]
        made = _rectangle(centre - width / 2, centre + width / 2, step)
        return Band(name or key, made[0], made[1], "Sentinel-2A MSI, rectangular from centre and bandwidth")
    if isinstance(response, (tuple, list)) and len(response) == 2 and all(np.isscalar(v) for v in response):
        low, high = (_nm(f"band edge {which}", v) for which, v in zip(("low", "high"), response))
        made = _rectangle(low, high, step)
        return Band(name or f"{low:g}-{high:g}", made[0], made[1], "rectangular")
    if isinstance(response, Mapping):
        pairs = sorted((_nm("a response dict's wavelength", k), _nm(f"the response at {k!r} nm", v))
                       for k, v in response.items())
        return _checked(name or "band", np.array([p[0] for p in pairs]), np.array([p[1] for p in pairs]), "given")
    if isinstance(response, str) and not Path(response).is_file() and _edges(response) is not None:
        return band(_edges(response), name, step)  # "650-680": edges in nm, as a text writes them
    if isinstance(response, (str, os.PathLike)):
        path = Path(response)
        if not path.is_file():
            raise ValueError(f"response must be a Sentinel-2 band ({', '.join(SENTINEL_2)}), edges (low, high), a "
                             f"dict or a two-column file; no file {str(path)!r}")
        try:
            table = np.loadtxt(path, comments="#", delimiter="," if "," in path.read_text() else None, ndmin=2)
        except ValueError as error:
            raise ValueError(f"response file {path}: two numeric columns (wavelength nm, response) ({error})") from None
        if table.shape[1] != 2:
            raise ValueError(f"response file {path}: two columns (wavelength nm, response), got {table.shape[1]}")
        order = np.argsort(table[:, 0])
        return _checked(name or path.stem, table[order, 0], table[order, 1], f"file {path.name}")
    raise ValueError(f"response must be a Sentinel-2 band ({', '.join(SENTINEL_2)}), edges (low, high) in nm, a dict "
                     f"{{wavelength: response}} or a two-column file (got {response!r})")


def _edges(text: str) -> tuple[float, float] | None:
    """``(650.0, 680.0)`` of ``"650-680"``; ``None`` for a text that is not two numbers joined by ``-``."""

    low, sep, high = text.partition("-")
    try:
        return (float(low), float(high)) if sep else None
    except ValueError:
        return None


def _rectangle(low: float, high: float, step: float) -> tuple[np.ndarray, np.ndarray]:
    if not (np.isfinite(low) and np.isfinite(high) and 0 < low < high):
        raise ValueError(f"band edges must be 0 < low < high nm (got {low:g}, {high:g})")
    inner = np.arange(np.ceil(low / step) * step, high, step)
    grid = np.unique(np.concatenate([[low], inner[inner > low], [high]]))
    return grid, np.ones(len(grid))


def _checked(name: str, wavelengths: np.ndarray, response: np.ndarray, source: str) -> Band:
    if len(wavelengths) < 1 or len(np.unique(wavelengths)) != len(wavelengths):
        raise ValueError(f"band {name}: response wavelengths must be distinct (got {len(wavelengths)})")
    if np.any(response < 0) or not np.any(response > 0) or not np.all(np.isfinite(response)):
        raise ValueError(f"band {name}: the response must be finite, >= 0 and somewhere > 0")
    if np.any(wavelengths <= 0):
        raise ValueError(f"band {name}: wavelengths must be positive nm")
    return Band(name, wavelengths, response, source)
