"""
The PROSPECT-D leaf model (NumPy): reflectance and transmittance of a pile of N plates
======================================================================================

PROSPECT represents a leaf as N homogeneous absorbing plates separated by N − 1 air
spaces (Jacquemoud & Baret 1990). The first plate's surfaces reflect as a dielectric of
refractive index n(λ) lit over a cone of half-angle α = 40° (its top) and
isotropically (inside the leaf), with the transmissivity ``tav`` of Stern (1964),
Allen (1973) averaged over the incidence directions; its absorption is the plate's
transmission of isotropic light, τ = (1 − k) e^(−k) + k² E₁(k), with
k(λ) = Σ C_i K_i(λ) / N (Allen et al. 1969). The remaining N − 1 plates are combined
by Stokes' (1862) formulae for a pile of plates, N real. PROSPECT-D (Féret et al. 2017)
has seven absorbers: chlorophylls a + b (``Cab``, µg cm⁻²), carotenoids (``Car``, µg
cm⁻²), anthocyanins (``Anth``, µg cm⁻²), brown pigments (``Cbrown``, arbitrary units),
equivalent water thickness (``Cw``, cm) and leaf mass per area (``Cm``, g cm⁻²).

Everything is vectorised: :func:`prospect_d` takes parameters as numbers or arrays of
one shape P and returns R and T of shape P + (n_λ,).

The coefficients
----------------
The specific absorption coefficients K_i(λ) and the refractive index n(λ) (400–2500 nm,
1 nm) are the model's data. virtspec-mi **ships them** (:data:`SHIPPED`,
``virtspec_mi/data/prospect-d/``): Féret et al.'s (2017) PROSPECT-D coefficients, which
their author distributes under the MIT licence (the R package ``prospect``); the folder
holds that licence and a README with the copy's provenance (the PyPI package ``prosail``
2.0.5). :func:`prospect_coefficients` reads them, in this order, from

1. the ``source`` given (a path to a whitespace- or comma-separated table of eight columns:
   wavelength in nm, n, K_Cab, K_Car, K_Anth, K_Cbrown, K_Cw, K_Cm; ``#`` comments —
   the layout of ``dataSpec_PDB.m``, Féret et al. 2017, as the shipped table);
2. the environment variable ``VIRTSPEC_PROSPECT_DATA`` (such a path);
3. the shipped table :data:`SHIPPED`;

and raises :class:`ProspectDataError` when the table it reads is missing or malformed.

References
----------
S. Jacquemoud, F. Baret (1990), *PROSPECT: a model of leaf optical properties
spectra*, Remote Sens. Environ. 34, 75–91 (eqs. 1–7, the plate and the pile).
J.-B. Féret, A.A. Gitelson, S.D. Noble, S. Jacquemoud (2017), *PROSPECT-D: towards
modeling leaf optical properties through a complete lifecycle*, Remote Sens. Environ.
193, 204–215.
G.G. Stokes (1862), *On the intensity of the light reflected from or transmitted
through a pile of plates*, Proc. R. Soc. Lond. 11, 545–556.
F. Stern (1964), *Transmission of isotropic radiation across an interface between two
dielectrics*, Appl. Opt. 3(1), 111–113; W.A. Allen (1973), J. Opt. Soc. Am. 63(6),
664–666 (``tav``).
W.A. Allen, H.W. Gausman, A.J. Richardson, J.R. Thomas (1969), *Interaction of
isotropic light with a compact plant leaf*, J. Opt. Soc. Am. 59(10), 1376–1379.
"""

from __future__ import annotations

import functools
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from scipy.special import exp1

__all__ = ["PROSPECT_PARAMETERS", "PROSPECT_DEFAULTS", "ProspectCoefficients", "ProspectDataError",
           "prospect_coefficients", "prospect_d", "tav", "check_prospect_parameters", "ENVIRONMENT_VARIABLE",
           "SHIPPED"]

ENVIRONMENT_VARIABLE: str = "VIRTSPEC_PROSPECT_DATA"
"""Environment variable naming a PROSPECT-D coefficient table (see the module docstring)."""

SHIPPED: Path = Path(__file__).resolve().parents[2] / "data" / "prospect-d" / "prospect_d_coefficients.txt"
"""The coefficient table shipped with the package (Féret et al. 2017, MIT; its folder's LICENSE and README)."""

# name: (default, lowest, highest, unit, meaning). The ranges are the model's domain of
# validity as calibrated (Féret et al. 2017, Table 1 and Sect. 2), widened to round numbers.
PROSPECT_PARAMETERS: dict[str, tuple[float, float, float, str, str]] = {
    "N": (1.5, 1.0, 4.0, "", "leaf structure parameter (number of plates)"),
    "Cab": (40.0, 0.0, 150.0, "ug/cm2", "chlorophylls a + b"),
    "Car": (8.0, 0.0, 40.0, "ug/cm2", "carotenoids"),
    "Anth": (0.0, 0.0, 40.0, "ug/cm2", "anthocyanins"),
    "Cbrown": (0.0, 0.0, 4.0, "a.u.", "brown pigments"),
    "Cw": (0.01, 0.0, 0.1, "cm", "equivalent water thickness"),
    "Cm": (0.009, 0.0, 0.05, "g/cm2", "leaf mass per area (dry matter)"),
}
"""Each input of :func:`prospect_d`: (default, lowest, highest, unit, meaning)."""

PROSPECT_DEFAULTS: dict[str, float] = {name: row[0] for name, row in PROSPECT_PARAMETERS.items()}
"""The default leaf (a green leaf: N 1.5, Cab 40, Car 8, Cw 0.01 cm, Cm 0.009 g/cm²)."""

_COLUMNS = ("wavelength", "n", "Cab", "Car", "Anth", "Cbrown", "Cw", "Cm")


class ProspectDataError(RuntimeError):
    """The PROSPECT-D coefficients were not found (the message names the fixes)."""


@dataclass(frozen=True, eq=False)
class ProspectCoefficients:
    """The model's data on its wavelength grid: ``n`` (refractive index) and one K per absorber."""

    wavelengths: np.ndarray
    n: np.ndarray
    absorption: dict[str, np.ndarray]
    source: str

    def surfaces(self, alpha: float) -> tuple[np.ndarray, ...]:
        """
        The plate surfaces' (r_α, t_α, r₁₂, t₁₂, r₂₁, t₂₁) at every wavelength: from the cone of
        half-angle ``alpha`` and isotropic light, inside to outside (computed once per α).
        """

        cache = self.__dict__.setdefault("_surfaces", {})
        if alpha not in cache:
            t_alpha, t12 = tav(alpha, self.n), tav(90.0, self.n)
            t21 = t12 / (self.n * self.n)
            cache[alpha] = (1.0 - t_alpha, t_alpha, 1.0 - t12, t12, 1.0 - t21, t21)
        return cache[alpha]

    def at(self, wavelengths: Any) -> "ProspectCoefficients":
        """The coefficients linearly interpolated at ``wavelengths`` (nm, inside the data's range)."""

        wavelengths = np.atleast_1d(np.asarray(wavelengths, dtype=np.float64))
        low, high = self.wavelengths[0], self.wavelengths[-1]
        if wavelengths.size and (wavelengths.min() < low or wavelengths.max() > high):
            raise ValueError(f"PROSPECT-D wavelengths must lie in {low:g}-{high:g} nm, the coefficients' range "
                             f"(got {wavelengths.min():g}-{wavelengths.max():g} nm)")
        return ProspectCoefficients(
            wavelengths, np.interp(wavelengths, self.wavelengths, self.n),
            {name: np.interp(wavelengths, self.wavelengths, k) for name, k in self.absorption.items()},
            self.source)


def _read_table(path: Path, source: str) -> ProspectCoefficients:
    try:
        table = np.loadtxt(path, comments="#", delimiter="," if path.suffix.lower() == ".csv" else None, ndmin=2)
    except (OSError, ValueError) as error:
        raise ProspectDataError(f"cannot read the PROSPECT-D coefficients from {source}: {error}") from None
    if table.shape[1] != len(_COLUMNS) or len(table) < 2:
        raise ProspectDataError(f"{source} must hold rows of {len(_COLUMNS)} columns ({', '.join(_COLUMNS)}); "
                                f"got {table.shape[0]} rows of {table.shape[1]}")
    wavelengths = table[:, 0]
    if not (np.all(np.isfinite(table)) and np.all(np.diff(wavelengths) > 0) and np.all(table[:, 1] > 1.0)
            and np.all(table[:, 2:] >= 0)):
        raise ProspectDataError(f"{source}: wavelengths must increase, n be > 1 and every K be finite and >= 0")
    return ProspectCoefficients(wavelengths, table[:, 1], dict(zip(_COLUMNS[2:], table[:, 2:].T)), source)


@functools.lru_cache(maxsize=8)
def _cached(path: str, source: str) -> ProspectCoefficients:
    return _read_table(Path(path), source)


def prospect_coefficients(source: str | os.PathLike | None = None) -> ProspectCoefficients:
    """
    The PROSPECT-D coefficients from ``source``, ``$VIRTSPEC_PROSPECT_DATA`` or the table
    shipped with the package (:data:`SHIPPED`; in this order, see the module docstring).
    Read once per path.

    Raises
    ------
    ProspectDataError
        The table is missing, unreadable or not one of eight columns.
    """

    if source is not None and str(source) != "":
        return _cached(str(Path(source).resolve()), str(source))
    given = os.environ.get(ENVIRONMENT_VARIABLE, "")
    if given:
        return _cached(str(Path(given).resolve()), f"${ENVIRONMENT_VARIABLE} = {given}")
    if not SHIPPED.is_file():
        raise ProspectDataError(
            f"the PROSPECT-D coefficients shipped with virtspec-mi are missing ({SHIPPED}): reinstall the package, "
            f"or set ${ENVIRONMENT_VARIABLE} (or the plugin's data=...) to a table of eight columns: "
            f"{', '.join(_COLUMNS)} (the layout of dataSpec_PDB.m)")
    return _cached(str(SHIPPED), "the PROSPECT-D coefficients shipped with virtspec-mi (Feret et al. 2017, MIT)")


def tav(alpha: float, n: Any) -> np.ndarray:
    """
    Transmissivity of a dielectric interface of relative index ``n`` for isotropic light
    within a cone of half-angle ``alpha`` (degrees, 0 < α ≤ 90) about the normal
    (Stern 1964, eqs. 6–8; Allen 1973).
    """

    if not 0.0 < alpha <= 90.0:
        raise ValueError(f"tav: alpha must satisfy 0 < alpha <= 90 degrees (got {alpha!r})")
    n = np.asarray(n, dtype=np.float64)
    n2 = n * n
    np_, nm = n2 + 1.0, n2 - 1.0
    a = (n + 1.0) ** 2 / 2.0
    k = -(n2 - 1.0) ** 2 / 4.0
    sa = np.sin(np.deg2rad(alpha))
    b2 = sa * sa - np_ / 2.0
    b1 = np.sqrt(b2 * b2 + k) if alpha != 90.0 else 0.0
    b = b1 - b2
    ts = (k ** 2 / (6 * b ** 3) + k / b - b / 2) - (k ** 2 / (6 * a ** 3) + k / a - a / 2)
    tp1 = -2 * n2 * (b - a) / np_ ** 2
    tp2 = -2 * n2 * np_ * np.log(b / a) / nm ** 2
    tp3 = n2 * (1 / b - 1 / a) / 2
    tp4 = (16 * n2 ** 2 * (n2 ** 2 + 1) * np.log((2 * np_ * b - nm ** 2) / (2 * np_ * a - nm ** 2))
           / (np_ ** 3 * nm ** 2))
    tp5 = 16 * n2 ** 3 * (1 / (2 * np_ * b - nm ** 2) - 1 / (2 * np_ * a - nm ** 2)) / np_ ** 3
    return (ts + tp1 + tp2 + tp3 + tp4 + tp5) / (2 * sa * sa)


def check_prospect_parameters(values: dict[str, Any]) -> dict[str, np.ndarray]:
    """Every parameter as a float64 array (defaults filled in), each inside its range, else ``ValueError``."""

    unknown = sorted(set(values) - set(PROSPECT_PARAMETERS))
    if unknown:
        raise ValueError(f"PROSPECT-D has no parameter {unknown[0]!r} "
                         f"(its parameters: {', '.join(PROSPECT_PARAMETERS)})")
    checked = {}
    for name, (default, low, high, unit, meaning) in PROSPECT_PARAMETERS.items():
        value = np.asarray(values.get(name, default), dtype=np.float64)
        if not np.all(np.isfinite(value) & (value >= low) & (value <= high)):
            bad = value[~(np.isfinite(value) & (value >= low) & (value <= high))].ravel()[0]
            raise ValueError(f"PROSPECT-D: '{name}' ({meaning}) must satisfy {low:g} <= {name} <= {high:g} "
                             f"{unit} (got {float(bad)!r})".rstrip())
        checked[name] = value
    return checked


def prospect_d(wavelengths: Any = None, *, coefficients: ProspectCoefficients | None = None, alpha: float = 40.0,
               **parameters: Any) -> tuple[np.ndarray, np.ndarray]:
    """
    PROSPECT-D reflectance and transmittance (directional-hemispherical, light from a cone
    of half-angle ``alpha`` about the normal).

    Parameters
    ----------
    wavelengths
        nm (inside the coefficients' range); default: the coefficients' grid (400–2500 nm, 1 nm).
    coefficients
        The model's data; default :func:`prospect_coefficients`.
    alpha
        Half-angle (degrees) of the incidence cone at the top surface (40°, the model's).
    **parameters
        ``N``, ``Cab``, ``Car``, ``Anth``, ``Cbrown``, ``Cw``, ``Cm`` (:data:`PROSPECT_PARAMETERS`;
        numbers or arrays broadcast to one shape P; defaults :data:`PROSPECT_DEFAULTS`).

    Returns
    -------
    reflectance, transmittance : ndarray
        Shape P + (n_λ,).

    References
    ----------
    Jacquemoud & Baret (1990), eqs. 1–7; Stokes (1862); Féret et al. (2017).
    """

    data = coefficients if coefficients is not None else prospect_coefficients()
    if wavelengths is not None:
        data = data.at(wavelengths)
    values = check_prospect_parameters(parameters)
    shape = np.broadcast_shapes(*(v.shape for v in values.values()))
    flat = {name: np.broadcast_to(v, shape).reshape(-1, 1) for name, v in values.items()}
    size = int(np.prod(shape, dtype=np.int64))
    reflectance = np.empty((size, len(data.n)))
    transmittance = np.empty((size, len(data.n)))
    block = max(1, _BLOCK // max(1, len(data.n)))  # parameter sets per block: the arrays stay in cache
    for start in range(0, size, block):
        part = slice(start, start + block)
        reflectance[part], transmittance[part] = _pile(data, alpha, {name: v[part] for name, v in flat.items()})
    return reflectance.reshape(*shape, -1), transmittance.reshape(*shape, -1)


_BLOCK = 1 << 16  # values per array in one block of :func:`_pile`


def _pile(data: ProspectCoefficients, alpha: float, p: dict[str, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """R and T of the pile for parameter columns ``p`` (each of shape (m, 1)) on the data's wavelengths."""

    n_plates = p["N"]
    names = tuple(data.absorption)
    matrix = data.__dict__.setdefault("_matrix", np.stack([data.absorption[name] for name in names]))
    k = (np.hstack([p[name] for name in names]) @ matrix) / n_plates  # sum of C_i K_i(λ), over N
    positive = k > 0
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        transmission = np.where(positive, (1.0 - k) * np.exp(-k) + k * k * exp1(np.where(positive, k, 1.0)), 1.0)
    r_alpha, t_alpha, r12, t12, r21, t21 = data.surfaces(alpha)
    # one plate: lit from the cone (top) and isotropically (inside)
    denominator = 1.0 - r21 * r21 * transmission * transmission
    top_t = t_alpha * transmission * t21 / denominator
    top_r = r_alpha + r21 * transmission * top_t
    t = t12 * transmission * t21 / denominator
    r = r12 + r21 * transmission * t
    # the other N - 1 plates (Stokes)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        d = np.sqrt(np.maximum((1 + r + t) * (1 + r - t) * (1 - r + t) * (1 - r - t), 0.0))
        a = (1 + r * r - t * t + d) / (2 * r)
        b = (1 - r * r + t * t + d) / (2 * t)
        b_n1 = np.power(b, n_plates - 1)
        b_n2 = b_n1 * b_n1
        denominator = a * a * b_n2 - 1
        r_sub = a * (b_n2 - 1) / denominator
        t_sub = b_n1 * (a * a - 1) / denominator
    # No absorption (k = 0, or r + t rounded to 1): the limit of the formulae, taken whenever nothing absorbs —
    # not left to rounding, where Stokes' formula loses ~1e-9 to cancellation (d -> 0) and R + T drifts from 1.
    lossless = ~positive | (r + t >= 1.0)
    if lossless.any():
        t_lossless = t / (t + (1 - t) * (n_plates - 1))
        t_sub = np.where(lossless, t_lossless, t_sub)
        r_sub = np.where(lossless, 1 - t_lossless, r_sub)
        r = np.where(lossless, 1 - t, r)  # the lossless plate's own r + t = 1, exactly
    denominator = 1 - r_sub * r
    return top_r + top_t * r_sub * t / denominator, top_t * t_sub / denominator
