"""
Goniophotometer readings on the RGL grid: :class:`RGLReading`
=============================================================

A goniophotometer reading with ``binning="rgl"`` (:func:`virtspec_mi.gonio`,
``virtspec gonio --rgl FILE``) bins every reflected ray in the cell of an RGL ``.bsdf``'s
grid its half vector falls in (:mod:`virtspec_mi.instruments.goniophotometer.warped`).
:class:`RGLReading` is the spectrophotometer reading of the same rays with those exact cell
counts m_k over the dim ``cell`` (k = 0 … K − 1, K = 1 + (n − 1)²) and, derived from them:

- ``solid_angle`` Ω_k, the solid angle of the cell's reflected directions at the reading's
  θi (NaN: an index unused at θi = 0);
- ``cell_mean`` m_k/(N Ω_k), the estimate of the cell's solid-angle mean of f·cos θo,
  (1/Ω_k) ∫_cell f(wi, wo) cos θo dωo — the quantity the ``.bsdf`` stores at the node;
- ``cell_mean_lower``, ``cell_mean_upper``: its simultaneous Clopper–Pearson interval (each
  cell at δ/K, so all K cells of a reading at once with probability ≥ 1 − δ) divided by
  Ω_k — NaN where the reading is not certified or Ω_k = 0 (a cell with no reflected
  direction: its count is 0 always);
- ``bins_mu``: every cell fraction within μ at once (the guarantee's union bound).

The estimate is unbiased and the interval exact for a **collimated** beam (the only beam
this binning takes): a ray's share of the cell is then ∫_cell f cos θo dωo
(Nicodemus et al. 1977). :meth:`RGLReading.to_rgl` writes the ``.bsdf``
(:func:`~virtspec_mi.instruments.goniophotometer.rgl.rgl_export`); ``write("x.bsdf")`` does too.

References
----------
Nicodemus et al. (1977), NBS Monograph 160; Clopper, C.J. and Pearson, E.S. (1934),
Biometrika 26, 404–413; Dupuy & Jakob (2018), ACM Trans. Graph. 37(6), 274.
"""

from __future__ import annotations

import os
from functools import cached_property
from pathlib import Path
from typing import Any, ClassVar, Mapping

import numpy as np

from virtspec_mi.budgets import bins as histogram_bounds
from virtspec_mi.budgets.rules import guarantee_of
from virtspec_mi.instruments.goniophotometer.warped import DEFAULT_RESOLUTION, WarpedGrid
from virtspec_mi.kernel.counts import QUANTITIES
from virtspec_mi.results.base import ResultBase, attribute, plain_data, round_up, span, stored
from virtspec_mi.results.figures import Figure, sweep
from virtspec_mi.results.integrity import CountRules, field_value, whole_counts
from virtspec_mi.results.readings import Result
from virtspec_mi.results.variables import READINGS, Variable, of_reading

__all__ = ["RGLReading"]

_CELLS = "cell_counts (reflected)"
_CELL_RULES = CountRules(None, parts={_CELLS: "reflected"})
"""A reading's cells add up to at most its reflected rays (exactly, but for rays with no resolvable half vector)."""


def _to_rgl(reading: "RGLReading", path: Path, **options: Any) -> Path:
    return reading.to_rgl(path, **options).path


class RGLReading(ResultBase):
    """
    A goniophotometer reading binned on an RGL ``.bsdf``'s grid (see the module docstring).

    Parameters
    ----------
    result : Result
        The spectrophotometer reading of the same rays.
    cell_counts : ndarray
        Exact per-cell counts, ``int64``, shape (the result's dims …, K).
    resolution : int
        n, the grid's nodes per axis.
    guarantee : str
        How N was sized (:data:`~virtspec_mi.budgets.rules.GUARANTEES`), or ``"rays"`` when given.
    """

    FORMAT: ClassVar[str] = "virtspec-mi rgl 1"
    KIND: ClassVar[str] = "goniophotometer reading on the RGL grid"
    KIND_DIMS: ClassVar[tuple[str, ...]] = ("cell",)
    KIND_DIMS_REASON: ClassVar[str] = "its certificate is a union over all K cells"
    SHAPED_BY: ClassVar[str] = "cell_counts"
    QUANTITIES: ClassVar[tuple[str, ...]] = QUANTITIES
    VARIABLES: ClassVar[dict[str, tuple[str, str]]] = {
        "cell": ("1", "cell of the RGL grid: 0 the disc about the mirror direction, 1 + (i - 1)(n - 1) + j"),
        "cell_counts": ("1", "rays reflected into the cell (exact)"),
    }
    DERIVED: ClassVar[dict[str, Variable]] = {
        **of_reading(Result.DERIVED),
        "fraction": Variable("1", "cell_counts / rays", lambda g: g.fraction),
        "solid_angle": Variable("sr", "solid angle of the cell's reflected directions", lambda g: g.solid_angles),
        "cell_mean": Variable("1/sr", "solid-angle mean of f cos(theta_o) over the cell: fraction / solid_angle",
                              lambda g: g.cell_mean),
        **{f"cell_mean_{side}": Variable("1/sr", f"simultaneous Clopper-Pearson {side} bound of cell_mean",
                                         lambda g, end=end: g._band[end],
                                         attrs=lambda g: {"clopper_pearson_delta": g.delta / g.size})
           for end, side in ((0, "lower"), (1, "upper"))},
        "bins_mu": Variable("1", "every cell fraction within bins_mu at once at delta (NaN: not certified)",
                            lambda g: g.bins_mu, READINGS),
    }
    FIGURES: ClassVar[dict[str, Figure]] = {
        "sweep": Figure(lambda g, path, quantity, **options: sweep.draw(g.result, path, quantity, **options),
                        "the reading's R, T or A against theta_i or wavelength", QUANTITIES),
    }
    EXPORTS: ClassVar[dict[str, Any]] = {".bsdf": _to_rgl}

    def __init__(self, result: Result, cell_counts: Any, resolution: int = DEFAULT_RESOLUTION,
                 guarantee: str = "union") -> None:
        grid = WarpedGrid(resolution)
        self._extend(result, {"cell_counts": ((*result.dims, "cell"), cell_counts)}, {"cell": np.arange(grid.size)},
                     {"rgl_resolution": grid.resolution, "guarantee": guarantee})

    @cached_property
    def result(self) -> Result:
        """The spectrophotometer reading of the same rays."""

        return Result._of(self.data.drop_dims(["cell"]))

    cell_counts = stored("cell_counts", "Exact per-cell counts, ``int64``, shape (the reading's dims …, K).")
    resolution = attribute("rgl_resolution", "n, the grid's nodes per axis.", int)
    guarantee = attribute("guarantee", "How N was sized, or ``\"rays\"`` when given.", str)

    @property
    def grid(self) -> WarpedGrid:
        return WarpedGrid(self.resolution)

    @property
    def interval_delta(self) -> float:
        return self.result.interval_delta

    @property
    def size(self) -> int:
        """K, the number of cell indices."""

        return self.grid.size

    @property
    def rays(self) -> np.ndarray:
        return self.result.rays

    @property
    def fraction(self) -> np.ndarray:
        """m_k/N per cell."""

        return self.cell_counts / self.rays[..., None]

    @cached_property
    def solid_angles(self) -> np.ndarray:
        """Ω_k (sr) per reading and cell (they depend on the reading's θi only)."""

        theta = np.broadcast_to(self.data["theta_i"].broadcast_like(self.data["cell_counts"].isel(cell=0)).values,
                                self.rays.shape)
        table = {float(t): self.grid.solid_angles(float(t)) for t in np.unique(theta)}
        return np.stack([table[float(t)] for t in theta.ravel()]).reshape(*theta.shape, self.size)

    @property
    def cell_mean(self) -> np.ndarray:
        """m_k/(N Ω_k): the solid-angle mean of f·cos θo over the cell (sr⁻¹; NaN where Ω_k is 0 or unused)."""

        omega = self.solid_angles
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.where(omega > 0, self.fraction / np.where(omega > 0, omega, 1.0), np.nan)

    @cached_property
    def _band(self) -> tuple[np.ndarray, np.ndarray]:
        omega = self.solid_angles
        usable = omega > 0
        lower, upper = histogram_bounds.brdf_intervals(self.cell_counts, self.rays[..., None],
                                                       np.where(usable, omega, 1.0), self.delta, self.size)
        certified = np.isfinite(self.bins_mu)[..., None] & usable
        return np.where(certified, lower, np.nan), np.where(certified, upper, np.nan)

    @property
    def cell_mean_lower(self) -> np.ndarray:
        """Lower ends of the simultaneous Clopper–Pearson intervals of the cell means (all K at 1 − δ)."""

        return self._band[0]

    @property
    def cell_mean_upper(self) -> np.ndarray:
        """Upper ends of the simultaneous intervals of the cell means."""

        return self._band[1]

    @property
    def bins_mu(self) -> np.ndarray:
        """μ with |m_k/N − p_k| < μ for every cell at once at δ (per reading; NaN: not certified)."""

        if self.result.pilot is not None:
            mu = np.full(np.shape(self.rays), float(self.result.mu))
        else:
            mu = guarantee_of(self.guarantee).certified(self.rays, self.delta, self.result.mu, self.size)
        mu = mu + self.result.rounding_bias
        return np.where(self.result.certified & (mu < 1.0), mu, np.nan)

    def certificate(self) -> str:
        """What the reading's rays guarantee, in words (worst reading), or "not certified"."""

        k = self.size
        counted = f"N = {span(self.rays)} rays per reading, K = {k} cells ({self.resolution} x {self.resolution} nodes)"
        bins_mu = self.bins_mu
        if np.all(np.isnan(bins_mu)):
            return f"{counted}: NOT CERTIFIED (see the reading's warnings, or too few rays)"
        lines = [f"{counted}, each statement with probability >= {1 - self.delta:g} per reading:",
                 f"  every cell fraction at once: |m_k/N - p_k| < {round_up(float(np.nanmax(bins_mu))):g}",
                 f"  cell means of f cos(theta_o): simultaneous Clopper-Pearson intervals, each at delta/K = "
                 f"{self.delta / k:.3g}"]
        if np.any(np.isnan(bins_mu)):
            lines.append("  some readings NOT CERTIFIED")
        return "\n".join(lines)

    def summary(self) -> str:
        """The spectrophotometer summary, the grid and its certificate."""

        return "\n".join([self.result.summary(), "",
                          f"Goniophotometer on the RGL grid: {self.resolution} x {self.resolution} nodes, K = "
                          f"{self.size} cells of the half-vector lookup (identity warp); each cell's mean of "
                          "f cos(theta_o) is what the .bsdf stores at its nodes", self.certificate()])

    def __repr__(self) -> str:
        sizes = " x ".join(f"{n} {d}" for d, n in self.sizes.items())
        return f"RGLReading({sizes}, N = {int(np.max(self.rays)):,})"

    # -- plain data and files -----------------------------------------------------------

    def as_dict(self) -> dict[str, Any]:
        """Plain data (JSON-ready): the reading's result, the grid, the counts and the certificate."""

        return {"format": self.FORMAT, "result": self.result.as_dict(), "rgl_resolution": self.resolution,
                "cell_counts": self.cell_counts.tolist(), "guarantee": self.guarantee,
                "cell_mean": plain_data(self.cell_mean), "bins_mu": plain_data(self.bins_mu)}

    @classmethod
    def _from_dict(cls, data: Mapping[str, Any]) -> "RGLReading":
        return cls(result=Result.from_dict(field_value(data, "result", "object")),
                   cell_counts=whole_counts(data["cell_counts"], "cell_counts"),
                   resolution=field_value(data, "rgl_resolution", "number or null"),
                   guarantee=field_value(data, "guarantee", "text"))

    def _count_groups(self) -> list[tuple[str, Mapping[str, np.ndarray], CountRules, tuple[str, ...]]]:
        cells = {"reflected": self.result.reflected, _CELLS: self.cell_counts.sum(axis=-1)}
        return [*self.result._count_groups(), ("", cells, _CELL_RULES, self.result.dims)]

    def _file_attrs(self) -> dict[str, Any]:
        return {**self.result._file_attrs(), "binning": "rgl", "rgl_resolution": self.resolution,
                "guarantee": self.guarantee, "bins": self.size, "bins_delta": self.delta}

    def _quantity(self, quantity: str) -> tuple[np.ndarray, np.ndarray, float]:
        return self.result._quantity(quantity)

    def to_msds(self, theta_i: float | None = None) -> Any:
        return self.result.to_msds(theta_i)

    def to_rgl(self, path: str | os.PathLike) -> Any:
        """
        Write the reading as an RGL ``.bsdf`` for Mitsuba's ``measured`` plugin; returns the
        :class:`~virtspec_mi.instruments.goniophotometer.rgl.RGLExport` (nodes, values, certified intervals).
        """

        from virtspec_mi.instruments.goniophotometer.rgl import rgl_export

        return rgl_export(self, path)
