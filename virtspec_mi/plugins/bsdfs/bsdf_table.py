"""
BSDF tables: a goniophotometer reading as the ``tabulated`` BSDF reads it
=========================================================================

A goniophotometer reading (docs/guide/goniophotometer.md) is an
``xarray.Dataset`` with dims ``wavelength`` (nm), ``theta_i`` (deg), ``theta_o`` and
``phi_o`` (bins), bin edges ``theta_o_lower/upper`` and ``phi_o_lower/upper`` (deg),
exact counts ``bin_counts`` (wavelength, theta_i, theta_o, phi_o), rays ``rays``
(wavelength, theta_i), the estimate ``brdf`` (sr⁻¹) and attributes ``phi_i`` and
``phi_folded``. This module

- reads and validates such a dataset (or its NetCDF file) into a :class:`BSDFTable`:
  bad input is a ``ValueError`` naming the variable and the allowed range;
- derives what the ``tabulated`` BSDF needs: the fraction of incident rays per bin
  p_k = m_k/N, the projected solid angle Ω_k = ∫_bin |cos θo| dωo, the piecewise-constant
  BSDF f_k = p_k/Ω_k, the per-row (λ, θi) cumulative sums of p_k (sampling) and the
  reflected and transmitted totals R = Σ_{θo<90} p_k, T = Σ_{θo>90} p_k;
- gives the plugin its properties as plain arrays (:meth:`BSDFTable.properties`; the
  dict-scene entry is :func:`virtspec_mi.runtime.scene.tabulated_bsdf`);
- writes a table back as a contract dataset (:func:`table_dataset`).

Folded azimuths (``phi_folded = 1``): the specimen was taken as isotropic and φo folded
to the relative azimuth |φo − φi| ∈ [0, 180]; a folded bin [a, b] stands for the two
real bins [φi + a, φi + b] and [φi − b, φi − a], so its Ω_k counts both (twice the
geometric formula) and its fraction is split evenly between them.

References
----------
Nicodemus et al. (1977), *Geometrical considerations and nomenclature for
reflectance*, NBS Monograph 160 (BRDF, projected solid angle); the goniophotometer
contract of issue 15.
"""

from __future__ import annotations

import hashlib
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

__all__ = [
    "BSDFTable",
    "TABLE_PROPERTIES",
    "BRDF_RTOL",
    "projected_solid_angles",
    "read_table",
    "table_dataset",
]

BRDF_RTOL: float = 1e-6
"""Relative tolerance of a dataset's ``brdf`` against (bin_counts/rays)/Ω_k."""


TABLE_PROPERTIES: tuple[str, ...] = ("wavelength", "theta_i", "theta_o_lower", "theta_o_upper", "phi_o_lower",
                                     "phi_o_upper", "fraction", "phi_i", "phi_folded")
"""The ``tabulated`` plugin's parameters that carry a table in a dict scene (instead of ``filename``)."""


def projected_solid_angles(theta_lower: np.ndarray, theta_upper: np.ndarray, phi_lower: np.ndarray,
                           phi_upper: np.ndarray, folded: bool = False) -> np.ndarray:
    """
    Ω_k = ∫_bin |cos θo| dωo = Δφ (rad) · |sin²θ_upper − sin²θ_lower| / 2 for every
    (θo, φo) bin, shape (n_theta_o, n_phi_o); twice that when ``folded``.
    """

    sin2 = np.abs(np.sin(np.radians(theta_upper)) ** 2 - np.sin(np.radians(theta_lower)) ** 2) / 2.0
    dphi = np.radians(np.asarray(phi_upper, dtype=np.float64) - np.asarray(phi_lower, dtype=np.float64))
    return np.outer(sin2, dphi) * (2.0 if folded else 1.0)


def _check_edges(name: str, lower: np.ndarray, upper: np.ndarray, low: float, high: float) -> None:
    """Contiguous, increasing bin edges within [low, high]."""

    if lower.ndim != 1 or lower.shape != upper.shape or lower.size == 0:
        raise ValueError(f"{name}_lower and {name}_upper must be 1-D of the same non-zero length "
                         f"(got shapes {lower.shape} and {upper.shape})")
    if not (np.all(np.isfinite(lower)) and np.all(np.isfinite(upper))):
        raise ValueError(f"{name}_lower/{name}_upper must be finite")
    if not np.all(upper > lower):
        raise ValueError(f"{name} bins must have {name}_lower < {name}_upper")
    if np.any(lower[1:] != upper[:-1]):
        raise ValueError(f"{name} bins must be contiguous and increasing ({name}_lower[k+1] == {name}_upper[k])")
    if lower[0] < low or upper[-1] > high:
        raise ValueError(f"{name} bin edges must lie in [{low:g}, {high:g}] degrees "
                         f"(got {lower[0]:g} … {upper[-1]:g})")


@dataclass(frozen=True)
class BSDFTable:
    """
    A validated BSDF table: fractions p_k of incident rays per (θo, φo) bin for every
    (wavelength, θi) row (see the module docstring).

    Parameters
    ----------
    wavelength : ndarray, shape (n_wavelength,)
        nm, strictly increasing, > 0.
    theta_i : ndarray, shape (n_theta_i,)
        Incidence θi in degrees, strictly increasing, in [0, 90].
    theta_o_lower, theta_o_upper : ndarray, shape (n_theta_o,)
        θo bin edges in degrees: contiguous, increasing, within [0, 180]; no bin
        straddles 90 (reflected bins θo < 90, transmitted θo > 90).
    phi_o_lower, phi_o_upper : ndarray, shape (n_phi_o,)
        φo bin edges in degrees: contiguous, within [0, 360] ([0, 180] when folded).
    fraction : ndarray, shape (n_wavelength, n_theta_i, n_theta_o, n_phi_o)
        p_k = m_k/N ≥ 0 with Σ_k p_k ≤ 1 per row (the rest was absorbed).
    phi_i : float
        φi of the reading in degrees (unfolded tables are read relative to it).
    phi_folded : bool
        φo is the folded relative azimuth |φo − φi| ∈ [0, 180].
    """

    wavelength: np.ndarray
    theta_i: np.ndarray
    theta_o_lower: np.ndarray
    theta_o_upper: np.ndarray
    phi_o_lower: np.ndarray
    phi_o_upper: np.ndarray
    fraction: np.ndarray
    phi_i: float = 0.0
    phi_folded: bool = False
    attrs: dict = field(default_factory=dict, compare=False)

    def __post_init__(self) -> None:
        arrays = {name: np.array(getattr(self, name), dtype=np.float64)
                  for name in ("wavelength", "theta_i", "theta_o_lower", "theta_o_upper", "phi_o_lower",
                               "phi_o_upper", "fraction")}
        for name, value in arrays.items():
            value.setflags(write=False)
            object.__setattr__(self, name, value)
        wavelength, theta_i = arrays["wavelength"], arrays["theta_i"]
        for name, value, (low, high) in (("wavelength", wavelength, (0.0, math.inf)), ("theta_i", theta_i, (0.0, 90.0))):
            if value.ndim != 1 or value.size == 0:
                raise ValueError(f"{name} must be a non-empty 1-D coordinate (got shape {value.shape})")
            if not np.all(np.isfinite(value)) or value.min() < low or value.max() > high or (name == "wavelength" and value.min() <= 0):
                raise ValueError(f"{name} must lie in {'(0, inf) nm' if name == 'wavelength' else '[0, 90] degrees'} "
                                 f"(got {value.min():g} … {value.max():g})")
            if np.any(np.diff(value) <= 0):
                raise ValueError(f"{name} must be strictly increasing")
        _check_edges("theta_o", arrays["theta_o_lower"], arrays["theta_o_upper"], 0.0, 180.0)
        if np.any((arrays["theta_o_lower"] < 90.0) & (arrays["theta_o_upper"] > 90.0)):
            raise ValueError("theta_o bins must not straddle 90 degrees (reflected and transmitted bins apart)")
        _check_edges("phi_o", arrays["phi_o_lower"], arrays["phi_o_upper"], 0.0, 180.0 if self.phi_folded else 360.0)
        if not (isinstance(self.phi_folded, (bool, np.bool_)) or self.phi_folded in (0, 1)):
            raise ValueError(f"phi_folded must be 0 or 1 (got {self.phi_folded!r})")
        object.__setattr__(self, "phi_folded", bool(self.phi_folded))
        phi_i = float(self.phi_i)
        if not math.isfinite(phi_i):
            raise ValueError(f"phi_i must be a finite angle in degrees (got {self.phi_i!r})")
        object.__setattr__(self, "phi_i", phi_i)
        fraction = arrays["fraction"]
        shape = (wavelength.size, theta_i.size, arrays["theta_o_lower"].size, arrays["phi_o_lower"].size)
        if fraction.shape != shape:
            raise ValueError(f"fraction must have shape (wavelength, theta_i, theta_o, phi_o) = {shape} "
                             f"(got {fraction.shape})")
        if not np.all(np.isfinite(fraction)) or fraction.min() < 0:
            raise ValueError("fraction (bin_counts/rays) must be finite and >= 0")
        totals = fraction.sum(axis=(2, 3))
        if totals.max() > 1.0 + 1e-12:
            raise ValueError(f"fraction must sum to at most 1 over the bins of each (wavelength, theta_i) row "
                             f"(got {totals.max():.17g})")

    # ------------------------------------------------------------------ derived
    @property
    def shape(self) -> tuple[int, int, int, int]:
        """(n_wavelength, n_theta_i, n_theta_o, n_phi_o)."""

        return self.fraction.shape  # type: ignore[return-value]

    @property
    def solid_angles(self) -> np.ndarray:
        """Ω_k = ∫_bin |cos θo| dωo (sr), shape (n_theta_o, n_phi_o); folded bins count both halves."""

        return projected_solid_angles(self.theta_o_lower, self.theta_o_upper, self.phi_o_lower,
                                      self.phi_o_upper, self.phi_folded)

    @property
    def brdf(self) -> np.ndarray:
        """f_k = p_k/Ω_k (sr⁻¹; BTDF for θo > 90), shape of :attr:`fraction`."""

        return self.fraction / self.solid_angles

    @property
    def reflected_bins(self) -> np.ndarray:
        """True for the θo bins of the upper hemisphere (θo < 90)."""

        return self.theta_o_upper <= 90.0

    @property
    def reflectance(self) -> np.ndarray:
        """R = Σ_{θo<90} p_k per (wavelength, theta_i)."""

        return self.fraction[:, :, self.reflected_bins].sum(axis=(2, 3))

    @property
    def transmittance(self) -> np.ndarray:
        """T = Σ_{θo>90} p_k per (wavelength, theta_i)."""

        return self.fraction[:, :, ~self.reflected_bins].sum(axis=(2, 3))

    @property
    def digest(self) -> str:
        """A short SHA-256 of the table's numbers (names it in scene fingerprints)."""

        digest = hashlib.sha256()
        for value in (self.wavelength, self.theta_i, self.theta_o_lower, self.theta_o_upper,
                      self.phi_o_lower, self.phi_o_upper, self.fraction):
            digest.update(np.ascontiguousarray(value).tobytes())
        digest.update(repr((self.phi_i, self.phi_folded)).encode())
        return digest.hexdigest()[:16]

    def properties(self) -> dict[str, Any]:
        """The ``tabulated`` plugin's table parameters as NumPy arrays and scalars (:data:`TABLE_PROPERTIES`)."""

        return {name: getattr(self, name) for name in TABLE_PROPERTIES}

    def cumulative(self) -> np.ndarray:
        """Per-row cumulative sums of p_k over the flattened bins (θo major), shape (rows, K)."""

        rows = self.shape[0] * self.shape[1]
        return np.cumsum(self.fraction.reshape(rows, -1), axis=1)


# ---------------------------------------------------------------------- reading
_REQUIRED_COORDS = ("wavelength", "theta_i", "theta_o", "phi_o", "theta_o_lower", "theta_o_upper",
                    "phi_o_lower", "phi_o_upper")
_DIMS = ("wavelength", "theta_i", "theta_o", "phi_o")


def _variable(dataset: Any, name: str) -> Any:
    if name not in dataset.variables:
        raise ValueError(f"BSDF table: the dataset has no variable {name!r} (goniophotometer contract: "
                         f"dims {_DIMS}, bin edges, bin_counts, rays, brdf)")
    return dataset[name]


def read_table(source: Any) -> BSDFTable:
    """
    A :class:`BSDFTable` from a goniophotometer dataset (``xarray.Dataset``), an object
    with ``to_dataset()``, or the path of its NetCDF file. Fractions are
    ``bin_counts / rays``; ``brdf`` must agree with them (relative :data:`BRDF_RTOL`).
    A scalar ``wavelength`` or ``theta_i`` label (one reading) becomes a dim of one, other
    dims of one value (e.g. ``phi_i``) are dropped; ``phi_i`` is read from the attributes
    or a one-value coordinate (default 0).
    """

    import xarray as xr

    if isinstance(source, (str, Path)):
        path = Path(source)
        if not path.is_file():
            raise ValueError(f"BSDF table: filename {str(path)!r} is not a file")
        from virtspec_mi.base.files import read_netcdf

        dataset = read_netcdf(path, "BSDF table: filename (a goniophotometer table)")
    elif hasattr(source, "to_dataset") and not isinstance(source, xr.Dataset):
        dataset = source.to_dataset()
    else:
        dataset = source
    if not isinstance(dataset, xr.Dataset):
        raise ValueError(f"BSDF table: expected an xarray.Dataset or a NetCDF path (got {type(source).__name__})")
    for name in ("wavelength", "theta_i"):  # a single reading may carry them as scalar labels
        if name in dataset.coords and name not in dataset.dims and dataset[name].ndim == 0:
            dataset = dataset.expand_dims(name)
    extra = [dim for dim in dataset.dims if dim not in _DIMS and dataset.sizes[dim] == 1]
    if extra:  # e.g. a phi_i dim of one value
        dataset = dataset.squeeze(extra)
    for name in _REQUIRED_COORDS:
        _variable(dataset, name)
    counts = _variable(dataset, "bin_counts")
    if tuple(counts.dims) != _DIMS:
        counts = counts.transpose(*_DIMS) if set(counts.dims) == set(_DIMS) else None
        if counts is None:
            raise ValueError(f"BSDF table: bin_counts must have dims {_DIMS} (got {tuple(_variable(dataset, 'bin_counts').dims)})")
    rays = _variable(dataset, "rays")
    if set(rays.dims) != {"wavelength", "theta_i"}:
        raise ValueError(f"BSDF table: rays must have dims ('wavelength', 'theta_i') (got {tuple(rays.dims)})")
    rays = rays.transpose("wavelength", "theta_i")
    if not np.issubdtype(counts.dtype, np.integer) or not np.issubdtype(rays.dtype, np.integer):
        raise ValueError(f"BSDF table: bin_counts and rays must be integers (got {counts.dtype}, {rays.dtype})")
    counts_np = counts.values.astype(np.int64)
    rays_np = rays.values.astype(np.int64)
    if rays_np.min() < 1:
        raise ValueError(f"BSDF table: rays must be >= 1 in every (wavelength, theta_i) row (got {rays_np.min()})")
    if counts_np.min() < 0:
        raise ValueError(f"BSDF table: bin_counts must be >= 0 (got {counts_np.min()})")
    if np.any(counts_np.sum(axis=(2, 3)) > rays_np):
        raise ValueError("BSDF table: bin_counts summed over the bins must not exceed rays")
    folded = dataset.attrs.get("phi_folded", 0)
    folded = int(folded) if np.ndim(folded) == 0 and folded in (0, 1) else folded
    if folded not in (0, 1):
        raise ValueError(f"BSDF table: attribute phi_folded must be 0 or 1 (got {folded!r})")
    if "phi_i" in dataset.attrs:
        phi_i = dataset.attrs["phi_i"]
    elif "phi_i" in dataset.variables and dataset["phi_i"].size == 1:
        phi_i = dataset["phi_i"].values.item()
    else:
        phi_i = 0.0
    table = BSDFTable(
        wavelength=dataset["wavelength"].values,
        theta_i=dataset["theta_i"].values,
        theta_o_lower=dataset["theta_o_lower"].values,
        theta_o_upper=dataset["theta_o_upper"].values,
        phi_o_lower=dataset["phi_o_lower"].values,
        phi_o_upper=dataset["phi_o_upper"].values,
        fraction=counts_np / rays_np[:, :, None, None],
        phi_i=float(phi_i),
        phi_folded=bool(folded),
        attrs=dict(dataset.attrs),
    )
    if "brdf" in dataset.variables:
        given = dataset["brdf"].transpose(*_DIMS).values.astype(np.float64)
        expected = table.brdf
        if given.shape != expected.shape or not np.allclose(given, expected, rtol=BRDF_RTOL, atol=0.0):
            worst = np.nanmax(np.abs(given - expected) / np.where(expected > 0, expected, 1.0)) if given.shape == expected.shape else math.inf
            raise ValueError(
                "BSDF table: brdf must equal (bin_counts/rays)/Ω_k with Ω_k = Δφ·|Δsin²θ|/2 "
                f"(doubled for folded φo) within relative {BRDF_RTOL:g} (largest relative difference {worst:.3g})")
    else:
        raise ValueError("BSDF table: the dataset has no variable 'brdf' (units 1/sr)")
    return table


def table_dataset(table: BSDFTable, rays: int | np.ndarray, counts: np.ndarray | None = None) -> Any:
    """
    The contract dataset of ``table``: ``bin_counts`` (given, or the fractions times
    ``rays`` rounded to integers), ``rays``, ``brdf`` (recomputed from the counts) and the
    bin geometry.
    """

    import xarray as xr

    n_wavelength, n_theta_i, _, _ = table.shape
    rays_np = np.broadcast_to(np.asarray(rays, dtype=np.int64), (n_wavelength, n_theta_i)).copy()
    if counts is None:
        counts = np.rint(table.fraction * rays_np[:, :, None, None]).astype(np.int64)
    counts = np.asarray(counts, dtype=np.int64)
    brdf = counts / rays_np[:, :, None, None] / table.solid_angles
    centre = lambda low, high: (low + high) / 2.0  # noqa: E731
    return xr.Dataset(
        {
            "bin_counts": (_DIMS, counts),
            "rays": (("wavelength", "theta_i"), rays_np),
            "brdf": (_DIMS, brdf, {"units": "1/sr"}),
        },
        coords={
            "wavelength": ("wavelength", table.wavelength, {"units": "nm"}),
            "theta_i": ("theta_i", table.theta_i, {"units": "deg"}),
            "theta_o": ("theta_o", centre(table.theta_o_lower, table.theta_o_upper), {"units": "deg"}),
            "phi_o": ("phi_o", centre(table.phi_o_lower, table.phi_o_upper), {"units": "deg"}),
            "theta_o_lower": ("theta_o", table.theta_o_lower),
            "theta_o_upper": ("theta_o", table.theta_o_upper),
            "phi_o_lower": ("phi_o", table.phi_o_lower),
            "phi_o_upper": ("phi_o", table.phi_o_upper),
        },
        attrs={**table.attrs, "phi_i": table.phi_i, "phi_folded": int(table.phi_folded)},
    )
