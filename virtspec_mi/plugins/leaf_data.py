"""
NPSG leaf data for the ABM-B / ABM-U specimens
==============================================

The ABM leaf models (``abm_b``, ``abm_u``) take their spectral data from the files of
the NPSG reference implementation (BSD-3-Clause, © 2010 Natural Phenomena Simulation
Group, University of Waterloo), shipped with the package under that licence
(``virtspec_mi/data/abm-npsg``, with its LICENSE and a provenance note). :func:`leaf_data_dir`
reads them from the directory given by the plugin parameter ``data_dir``, else by the
environment variable ``VIRTSPEC_LEAF_DATA`` (an override, e.g. for other data files of the
same layout), else from the shipped copy.

Every file holds 421 values, one per line, 400–2500 nm in 5 nm steps. :func:`load_leaf_data`
reads them and converts to SI units (specific absorption coefficients cm² g⁻¹ × 0.1 →
m² kg⁻¹, water absorption cm⁻¹ × 100 → m⁻¹); :func:`mesophyll_absorption` combines them
into the mesophyll absorption coefficient α(λ) (m⁻¹) and :func:`grid_lookup` gives the
reference's spectral lookup for any wavelength.

References
----------
Baranoski, G.V.G. (2006). Modeling the interaction of infrared radiation (750 to 2500 nm)
with bifacial and unifacial plant leaves. Remote Sens. Environ. 100, 335–347 (ABM-B/ABM-U).

NPSG reference C++ implementation of ABM-B and ABM-U (BSD-3, © 2010 NPSG),
https://github.com/turtlesoupy/ABM-U-and-ABM-B-CPP: ``abm_interfaces.cpp``
(``buildInterfaces``: α(λ) and the unit conversions), the ``data/`` files (names as in
:data:`LEAF_DATA_FILES`) and the sample leaves ``samples/lopex_0219_0220.json``
(soybean) and ``samples/lopex_0141_0142.json`` (corn).
"""

from __future__ import annotations

import functools
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

__all__ = [
    "ENV_VAR",
    "SHIPPED",
    "LEAF_DATA_FILES",
    "WAVELENGTH_RANGE",
    "GRID_STEP",
    "GRID",
    "LOOKUPS",
    "LeafData",
    "leaf_data_dir",
    "load_leaf_data",
    "mesophyll_absorption",
    "grid_lookup",
]

ENV_VAR: str = "VIRTSPEC_LEAF_DATA"
"""Environment variable naming a directory of NPSG leaf data files (overrides the shipped copy)."""

SHIPPED: Path = Path(__file__).resolve().parents[1] / "data" / "abm-npsg"
"""The NPSG leaf data shipped with the package (BSD-3-Clause, with its LICENSE)."""

WAVELENGTH_RANGE: tuple[float, float] = (400.0, 2500.0)
"""Wavelengths (nm) covered by the data, both ends included."""

GRID_STEP: float = 5.0
GRID: np.ndarray = np.arange(421) * GRID_STEP + WAVELENGTH_RANGE[0]
"""The data's wavelength grid, 400–2500 nm in 5 nm steps (421 values)."""

LOOKUPS: tuple[str, ...] = ("step", "linear")
"""Spectral lookups: ``step`` = the C++ reference's ⌊(λ − 400)/5⌋ (default), ``linear`` = MATLAB's."""

# quantity -> (file name, factor to SI, meaning)
LEAF_DATA_FILES: dict[str, tuple[str, float, str]] = {
    "chlorophyll": ("chloAB-DFA-400-2500.txt", 0.1, "specific absorption, chlorophyll a+b (cm2/g)"),
    "carotenoids": ("caro-PAS-400-2500.txt", 0.1, "specific absorption, carotenoids (cm2/g)"),
    "protein": ("protein400-2500.txt", 0.1, "specific absorption, protein (cm2/g)"),
    "cellulose": ("cellulose400-2500.txt", 0.1, "specific absorption, cellulose and lignin (cm2/g)"),
    "water": ("sacwH400-2500.txt", 100.0, "absorption coefficient of pure water (1/cm)"),
    "n_cuticle": ("rcH400-2500.txt", 1.0, "refractive index, cuticle / epicuticular wax"),
    "n_mesophyll": ("rmH400-2500.txt", 1.0, "refractive index, wet mesophyll cell wall"),
    "n_antidermal": ("raH400-2500.txt", 1.0, "refractive index, antidermal wall"),
}


@dataclass(frozen=True)
class LeafData:
    """
    The NPSG spectral data on :data:`GRID`, in SI units.

    ``chlorophyll``, ``carotenoids``, ``protein`` and ``cellulose`` are specific absorption
    coefficients in m² kg⁻¹ (chlorophyll a and b share one; lignin uses cellulose's);
    ``water`` is the absorption coefficient of pure liquid water in m⁻¹; ``n_*`` are
    refractive indices.
    """

    directory: Path
    chlorophyll: np.ndarray
    carotenoids: np.ndarray
    protein: np.ndarray
    cellulose: np.ndarray
    water: np.ndarray
    n_cuticle: np.ndarray
    n_mesophyll: np.ndarray
    n_antidermal: np.ndarray


def _needed() -> str:
    names = ", ".join(name for name, _, _ in LEAF_DATA_FILES.values())
    return f"{names} (BSD-3: the data/ folder of github.com/turtlesoupy/ABM-U-and-ABM-B-CPP)"


def leaf_data_dir(data_dir: str | os.PathLike | None = None) -> Path:
    """
    The directory holding the NPSG leaf data: ``data_dir`` if given (not empty), else
    ``$VIRTSPEC_LEAF_DATA`` if set, else the shipped copy (:data:`SHIPPED`). Raises
    ``FileNotFoundError`` (one line) naming the files needed and where they were looked for
    when the directory or a file is missing.
    """

    if data_dir not in (None, ""):
        directory, origin = Path(data_dir), "the parameter data_dir"
    elif os.environ.get(ENV_VAR):
        directory, origin = Path(os.environ[ENV_VAR]), f"${ENV_VAR}"
    else:
        directory, origin = SHIPPED, "the data shipped with virtspec-mi (an incomplete installation)"
    if not directory.is_dir():
        raise FileNotFoundError(
            f"ABM leaf data not found: directory '{directory}' (from {origin}) does not exist; point "
            f"{ENV_VAR} (or the BSDF parameter data_dir) at a directory holding the NPSG files {_needed()}"
        )
    missing = [name for name, _, _ in LEAF_DATA_FILES.values() if not (directory / name).is_file()]
    if missing:
        raise FileNotFoundError(
            f"ABM leaf data not found: directory '{directory}' (from {origin}) lacks "
            f"{', '.join(missing)}; point {ENV_VAR} (or the BSDF parameter data_dir) at a "
            f"directory holding the NPSG files {_needed()}"
        )
    return directory


@functools.lru_cache(maxsize=8)
def _load(directory: Path) -> LeafData:
    values = {}
    for quantity, (name, factor, meaning) in LEAF_DATA_FILES.items():
        path = directory / name
        try:
            data = np.loadtxt(path, dtype=np.float64, ndmin=1)
        except ValueError as error:
            raise ValueError(f"leaf data file {path} ({meaning}) is not one number per line: {error}") from None
        if data.shape != GRID.shape or not np.all(np.isfinite(data)):
            raise ValueError(
                f"leaf data file {path} ({meaning}) must hold {GRID.size} finite values, "
                f"400-2500 nm at 5 nm (got {data.size})"
            )
        values[quantity] = data * factor
    return LeafData(directory=directory, **values)


def load_leaf_data(data_dir: str | os.PathLike | None = None) -> LeafData:
    """Read (once per directory) and convert the NPSG files of :func:`leaf_data_dir`."""

    return _load(leaf_data_dir(data_dir).resolve())


def mesophyll_absorption(
    data: LeafData,
    *,
    chlorophyll_a: float,
    chlorophyll_b: float,
    carotenoids: float,
    protein: float,
    cellulose: float,
    lignin: float,
) -> np.ndarray:
    """
    Absorption coefficient α(λ) of the mesophyll on :data:`GRID`, in m⁻¹.

    α = (c_a + c_b) σ_ab + c_car σ_car + c_p σ_p + (c_cel + c_lig) σ_cel + μ_w, with the
    concentrations c in kg m⁻³ of mesophyll (= 1000 × the NPSG form's g cm⁻³). Pure
    water is added at full strength (the model has no water-content parameter).

    References
    ----------
    Baranoski (2006); NPSG reference C++, ``abm_interfaces.cpp`` (``buildInterfaces``).
    """

    return (
        (chlorophyll_a + chlorophyll_b) * data.chlorophyll
        + carotenoids * data.carotenoids
        + protein * data.protein
        + (cellulose + lignin) * data.cellulose
        + data.water
    )


def grid_lookup(values: np.ndarray, wavelengths: np.ndarray | float, lookup: str = "step") -> np.ndarray:
    """
    ``values`` (on :data:`GRID`) at ``wavelengths`` (nm, within :data:`WAVELENGTH_RANGE`).

    ``step``: the value at ⌊(λ − 400)/5⌋ (the C++ reference; 551 nm reads the 550 nm
    value); ``linear``: linear interpolation (the MATLAB reference).
    """

    if lookup not in LOOKUPS:
        raise ValueError(f"lookup must be one of {', '.join(LOOKUPS)} (got {lookup!r})")
    x = (np.asarray(wavelengths, dtype=np.float64) - WAVELENGTH_RANGE[0]) / GRID_STEP
    if lookup == "step":
        return values[np.clip(np.floor(x), 0, GRID.size - 1).astype(np.int64)]
    return np.interp(np.asarray(wavelengths, dtype=np.float64), GRID, values)
