"""
Optimal spectral windows: each parameter estimated where the spectrum is most sensitive to it
==============================================================================================

A leaf's constituents act on different parts of its spectrum, and a loss over the whole
400–2500 nm range lets errors of the model where one constituent dominates bias another's
estimate. Féret et al. (2019, 2021) and Spafford et al. (2021) therefore invert PROSPECT
**one constituent at a time, each on its own optimal spectral domain** — found by testing
every sub-domain on measured leaves — and keep from each inversion only that constituent's
value. :data:`OPTIMAL_WINDOWS` holds their domains for reflectance and transmittance together
(Spafford et al. 2021; Féret et al. 2021; as the R package ``prospect`` lists them): chlorophylls
700–720 nm, carotenoids 520–560 nm, anthocyanins 400–800 nm, water (EWT) and dry matter (LMA)
1700–2400 nm. (PROSPECT-PRO's proteins, 2100–2139 and 2160–2179 nm, and carbon-based
constituents, nine bands from 1480 to 2399 nm, have no specimen here.)

How :func:`virtspec_mi.applications.fitting.fit` uses them (``loss="windows"``): for each free
parameter with a window, the fit's refinement (its staged Nelder–Mead from the table's best
point) runs on the **chi-square restricted to that window's wavelengths**, with *all* the free
parameters free — as Féret et al. fit the constituents that act in a window together with the
structure N and keep only the target's value — and the target parameter's value is kept. Free
parameters without a window (``N``, ``thickness`` …) take their value from one more refinement
on the full range (``chi2``). The combination is the estimate, read at μ*. The loss reported for
any candidate is the mean over the windows of each window's chi-square.

The confidence set is untouched: it is the set of candidates whose certified spectrum is
consistent with the measurement at **every** fitted wavelength (:func:`.inversion.consistency`),
whatever loss led the search. The windows choose the estimate, not what counts as consistent.

Windows are given as ``{name: (lowest, highest)}`` (nm) or several intervals per name
(``{"Cab": [(700, 720), (740, 750)]}``, or ``"700:720"``); a given window must lie inside the
fitted wavelengths and hold at least one of them. The published windows are used for free
parameters named as PROSPECT-D's (``Cab``, ``Car``, ``Anth``, ``Cw``, ``Cm``) that are not given,
cut to the fitted range.

References
----------
J.-B. Féret, G. le Maire, S. Jay, et al. (2019), *Estimating leaf mass per area and
equivalent water thickness based on leaf optical properties: potential and limitations of
physical modeling and machine learning*, Remote Sens. Environ. 222, 133–143,
doi:10.1016/j.rse.2018.11.002 (the 1700–2400 nm domain for EWT and LMA).
J.-B. Féret, K. Berger, F. de Boissieu, Z. Malenovský (2021), *PROSPECT-PRO for estimating
content of nitrogen-containing leaf proteins and other carbon-based constituents*, Remote
Sens. Environ. 252, 112173.
L. Spafford, G. le Maire, A. MacDougall, F. de Boissieu, J.-B. Féret (2021), *Spectral
subdomains and prior estimation of leaf structure improves PROSPECT inversion on reflectance
or transmittance alone*, Remote Sens. Environ. 252, 112176.
"""

from __future__ import annotations

import math
from typing import Any, Callable, Mapping

import numpy as np

from virtspec_mi.applications.fitting.forward import Reading
from virtspec_mi.base.surface import spoken
from virtspec_mi.applications.fitting.problem import FitProblem
from virtspec_mi.base.checks import number

__all__ = ["OPTIMAL_WINDOWS", "FitWindows", "fit_windows", "window_loss"]

OPTIMAL_WINDOWS: dict[str, tuple[tuple[float, float], ...]] = {
    "Cab": ((700.0, 720.0),),
    "Car": ((520.0, 560.0),),
    "Anth": ((400.0, 800.0),),
    "Cw": ((1700.0, 2400.0),),
    "Cm": ((1700.0, 2400.0),),
}
"""The published optimal domains (nm) of PROSPECT-D's constituents, reflectance and transmittance together."""

_EDGE_NM = 1e-9


class FitWindows:
    """The windows of one fit: free parameter index → mask over the fit's wavelengths, and how they read."""

    def __init__(self, masks: dict[int, np.ndarray], text: dict[int, str]) -> None:
        self.masks = masks
        self.text = text

    def describe(self, names: tuple[str, ...]) -> str:
        """``windows (Cab 700-720 nm, Cm 1700-2400 nm)``: the loss's name as results record it."""

        return "windows (" + ", ".join(f"{names[i]} {self.text[i]}" for i in sorted(self.masks)) + ")"

    def loss(self) -> Callable[[Reading, FitProblem], float]:
        """The mean over the windows of each window's chi-square (the loss results report)."""

        losses = [window_loss(mask) for mask in self.masks.values()]
        return lambda reading, problem: float(np.mean([f(reading, problem) for f in losses]))


def window_loss(mask: np.ndarray) -> Callable[[Reading, FitProblem], float]:
    """The chi-square (mean squared residual in units of the uncertainty) over the wavelengths of ``mask``."""

    def loss(reading: Reading, problem: FitProblem) -> float:
        inside = mask if reading.subset is None else mask[reading.subset]  # over the reading's own wavelengths
        chosen = inside if reading.subset is None else reading.subset & mask
        return float(np.mean([np.mean(((reading.predicted[q][inside] - problem.measured[q][chosen])
                                       / problem.uncertainty[q][chosen]) ** 2) for q in problem.quantities]))

    return loss


def _intervals(name: str, value: Any) -> list[tuple[float, float]]:
    if isinstance(value, str):
        value = [part.split(":") for part in value.split(",")]
    elif isinstance(value, (tuple, list)) and len(value) == 2 and not isinstance(value[0], (tuple, list, str)):
        value = [value]
    if not isinstance(value, (tuple, list)) or not value:
        raise ValueError(f"the window of {name!r} must be (lowest, highest) in nm, or a list of them (got {value!r})")
    found = []
    for pair in value:
        if not isinstance(pair, (tuple, list)) or len(pair) != 2:
            raise ValueError(f"the window of {name!r} must be (lowest, highest) in nm, or a list of them "
                             f"(got {value!r})")
        low, high = number(f"window of {name} lowest", pair[0]), number(f"window of {name} highest", pair[1])
        if not (math.isfinite(low) and math.isfinite(high) and low < high):
            raise ValueError(f"the window of {name!r} must be finite with lowest < highest (got {low:g}, {high:g})")
        found.append((low, high))
    return found


def _short(name: str) -> str:
    return name.rsplit(".", 1)[-1]


def fit_windows(windows: Mapping[str, Any] | None, names: tuple[str, ...], wavelengths: np.ndarray) -> FitWindows:
    """
    The checked windows of a fit over the free parameters ``names`` on the fitted ``wavelengths``
    (see the module docstring); ``ValueError`` naming what is wrong.
    """

    if windows is not None and not isinstance(windows, Mapping):
        raise ValueError(f"windows must map free parameters to (lowest, highest) in nm (got {windows!r})")
    given = dict(windows or {})
    lowest, highest = float(wavelengths.min()), float(wavelengths.max())
    index = {}
    for i, name in enumerate(names):
        index[name] = i
        index.setdefault(_short(name), i)
    masks: dict[int, np.ndarray] = {}
    text: dict[int, str] = {}
    for name, value in given.items():
        if name not in index:
            raise ValueError(f"windows: {name!r} is not a free parameter of this fit (free: {', '.join(names)})")
        intervals = _intervals(name, value)
        for low, high in intervals:
            if low < lowest - _EDGE_NM or high > highest + _EDGE_NM:
                raise ValueError(f"the window of {name!r}, {low:g}-{high:g} nm, reaches outside the fitted "
                                 f"wavelengths ({lowest:g}-{highest:g} nm)")
        masks[index[name]], text[index[name]] = _mask(name, intervals, wavelengths)
    for i, name in enumerate(names):
        published = OPTIMAL_WINDOWS.get(_short(name))
        if i in masks or published is None:
            continue
        cut = [(max(low, lowest), min(high, highest)) for low, high in published if high >= lowest and low <= highest]
        if not cut:
            raise ValueError(f"the published window of {name!r} ({_text(published)}) lies outside the fitted "
                             f"wavelengths ({lowest:g}-{highest:g} nm): give "
                             + spoken(f"windows={{{_short(name)!r}: ...}}", f"--window {_short(name)}=LOWEST:HIGHEST")
                             + " or fit another range")
        masks[i], text[i] = _mask(name, cut, wavelengths)
    if not masks:
        loss = spoken("loss='windows'", "--loss windows")
        window = spoken("windows={name: (lowest, highest)}", "--window NAME=LOWEST:HIGHEST")
        raise ValueError(f"{loss} needs a window for at least one free parameter ({', '.join(names)}): give {window} "
                         f"(published windows: {', '.join(OPTIMAL_WINDOWS)})")
    return FitWindows(masks, text)


def _text(intervals: Any) -> str:
    return ", ".join(f"{low:g}-{high:g}" for low, high in intervals) + " nm"


def _mask(name: str, intervals: list[tuple[float, float]], wavelengths: np.ndarray) -> tuple[np.ndarray, str]:
    mask = np.zeros(len(wavelengths), dtype=bool)
    for low, high in intervals:
        mask |= (wavelengths >= low - _EDGE_NM) & (wavelengths <= high + _EDGE_NM)
    if not mask.any():
        raise ValueError(f"the window of {name!r} ({_text(intervals)}) holds none of the fitted wavelengths: "
                         "fit wavelengths inside it")
    return mask, _text(intervals)
