"""
Certified directional-albedo tables of microfacet BSDFs
=======================================================

Renderers compensate the energy that single-scattering microfacet BSDFs lose
(Kulla & Conty 2017) with precomputed tables of the directional albedo

    E(μ, α) = ∫ f(ω_i, ω_o) cos θ_o dω_o,   μ = cos θ_i,

and of its cosine-weighted average E_avg(α) = 2 ∫₀¹ E(μ) μ dμ. The instrument's
directional-hemispherical reading of a specimen lit by a collimated beam at
θ_i = arccos μ *is* E(μ): each ray leaves the specimen (reflected or transmitted) or is
lost, with probability exactly E(μ) of leaving, and its fate is an exact count. A
reading under the cosine-weighted diffuse beam (``beam="diffuse"``) *is* E_avg: its
incidence cosines are drawn with density 2μ, so one Bernoulli trial per ray has mean
2 ∫ E(μ) μ dμ — no quadrature, no quadrature error; that is why E_avg is measured that
way here rather than integrated from the certified cells (a quadrature of the cells
would add an error term that cannot be bounded without a smoothness assumption on E
near grazing incidence, where E changes fastest).

:func:`albedo_table` measures, on the user's grid or on an engine's
(:mod:`virtspec_mi.exchange.conventions`):

- ``model="conductor"``: Mitsuba's ``roughconductor`` with Fresnel = 1
  (``material="none"``), ``distribution`` ``ggx`` or ``beckmann``: E = reflected;
- ``model="glass"``: Mitsuba's ``roughdielectric``: E = reflected + transmitted (the
  energy *not lost* by single scattering — for a smooth dielectric nothing is lost, but
  the masking term of a rough one loses energy), for light from outside (relative index
  η) and from inside (1/η, the swept ``eta`` of the BSDF; Cycles' ``_inv_`` tables), with
  E_R and E_T alongside (certified too with ``parts=True``).

**The certificate.** Every cell of the table (and every E_avg value) is within ε of the
model's true value *at once* with probability ≥ 1 − δ: the union bound over the C cells
and the |Q| certified quantities of each. ``bound="hoeffding"`` gives every cell
N = ⌈ln(2C|Q|/δ)/(2ε²)⌉ rays (δ split evenly); ``bound="two-stage"`` (default) spends a
pilot per cell (δ/10 split evenly over the pilots) and sizes a fresh second batch by the
binomial tail bounds of Zubkov & Serov (2013) over the pilot's interval, the other 9δ/10
shared among the cells in proportion to the variance their pilot allows
(:mod:`virtspec_mi.exchange.sizing`); cells near 0 or 1 (low roughness: E ≈ 1) then need
a small fraction of Hoeffding's rays. A BSDF weight rounded into [0, 1] adds its largest bias to the cell's
tolerance (``certified_epsilon``: Mitsuba's Beckmann G₁ overshoots 1 by 6·10⁻⁵);
weight violations or invalid directions leave a cell uncertified (NaN).

**Between the cells.** Linear interpolation between certified cells carries an error
that the rays do not bound: it depends on E″, which no finite set of readings
certifies without a smoothness assumption. :meth:`AlbedoTable.interpolation_estimate`
states h²|E″|/8 with |E″| estimated from the certified second divided differences
(|Δ²Ê| + 4ε bounds |Δ²E| for certain, the step from Δ² to E″ is the assumption);
:meth:`AlbedoTable.interpolate` with :meth:`AlbedoTable.compare` checks an interpolated
table against a certified table of the midpoints, which *is* a certified statement at
those points.

Runs: the cells are traced by :func:`virtspec_mi.sweep` calls (parameter sweeps over
α — and η — at each θ_i), grouped by the number of rays they need. With
``checkpoint=DIR`` (or ``out=FILE``: ``FILE.parts``) every finished group is written
there and a re-run traces only the missing ones (the same counts as an uninterrupted
run: every group's seed is derived from ``seed`` and the group's identity).

References
----------
Kulla, C., Conty, A. (2017). Revisiting physically based shading at Imageworks. SIGGRAPH
course *Physically Based Shading in Theory and Practice*: E(μ), E_avg, energy compensation.
Walter, B. et al. (2007). Microfacet models for refraction through rough surfaces. EGSR.
Hoeffding, W. (1963). JASA 58, 13–30: Theorem 1, eq. (2.3).
Zubkov, A.M., Serov, A.A. (2013). Theory of Probability and its Applications 57(3),
539–544: Theorem 1.
Baranoski, G.V.G., Rokne, J.G., Xu, G. (2001). The Visual Computer 17, 506–518: eqs. (2), (23).
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import re
import time
import warnings
from contextlib import nullcontext
from dataclasses import dataclass, field
from datetime import datetime, timezone
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from virtspec_mi import __version__
from virtspec_mi.checks import check_delta, number, shown_value
from virtspec_mi.engine import interrupts
from virtspec_mi.engine.checkpoint import locked
from virtspec_mi.settings import true_or_false, whole_number
from virtspec_mi.exchange.common import atomic_write, check_companions, derived_seed
from virtspec_mi.exchange.conventions import Convention, convention
from virtspec_mi.exchange.sizing import (binomial_rays, clopper_pearson_each, pilot_intervals, stage_two_shares,
                                         union_hoeffding_rays, union_hoeffding_rays_array)

__all__ = ["MODELS", "DISTRIBUTIONS", "BOUNDS", "TableBudget", "AlbedoTable", "TableComparison", "albedo_table",
           "read_albedo_table"]

MODELS: dict[str, str] = {
    "conductor": "Mitsuba roughconductor, Fresnel = 1 (material none): E = reflected",
    "glass": "Mitsuba roughdielectric: E = reflected + transmitted, light from outside (eta) and inside (1/eta)",
}
"""Models a table can hold, and what E counts."""

DISTRIBUTIONS: tuple[str, ...] = ("ggx", "beckmann")
"""Microfacet distributions (Mitsuba's ``distribution``)."""

@dataclass(frozen=True)
class TableBudget:
    """A table's ray budget: what it does, whether a pilot sizes each cell, how it splits δ (``split``)."""

    description: str
    adaptive: bool
    split: str

    def split_words(self, cells: int, quantities: int) -> str:
        """How δ is split over this table's cells and quantities, for its certificate."""

        return self.split.format(cells=cells, quantities=quantities)


BOUNDS: dict[str, TableBudget] = {
    "two-stage": TableBudget("a pilot per cell, then a fresh batch sized by the Zubkov-Serov binomial bound over the "
                             "pilot's interval", True,
                             "delta/10 over the {cells:,} pilots, 9 delta/10 over the second batches by pilot variance"),
    "hoeffding": TableBudget("every cell N = ceil(ln(2 C |Q| / delta) / (2 epsilon^2)) rays", False,
                             "delta split evenly over {cells:,} cells x {quantities} quantities"),
}
"""Ray budgets of a table, by name (:mod:`virtspec_mi.exchange.sizing`)."""

SIDES: tuple[str, ...] = ("outside", "inside")
"""Glass: light arriving from outside (relative index η) or from inside (1/η)."""

_CLASS_STEP = 2.0 ** 0.125  # cells are traced in groups whose rays differ by at most this factor
_FORMAT = "virtspec-mi albedo table 1"


# ----------------------------------------------------------------------------- the table

@dataclass(frozen=True, eq=False)
class AlbedoTable:
    """
    A certified table of E(μ, α[, η]) and E_avg(α[, η]) (see the module docstring).

    Canonical dims: conductor E ``("mu", "alpha")``, E_avg ``("alpha",)``; glass E
    ``("side", "eta", "mu", "alpha")``, E_avg ``("side", "eta", "alpha")``. Files are
    written in the engine's memory order (:attr:`order`).

    Attributes
    ----------
    model, distribution : str
        :data:`MODELS` key and ``ggx`` / ``beckmann``.
    mu, alpha : ndarray
        Grid nodes (μ = cos θ_i; α the Mitsuba roughness).
    eta : ndarray or None
        Glass: the relative indices of the ``outside`` side (``inside`` uses 1/η).
    roughness : ndarray or None
        The engine's roughness (α = roughness²) when its convention has one.
    engine : str
        ``cycles``, ``filament``, ``unreal`` or ``grid``.
    order : tuple of str
        The engine's memory order of E (slowest first), e.g. ``("mu", "alpha")``.
    counts : dict of str to ndarray
        Exact int64 counts of the cells' estimating batches: ``rays``, ``reflected``,
        ``transmitted``, ``rounded_weights``, ``weight_violations``, ``invalid_directions``,
        ``capped``; ``pilot_rays`` (0 for ``hoeffding``) and ``pilot_violations``; and
        ``interval_delta`` (float: each cell's δ per quantity, :meth:`interval_delta`).
    average_counts : dict of str to ndarray or None
        The same for E_avg (diffuse beam); ``None`` when not measured.
    epsilon, delta : float
        Tolerance of every value and the joint failure probability of the whole table.
    bound : str
        :data:`BOUNDS` key.
    quantities : tuple of str
        Quantities certified per cell: ``E`` and, for glass with ``parts=True``, ``E_R``, ``E_T``.
    provenance : dict
        Seed, wavelength, Mitsuba and virtspec-mi versions, seconds, creation time, rays.
    """

    model: str
    distribution: str
    mu: np.ndarray
    alpha: np.ndarray
    eta: np.ndarray | None
    roughness: np.ndarray | None
    engine: str
    order: tuple[str, ...]
    counts: dict[str, np.ndarray]
    average_counts: dict[str, np.ndarray] | None
    epsilon: float
    delta: float
    bound: str
    quantities: tuple[str, ...] = ("E",)
    provenance: dict[str, Any] = field(default_factory=dict)

    # -- dims ------------------------------------------------------------------------

    @property
    def dims(self) -> tuple[str, ...]:
        """Canonical dims of E."""

        return ("side", "eta", "mu", "alpha") if self.model == "glass" else ("mu", "alpha")

    @property
    def average_dims(self) -> tuple[str, ...]:
        return ("side", "eta", "alpha") if self.model == "glass" else ("alpha",)

    @property
    def cells(self) -> int:
        """C: the certified cells, E_avg values included."""

        average = 0 if self.average_counts is None else self.average_counts["rays"].size
        return int(self.counts["rays"].size + average)

    def interval_delta(self, average: bool = False) -> np.ndarray:
        """
        Per cell, δ of each quantity's estimating batch: δ/(C|Q|) for ``hoeffding``; for
        ``two-stage`` the cell's share of 0.9δ (:func:`~virtspec_mi.exchange.sizing.stage_two_shares`,
        its pilots having 0.1δ). They add up to at most δ over the table.
        """

        counts = self.average_counts if average else self.counts
        if counts is None:
            raise ValueError("this table has no E_avg (made with average=False)")
        return counts["interval_delta"]

    # -- values ----------------------------------------------------------------------

    def _value(self, counts: dict[str, np.ndarray] | None, quantity: str) -> np.ndarray | None:
        if counts is None:
            return None
        if quantity == "E":
            hits = counts["reflected"] + counts["transmitted"]
        elif quantity == "E_R":
            hits = counts["reflected"]
        elif quantity == "E_T":
            hits = counts["transmitted"]
        else:
            raise ValueError(f"quantity must be one of E, E_R, E_T (got {quantity!r})")
        return hits / counts["rays"]

    @property
    def E(self) -> np.ndarray:
        """Ê = (reflected + transmitted)/N per cell, canonical dims."""

        return self._value(self.counts, "E")

    @property
    def E_R(self) -> np.ndarray:
        return self._value(self.counts, "E_R")

    @property
    def E_T(self) -> np.ndarray:
        return self._value(self.counts, "E_T")

    @property
    def E_avg(self) -> np.ndarray | None:
        """Ê_avg from the diffuse-beam readings (``None`` when not measured)."""

        return self._value(self.average_counts, "E")

    def quantity(self, name: str, average: bool = False) -> np.ndarray:
        """``E``, ``E_R`` or ``E_T`` of the cells (``average=True``: of E_avg)."""

        values = self._value(self.average_counts if average else self.counts, name)
        if values is None:
            raise ValueError("this table has no E_avg (made with average=False)")
        return values

    # -- certificate -----------------------------------------------------------------

    def _certified(self, counts: dict[str, np.ndarray]) -> np.ndarray:
        return ((counts["weight_violations"] == 0) & (counts["invalid_directions"] == 0) & (counts["capped"] == 0)
                & (counts["pilot_violations"] == 0))

    def certified_epsilon(self, average: bool = False) -> np.ndarray:
        """
        Per cell, the tolerance the certificate gives: ε plus the largest bias of BSDF
        weights rounded into [0, 1] (rounded·10⁻⁴/N); NaN where the cell is not certified
        (weight violations, invalid directions or capped walks in its batches).
        """

        from virtspec_mi.kernel.counts import WEIGHT_ROUNDING

        counts = self.average_counts if average else self.counts
        if counts is None:
            raise ValueError("this table has no E_avg (made with average=False)")
        bias = counts["rounded_weights"] * WEIGHT_ROUNDING / counts["rays"]
        return np.where(self._certified(counts), self.epsilon + bias, np.nan)

    @property
    def certified(self) -> bool:
        """True when every value of the table is certified."""

        ok = bool(np.all(self._certified(self.counts)))
        return ok and (self.average_counts is None or bool(np.all(self._certified(self.average_counts))))

    def interval(self, quantity: str = "E", average: bool = False) -> tuple[np.ndarray, np.ndarray]:
        """
        Clopper–Pearson interval of each cell's ``quantity`` from its estimating batch, at
        its :meth:`interval_delta` (all of them hold at once with probability ≥ 1 − δ).
        """

        counts = self.average_counts if average else self.counts
        values = self.quantity(quantity, average)
        hits = np.rint(values * counts["rays"]).astype(np.int64)
        return clopper_pearson_each(hits, counts["rays"], counts["interval_delta"])

    @property
    def rays(self) -> int:
        """Every ray traced for the table (pilots included)."""

        total = int(self.counts["rays"].sum() + self.counts["pilot_rays"].sum())
        if self.average_counts is not None:
            total += int(self.average_counts["rays"].sum() + self.average_counts["pilot_rays"].sum())
        return total

    def statement(self) -> str:
        """The certificate in one sentence."""

        worst = np.nanmax(self.certified_epsilon())
        if self.average_counts is not None:
            worst = max(worst, np.nanmax(self.certified_epsilon(average=True)))
        what = " and ".join(self.quantities) + (" and E_avg" if self.average_counts is not None else "")
        if not self.certified:
            bad = int(np.isnan(self.certified_epsilon()).sum())
            if self.average_counts is not None:
                bad += int(np.isnan(self.certified_epsilon(average=True)).sum())
            return (f"NOT CERTIFIED: {bad:,} of {self.cells:,} values had weight violations, invalid directions or "
                    f"capped walks (certified_epsilon is NaN there); the others: |value - true| < {worst:.4g}")
        split = BOUNDS[self.bound].split_words(self.cells, len(self.quantities))
        return (f"every value ({what}; {self.cells:,} cells) within {worst:.4g} of the model's true value at once "
                f"with probability >= {1 - self.delta:g} (bound {self.bound}: {split}; union bound)")

    # -- interpolation ----------------------------------------------------------------

    def interpolation_estimate(self) -> dict[str, np.ndarray]:
        """
        Per axis (``mu``, ``alpha``), h²·|E″|/8 between each pair of neighbouring nodes,
        with |E″| ≈ 2(|Ê[x₀,x₁,x₂]| + 2ε(1/h₀ + 1/h₁)/(h₀ + h₁)), the larger of the two
        adjacent triples (Ê[·] the second divided difference; the added term bounds what
        ε-accurate values can change it): an *estimate* of the linear-interpolation error
        under the assumption that E″ varies little over three nodes (the rays certify the
        divided differences, not E″).
        Arrays along the axis have one entry fewer than the nodes (NaN where no triple).
        """

        out: dict[str, np.ndarray] = {}
        values = self.E
        for axis_name in ("mu", "alpha"):
            axis = self.dims.index(axis_name)
            nodes = getattr(self, axis_name)
            order = np.argsort(nodes)
            x = nodes[order]
            v = np.take(values, order, axis=axis)
            v = np.moveaxis(v, axis, -1)
            n = len(x)
            if n < 3:
                out[axis_name] = np.full(v.shape[:-1] + (max(n - 1, 0),), np.nan)
                continue
            d0, d1 = x[1:-1] - x[:-2], x[2:] - x[1:-1]
            # second divided difference E[x0,x1,x2] = ((v2-v1)/d1 - (v1-v0)/d0)/(d0+d1) ≈ E''/2
            dd = ((v[..., 2:] - v[..., 1:-1]) / d1 - (v[..., 1:-1] - v[..., :-2]) / d0) / (d0 + d1)
            slack = 2 * self.epsilon * (1 / d0 + 1 / d1) / (d0 + d1)  # the most ε-accurate values can move it
            curvature = 2 * (np.abs(dd) + slack)
            h = np.diff(x)
            left = np.concatenate([np.full(v.shape[:-1] + (1,), np.nan), curvature], axis=-1)
            right = np.concatenate([curvature, np.full(v.shape[:-1] + (1,), np.nan)], axis=-1)
            worst = np.fmax(left, right)
            out[axis_name] = h * h * worst / 8.0
        return out

    def interpolate(self, mu: Any, alpha: Any, side: str = "outside", eta: float | None = None) -> np.ndarray:
        """
        Ê linearly interpolated at (μ, α) pairs (broadcast), within the grid's range; glass:
        on one ``side`` at one of the table's ``eta`` nodes.
        """

        from scipy.interpolate import RegularGridInterpolator

        values = self.E
        if self.model == "glass":
            if eta is None or not np.any(np.isclose(self.eta, eta)):
                raise ValueError(f"eta must be one of the table's eta nodes for a glass table (got {eta!r})")
            values = values[SIDES.index(side), int(np.argmin(np.abs(self.eta - eta)))]
        mu_order, alpha_order = np.argsort(self.mu), np.argsort(self.alpha)
        grid = RegularGridInterpolator((self.mu[mu_order], self.alpha[alpha_order]),
                                       values[np.ix_(mu_order, alpha_order)], method="linear")
        mu, alpha = np.broadcast_arrays(np.asarray(mu, dtype=np.float64), np.asarray(alpha, dtype=np.float64))
        return grid(np.stack([mu.ravel(), alpha.ravel()], axis=-1)).reshape(mu.shape)

    # -- layout and files ---------------------------------------------------------------

    def layout(self, values: np.ndarray | None = None, average: bool = False) -> np.ndarray:
        """
        ``values`` (default Ê; canonical dims) in the engine's memory order: conductor
        E ``order``; glass ``("side", *order)``; E_avg in the order of its own dims.
        """

        if average:
            return self.E_avg if values is None else values
        values = self.E if values is None else values
        dims = list(self.dims)
        target = (["side"] if self.model == "glass" else []) + list(self.order)
        return np.transpose(values, [dims.index(d) for d in target])

    def to_dataset(self) -> Any:
        """The table as an ``xarray.Dataset`` (canonical dims), counts and certificate included."""

        import xarray as xr

        coords: dict[str, Any] = {"mu": self.mu, "alpha": self.alpha}
        if self.roughness is not None:
            coords["roughness"] = ("alpha", self.roughness)
        if self.model == "glass":
            coords["side"] = list(SIDES)
            coords["eta"] = self.eta
            coords["relative_eta"] = (("side", "eta"), np.stack([self.eta, 1.0 / self.eta]))
        data: dict[str, Any] = {}
        dims, adims = self.dims, self.average_dims
        for name in ("E", "E_R", "E_T") if self.model == "glass" else ("E",):
            data[name] = (dims, self.quantity(name))
            lower, upper = self.interval(name)
            data[f"{name}_lower"], data[f"{name}_upper"] = (dims, lower), (dims, upper)
        data["certified_epsilon"] = (dims, self.certified_epsilon())
        for key, value in self.counts.items():
            data[key] = (dims, value)
        if self.average_counts is not None:
            for name in ("E", "E_R", "E_T") if self.model == "glass" else ("E",):
                data[f"{name}_avg"] = (adims, self.quantity(name, average=True))
                lower, upper = self.interval(name, average=True)
                data[f"{name}_avg_lower"], data[f"{name}_avg_upper"] = (adims, lower), (adims, upper)
            data["certified_epsilon_avg"] = (adims, self.certified_epsilon(average=True))
            for key, value in self.average_counts.items():
                data[f"avg_{key}"] = (adims, value)
        attrs = {"format": _FORMAT, "model": self.model, "distribution": self.distribution, "engine": self.engine,
                 "order": " ".join(self.order), "epsilon": self.epsilon, "delta": self.delta, "bound": self.bound,
                 "quantities": " ".join(self.quantities),
                 "certificate": self.statement(), "rays_total": self.rays,
                 "provenance": json.dumps(self.provenance, sort_keys=True)}
        return xr.Dataset(data, coords=coords, attrs=attrs)

    @classmethod
    def from_dataset(cls, dataset: Any) -> "AlbedoTable":
        attrs = dataset.attrs
        if attrs.get("format") != _FORMAT:
            raise ValueError(f"not a virtspec-mi albedo table (format {attrs.get('format')!r}, expected {_FORMAT!r})")
        model = str(attrs["model"])
        keys = ("rays", "reflected", "transmitted", "rounded_weights", "weight_violations", "invalid_directions",
                "capped", "pilot_rays", "pilot_violations")
        missing = [k for k in keys + ("interval_delta", "mu", "alpha") if k not in dataset.variables]
        if missing:
            raise ValueError(f"albedo table: {', '.join(map(repr, missing))} missing")
        counts = {k: _table_counts(dataset[k].values, k) for k in keys}
        counts["interval_delta"] = np.asarray(dataset["interval_delta"].values, dtype=np.float64)
        average = None
        if "avg_rays" in dataset:
            average = {k: _table_counts(dataset[f"avg_{k}"].values, f"avg_{k}") for k in keys}
            average["interval_delta"] = np.asarray(dataset["avg_interval_delta"].values, dtype=np.float64)
        table = cls._built(dataset, attrs, model, counts, average)
        table._check_read(dataset)
        return table

    def _check_read(self, dataset: Any) -> None:
        """
        A table file read as strictly as a result file (:mod:`virtspec_mi.results.integrity`): counts that add up
        (each part within its rays, rays >= 1), an ε the rays can hold (N > 1/ε: no N smaller holds a fraction within
        ε), and every value it shows besides its counts — E, the intervals, ε' per cell, the certificate — equal to
        what the counts and settings give (an edited value is refused, not stated as certified).
        """

        for prefix, counts in (("", self.counts), ("avg_", self.average_counts)):
            if counts is None:
                continue
            rays = counts["rays"]
            if np.any(rays < 1):
                raise ValueError(f"albedo table: '{prefix}rays' holds {int(rays.min())}: every cell needs rays >= 1")
            for part, whole in (("reflected", "rays"), ("transmitted", "rays"), ("rounded_weights", "rays"),
                                ("weight_violations", "rays"), ("invalid_directions", "rays"), ("capped", "rays"),
                                ("pilot_violations", "pilot_rays")):
                if np.any(counts[part] > counts[whole]):
                    raise ValueError(f"albedo table: '{prefix}{part}' holds a count above '{prefix}{whole}'")
            if np.any(counts["reflected"] + counts["transmitted"] > rays):
                raise ValueError(f"albedo table: '{prefix}reflected' + '{prefix}transmitted' exceed '{prefix}rays'")
            if np.any(rays * self.epsilon <= 1.0):
                raise ValueError(f"albedo table: epsilon = {self.epsilon:g} cannot be certified with "
                                 f"{int(rays.min()):,} rays a cell (N > 1/epsilon is needed)")
            delta = counts["interval_delta"]
            if not np.all((delta > 0) & (delta <= self.delta)):
                raise ValueError(f"albedo table: '{prefix}interval_delta' must lie in (0, delta = {self.delta:g}]")
        shown = self.to_dataset()
        for name in shown.data_vars:
            if name in dataset and not np.array_equal(np.asarray(dataset[name].values), np.asarray(shown[name].values),
                                                      equal_nan=True):
                raise ValueError(f"albedo table: '{name}' disagrees with the counts and settings it is made from "
                                 "(edited?)")
        for name in ("certificate", "rays_total"):
            if str(dataset.attrs.get(name)) != str(shown.attrs[name]):
                raise ValueError(f"albedo table: the attribute '{name}' disagrees with the counts and settings "
                                 "(edited?)")

    @classmethod
    def _built(cls, dataset: Any, attrs: Any, model: str, counts: dict, average: dict | None) -> "AlbedoTable":
        return cls(model, str(attrs["distribution"]), np.asarray(dataset["mu"].values, dtype=np.float64),
                   np.asarray(dataset["alpha"].values, dtype=np.float64),
                   np.asarray(dataset["eta"].values, dtype=np.float64) if model == "glass" else None,
                   np.asarray(dataset["roughness"].values, dtype=np.float64) if "roughness" in dataset.coords else None,
                   str(attrs["engine"]), tuple(str(attrs["order"]).split()), counts, average,
                   float(attrs["epsilon"]), float(attrs["delta"]), str(attrs["bound"]),
                   tuple(str(attrs["quantities"]).split()), json.loads(str(attrs["provenance"])))

    def check_output(self, path: str | os.PathLike, overwrite: bool = False) -> None:
        """Refuse companions of ``path`` that would replace a file not written by this format (see :meth:`write`)."""

        _check_output(Path(path), self.E_avg is not None, overwrite)

    def write(self, path: str | os.PathLike, overwrite: bool = False) -> Path:
        """
        Write the table: ``.nc`` (NetCDF of :meth:`to_dataset`), ``.npy`` (Ê as float32 in
        the engine's memory order; E_avg in ``NAME_avg.npy``; provenance and certificate in
        ``NAME.json``) or ``.h`` / ``.hpp`` (a C header in Cycles' layout,
        :mod:`virtspec_mi.exchange.header`). A ``.npy``'s companions replace files of their
        names only when those are an albedo table's (its ``NAME.json`` says so) or with
        ``overwrite=True`` (else ``ValueError``, before anything is written).
        """

        from virtspec_mi.exchange.header import write_header

        path = Path(path)
        suffix = path.suffix.lower()
        self.check_output(path, overwrite)
        if suffix == ".nc":
            atomic_write(path, lambda tmp: self.to_dataset().to_netcdf(tmp))
        elif suffix == ".npy":
            atomic_write(path, lambda tmp: _save_npy(tmp, self.layout().astype(np.float32)))
            if self.E_avg is not None:
                avg = path.with_name(path.stem + "_avg.npy")
                atomic_write(avg, lambda tmp: _save_npy(tmp, self.E_avg.astype(np.float32)))
            sidecar = path.with_suffix(".json")
            atomic_write(sidecar, lambda tmp: Path(tmp).write_text(json.dumps(self.description(), indent=1)))
        elif suffix in (".h", ".hpp"):
            atomic_write(path, lambda tmp: Path(tmp).write_text(write_header(self)))
        else:
            raise ValueError(f"path must end in .nc, .npy, .h or .hpp (got {path.name!r})")
        return path

    def description(self) -> dict[str, Any]:
        """Provenance, layout and certificate as plain data (the ``.npy`` sidecar, the header's comment)."""

        return {"format": _FORMAT, "model": self.model, "model_description": MODELS[self.model],
                "distribution": self.distribution, "engine": self.engine,
                "order": list((["side"] if self.model == "glass" else []) + list(self.order)),
                "average_order": list(self.average_dims), "shape": list(self.layout().shape),
                "mu": self.mu.tolist(), "alpha": self.alpha.tolist(),
                "roughness": None if self.roughness is None else self.roughness.tolist(),
                "eta_outside": None if self.eta is None else self.eta.tolist(),
                "epsilon": self.epsilon, "delta": self.delta, "bound": self.bound, "quantities": list(self.quantities),
                "certificate": self.statement(), "rays_total": self.rays,
                "worst_certified_epsilon": float(np.nanmax(self.certified_epsilon())),
                "provenance": self.provenance}

    # -- reading and comparing -----------------------------------------------------------

    def compare(self, published: Any, *, average: bool = False, side: str = "outside", array: str | None = None,
                rounding: float = 0.0) -> "TableComparison":
        """
        Every cell where a published table falls outside this table's certified interval.

        Parameters
        ----------
        published
            An array, or a file: ``.npy``, ``.nc`` (variable ``E``/``E_avg``), ``.csv`` /
            ``.txt`` (numbers), or a C/C++ header holding ``float NAME[...] = {...};``
            (``array`` names it; default: this table's own array name, else the only one).
            Values in this table's engine memory order (:meth:`layout`), for glass one
            ``side``'s block (``[eta][mu][alpha]`` in Cycles' order).
        average
            Compare E_avg instead of E.
        side
            Glass: ``outside`` or ``inside`` (Cycles' ``_inv_`` tables).
        rounding
            The published values' own rounding (e.g. 5e-7 for six decimals), added to
            the interval: a rounded number cannot be held to more than its digits.

        Returns
        -------
        TableComparison
            The flagged cells with their coordinates, published value and certified interval.
        """

        from virtspec_mi.exchange.header import read_table_values

        if side not in SIDES:
            raise ValueError(f"side must be one of {', '.join(SIDES)} (got {side!r})")
        if side != "outside" and self.model != "glass":
            raise ValueError(f"side={side!r} names a glass table's block; a {self.model} table has one side (leave side "
                             "as 'outside')")
        if not (np.isfinite(rounding) and rounding >= 0):
            raise ValueError(f"rounding must be a finite number >= 0 (got {rounding!r})")
        mine = self.layout(average=average)
        tol = self.certified_epsilon(average=average)
        if not average:
            tol = self.layout(tol)
        if self.model == "glass":
            mine, tol = mine[SIDES.index(side)], tol[SIDES.index(side)]
        own = _own_table(published) if array is None else None
        if own is not None:  # an albedo table's .nc: canonical (mu, alpha) order, put in this table's memory order
            values = own.E_avg if average else self.layout(np.asarray(own.E))
            if values is None or np.shape(values) != np.shape(self.layout(average=average)):
                raise ValueError(f"the published table {published} is an albedo table of another grid "
                                 f"(shape {np.shape(own.E)}; this table's {np.shape(self.E)})")
            if self.model == "glass":  # one side's block, as the table's own values above
                values = values[SIDES.index(side)]
        else:
            if array is None and not isinstance(published, np.ndarray):
                from virtspec_mi.exchange.header import array_name

                array = array_name(self, average=average, side=side)
            values = read_table_values(published, array=array, expected=mine.size)
        values = np.asarray(values, dtype=np.float64).reshape(mine.shape)
        outside = ~(np.abs(values - mine) < tol + rounding)  # NaN tolerance (uncertified): reported too
        dims = list(self.average_dims if average else (["side"] if self.model == "glass" else []) + list(self.order))
        if self.model == "glass":
            dims = dims[1:]
        coords = {"mu": self.mu, "alpha": self.alpha, "eta": None if self.eta is None else
                  (self.eta if side == "outside" else 1.0 / self.eta)}
        flagged = []
        for index in zip(*np.nonzero(outside)):
            label = {d: float(coords[d][i]) for d, i in zip(dims, index)}
            flagged.append({"index": tuple(int(i) for i in index), **label, "published": float(values[index]),
                            "certified": float(mine[index]), "tolerance": float(tol[index])})
        return TableComparison(self, values, tuple(dims), flagged, int(mine.size), average, side, rounding)


@dataclass(frozen=True, eq=False)
class TableComparison:
    """A published table against a certified one (:meth:`AlbedoTable.compare`)."""

    table: AlbedoTable
    published: np.ndarray
    dims: tuple[str, ...]
    outside: list[dict[str, Any]]
    cells: int
    average: bool
    side: str
    rounding: float

    @property
    def share_outside(self) -> float:
        return len(self.outside) / self.cells

    def summary(self, limit: int = 20) -> str:
        what = "E_avg" if self.average else "E"
        side = f" ({self.side})" if self.table.model == "glass" else ""
        head = (f"{what}{side}: {len(self.outside):,} of {self.cells:,} published cells outside the certified interval "
                f"(|published - certified| >= epsilon' + rounding {self.rounding:g}; the certificate: "
                f"{self.table.statement()})")
        if not self.outside:
            return head
        lines = [head, "  " + "  ".join(f"{d:>9}" for d in self.dims) + "  published  certified  epsilon'"]
        for cell in self.outside[:limit]:
            lines.append("  " + "  ".join(f"{cell[d]:9.5g}" for d in self.dims)
                         + f"  {cell['published']:9.6f}  {cell['certified']:9.6f}  {cell['tolerance']:.3g}")
        if len(self.outside) > limit:
            lines.append(f"  ... and {len(self.outside) - limit:,} more")
        return "\n".join(lines)


def read_albedo_table(path: str | os.PathLike) -> AlbedoTable:
    """An :class:`AlbedoTable` from a NetCDF file written by :meth:`AlbedoTable.write`."""

    path = Path(path)
    if path.suffix.lower() != ".nc":
        raise ValueError(f"path must be a .nc file written by AlbedoTable.write (got {path.name!r})")
    from virtspec_mi.files import read_netcdf

    try:
        return AlbedoTable.from_dataset(read_netcdf(path, "albedo table"))
    except ValueError as error:
        text = str(error)
        raise ValueError(text.replace("albedo table:", f"albedo table {path}:", 1)) from None


def _own_table(published: Any) -> "AlbedoTable | None":
    """The :class:`AlbedoTable` of a published ``.nc`` written by :meth:`AlbedoTable.write` (else ``None``)."""

    if not isinstance(published, (str, os.PathLike)) or Path(published).suffix.lower() != ".nc":
        return None
    if not Path(published).is_file():
        return None
    import xarray as xr

    try:
        with xr.open_dataset(published) as dataset:
            if dataset.attrs.get("format") != _FORMAT:
                return None
    except Exception:  # not a NetCDF file: read_table_values says so
        return None
    return read_albedo_table(published)


def _table_counts(values: Any, name: str) -> np.ndarray:
    """A table file's counts: whole numbers >= 0 (:func:`virtspec_mi.results.integrity.whole_counts`)."""

    from virtspec_mi.results.integrity import whole_counts

    try:
        return whole_counts(values, name)
    except ValueError as error:
        raise ValueError(f"albedo table: {error}") from None


def _check_output(path: Path, average: bool, overwrite: bool) -> None:
    """A ``.npy`` output's companions (``NAME.json``, ``NAME_avg.npy``) replace only an albedo table's files."""

    if path.suffix.lower() != ".npy":
        return
    companions = [path.with_suffix(".json")] + ([path.with_name(path.stem + "_avg.npy")] if average else [])
    check_companions(path, companions, lambda companion: _ours(path), overwrite,
                     flag="overwrite=True (virtspec albedo-table --overwrite)")


def _check_epsilon(epsilon: Any) -> float:
    """ε of a table: a real number, 0 < ε < 0.5 (as μ: :func:`virtspec_mi.checks.check_mu`, named ``epsilon``)."""

    value = number("epsilon", epsilon)
    if not 0.0 < value < 0.5:
        raise ValueError(f"epsilon must satisfy 0 < epsilon < 0.5 (got {shown_value(epsilon)})")
    return value


def _whole(name: str, value: Any, low: int, high: int) -> int:
    """A whole number given as a number (a string or a boolean refused), ``low`` <= value <= ``high``."""

    if isinstance(value, str):
        raise ValueError(f"{name} must be a whole number, not a string (got {value!r})")
    return whole_number(name, low, high, f"{low} <= {name} <= {high}")(value)


def _ours(npy: Path) -> bool:
    """Whether ``NAME.json`` beside a table's ``NAME.npy`` is an albedo table's sidecar (so are its companions)."""

    try:
        return json.loads(npy.with_suffix(".json").read_text(encoding="utf-8")).get("format") == _FORMAT
    except (OSError, ValueError, AttributeError):
        return False


def _save_npy(path: str, values: np.ndarray) -> None:
    with open(path, "wb") as handle:
        np.save(handle, values)



# ----------------------------------------------------------------------------- measuring

@dataclass(frozen=True)
class _Grid:
    model: str
    distribution: str
    mu: np.ndarray
    alpha: np.ndarray
    eta: np.ndarray | None
    roughness: np.ndarray | None
    engine: str
    order: tuple[str, ...]

    @property
    def points(self) -> np.ndarray:
        """Parameter points (α[, relative η]) of the canonical cells, shape (P, 1 or 2)."""

        if self.model == "conductor":
            return self.alpha[:, None]
        sides = np.concatenate([self.eta, 1.0 / self.eta])  # (side, eta) flattened
        a, e = np.meshgrid(self.alpha, sides, indexing="ij")  # (alpha, side·eta)
        return np.stack([a.ravel(), e.ravel()], axis=-1)

    def canonical(self, values: np.ndarray) -> np.ndarray:
        """(μ, P) cell values → canonical dims of E."""

        if self.model == "conductor":
            return values
        n_a, n_e = len(self.alpha), len(self.eta)
        v = values.reshape(len(self.mu), n_a, 2, n_e)
        return np.transpose(v, (2, 3, 0, 1))

    def canonical_average(self, values: np.ndarray) -> np.ndarray:
        """(P,) E_avg values → canonical dims of E_avg."""

        if self.model == "conductor":
            return values
        v = values.reshape(len(self.alpha), 2, len(self.eta))
        return np.transpose(v, (1, 2, 0))


def _check_nodes(name: str, values: Any, low: float, high: float, open_low: bool = False) -> np.ndarray:
    if any(isinstance(value, (bool, np.bool_, str)) for value in np.ravel(np.asarray(values, dtype=object))):
        raise ValueError(f"{name} must be a sequence of numbers (got {values!r})")
    try:
        array = np.atleast_1d(np.asarray(values, dtype=np.float64))
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a sequence of numbers (got {values!r})") from None
    if array.ndim != 1 or array.size == 0:
        raise ValueError(f"{name} must be a non-empty one-dimensional sequence of numbers")
    bad = ~np.isfinite(array) | (array > high) | ((array <= low) if open_low else (array < low))
    if np.any(bad):
        rule = f"{low:g} < {name} <= {high:g}" if open_low else f"{low:g} <= {name} <= {high:g}"
        raise ValueError(f"{name} must satisfy {rule} (got {array[bad][0]!r})")
    if len(np.unique(array)) != len(array):
        raise ValueError(f"{name} nodes must be distinct (got repeated values)")
    return array


def _grid(model: str, distribution: str, engine: str | None, mu: Any, alpha: Any, roughness: Any,
          eta: Any) -> _Grid:
    if model not in MODELS:
        raise ValueError(f"model must be one of {', '.join(MODELS)} (got {model!r})")
    if distribution not in DISTRIBUTIONS:
        raise ValueError(f"distribution must be one of {', '.join(DISTRIBUTIONS)} (got {distribution!r})")
    if alpha is not None and roughness is not None:
        raise ValueError("give alpha or roughness (alpha = roughness^2), not both")
    given = mu is not None or alpha is not None or roughness is not None or eta is not None
    if engine is not None and given:
        raise ValueError(f"engine={engine!r} fixes the grid: give engine=None with mu, alpha (or roughness)"
                         + (" and eta" if model == "glass" else ""))
    if engine is not None:
        conv: Convention = convention(engine, model)
        return _Grid(model, distribution, conv.mu, conv.alpha, conv.eta, conv.roughness, conv.name, conv.order)
    if mu is None or (alpha is None and roughness is None) or (model == "glass" and eta is None):
        raise ValueError("give engine (cycles, filament, unreal) or the grid: mu and alpha (or roughness)"
                         + (" and eta" if model == "glass" else ""))
    mu = _check_nodes("mu", mu, 0.0, 1.0)
    rough = None
    if roughness is not None:
        rough = _check_nodes("roughness", roughness, 0.0, 10.0, open_low=True)
        alpha = rough * rough
    alpha = _check_nodes("alpha", alpha, 0.0, 10.0, open_low=True)
    etas = None
    if model == "glass":
        etas = _check_nodes("eta", eta, 0.0, 1e6, open_low=True)
        if np.any(etas < 1.0):
            raise ValueError("eta must satisfy eta >= 1 (the outside index; the inside side uses 1/eta)")
    elif eta is not None:
        raise ValueError("eta is a glass parameter (model='glass')")
    order = ("eta", "mu", "alpha") if model == "glass" else ("mu", "alpha")
    return _Grid(model, distribution, mu, alpha, etas, rough, "grid", order)


def _scene(grid: _Grid) -> dict[str, Any]:
    from virtspec_mi.scene import instrument_scene

    if grid.model == "conductor":
        bsdf = {"type": "roughconductor", "distribution": grid.distribution, "material": "none", "alpha": 0.5}
    else:
        bsdf = {"type": "roughdielectric", "distribution": grid.distribution, "alpha": 0.5, "int_ior": 1.5,
                "ext_ior": 1.0}
    return instrument_scene(bsdf)



_KEYS = ("reflected", "transmitted", "rounded_weights", "weight_violations", "invalid_directions", "capped")


class _Store:
    """
    Finished groups of a table, kept as result files in a directory (resume): ``identity.json``
    and one ``<16 hex>.nc`` per group, each written whole under its name (a temporary
    ``.<name>.<random>.tmp`` beside it, renamed).
    """

    _OURS = re.compile(r"identity\.json|[0-9a-f]{16}\.nc")
    _TEMPORARY = re.compile(r"\.(identity\.json|[0-9a-f]{16}\.nc)\.[0-9a-z]+\.tmp")

    def __init__(self, directory: Path | None, identity: dict[str, Any]) -> None:
        self.directory = directory
        self.reused = 0
        self.saved = 0
        if directory is None:
            return
        if directory.exists() and not directory.is_dir():
            raise ValueError(f"checkpoint must be a directory (got the file {directory})")
        directory.mkdir(parents=True, exist_ok=True)
        stamp = directory / "identity.json"
        text = json.dumps(identity, sort_keys=True)
        if stamp.exists():
            if stamp.read_text() != text:
                old = json.loads(stamp.read_text())
                differ = sorted(k for k in set(old) | set(identity) if old.get(k) != identity.get(k))
                raise ValueError(f"checkpoint {directory} belongs to a different table (differs in: "
                                 f"{', '.join(differ)}); re-run with the same settings, or delete it")
            self.saved = sum(1 for path in directory.iterdir() if self._OURS.fullmatch(path.name)) - 1
        else:
            atomic_write(stamp, lambda tmp: Path(tmp).write_text(text))

    def path(self, label: str) -> Path | None:
        if self.directory is None:
            return None
        return self.directory / (hashlib.blake2b(label.encode(), digest_size=8).hexdigest() + ".nc")

    def load(self, label: str) -> Any:
        path = self.path(label)
        if path is not None and path.exists():
            from virtspec_mi.results.hemispherical import Result

            self.reused += 1
            return Result.read(path)
        return None

    def save(self, label: str, result: Any) -> None:
        path = self.path(label)
        if path is not None:
            result.write(path)
            self.saved += 1

    def remove(self) -> None:
        """Remove the folder: what this store writes (identity.json, <16 hex>.nc, their temporaries), not more."""

        if self.directory is None:
            return
        for path in self.directory.iterdir():
            if self._OURS.fullmatch(path.name) or self._TEMPORARY.fullmatch(path.name):
                path.unlink()
        try:
            self.directory.rmdir()
        except OSError:
            pass


def albedo_table(
    model: str = "conductor",
    *,
    distribution: str = "ggx",
    engine: str | None = "cycles",
    mu: Sequence[float] | None = None,
    alpha: Sequence[float] | None = None,
    roughness: Sequence[float] | None = None,
    eta: Sequence[float] | None = None,
    epsilon: float = 1e-3,
    delta: float = 0.01,
    bound: str = "two-stage",
    average: bool = True,
    parts: bool = False,
    pilot_rays: int | None = None,
    seed: int = 0,
    wavelength: float = 551.0,
    checkpoint: str | os.PathLike | None = None,
    out: str | os.PathLike | Sequence[str | os.PathLike] | None = None,
    progress: bool | None = None,
    chunk_size: int | None = None,
    overwrite: bool = False,
) -> AlbedoTable:
    """
    Measure a certified albedo table (see the module docstring).

    Parameters
    ----------
    model
        ``conductor`` (``roughconductor``, Fresnel = 1) or ``glass`` (``roughdielectric``).
    distribution
        ``ggx`` or ``beckmann``.
    engine
        ``cycles`` (default), ``filament`` or ``unreal``: that engine's grid and memory
        order (:mod:`virtspec_mi.exchange.conventions`); ``None`` with ``mu`` and ``alpha``
        (or ``roughness``, α = roughness²), and ``eta`` (≥ 1) for glass.
    mu, alpha, roughness, eta
        A user grid (0 ≤ μ ≤ 1; α > 0; η ≥ 1, the inside side uses 1/η).
    epsilon, delta
        Every value within ε, the whole table at once with probability ≥ 1 − δ
        (0 < ε < 0.5, 0 < δ < 1).
    bound
        ``two-stage`` or ``hoeffding`` (:data:`BOUNDS`).
    average
        Also measure E_avg (diffuse beam) per α (and η, side).
    parts
        Glass: certify E_R and E_T too (three quantities per cell; more rays).
    pilot_rays
        Two-stage pilot per cell (default ⌈10/ε⌉).
    seed
        Seed of the run (each group's seed is derived from it).
    wavelength
        The wavelength traced (nm); the models are grey, the value only labels the rays.
    checkpoint
        Directory keeping the finished groups (resume); default with ``out``:
        ``OUT.parts`` (removed once the outputs are written).
    out
        File(s) to write when done: ``.nc``, ``.npy``, ``.h`` (:meth:`AlbedoTable.write`).
    progress
        tqdm bar on stderr: ``True`` always, ``False`` never, ``None`` when stderr is a
        terminal and the run is expected to last more than ~2 s.
    chunk_size
        Rays per kernel launch (memory only; the counts do not depend on it).
    overwrite
        Let a ``.npy`` output's companions (``NAME.json``, ``NAME_avg.npy``) replace files of those names that
        this table's format did not write (refused otherwise, before anything is traced).

    Returns
    -------
    AlbedoTable

    References
    ----------
    Kulla & Conty (2017); Hoeffding (1963), Theorem 1; Baranoski et al. (2001), eq. (23).
    """

    from virtspec_mi.api import sweep
    from virtspec_mi.engine.progress import Progress
    from virtspec_mi.runtime import mitsuba
    from virtspec_mi.scene import load_scene

    grid = _grid(model, distribution, engine, mu, alpha, roughness, eta)
    epsilon, delta = _check_epsilon(epsilon), check_delta(delta)  # any real number type (numpy's float32 too)
    average, parts = true_or_false("average")(average), true_or_false("parts")(parts)
    seed = _whole("seed", seed, 0, 2**32 - 1)
    wavelength = number("wavelength", wavelength)
    if not 0.0 < wavelength < float("inf"):
        raise ValueError(f"wavelength must be a finite number of nm > 0 (got {shown_value(wavelength)})")
    if bound not in BOUNDS:
        raise ValueError(f"bound must be one of {', '.join(BOUNDS)} (got {bound!r})")
    if parts and model != "glass":
        raise ValueError("parts=True certifies E_R and E_T of a glass table (model='glass')")
    epsilon, delta = float(epsilon), float(delta)
    n1 = math.ceil(40.0 / epsilon - 1e-9) if pilot_rays is None else _whole("pilot_rays", pilot_rays, 1, 2**32 - 1)
    outs = [] if out is None else [Path(out)] if isinstance(out, (str, os.PathLike)) else [Path(p) for p in out]
    for path in outs:
        if path.suffix.lower() not in (".nc", ".npy", ".h", ".hpp"):
            raise ValueError(f"out must end in .nc, .npy, .h or .hpp (got {path.name!r})")
        if not path.parent.exists():
            raise ValueError(f"out {path}: the directory {path.parent} does not exist")
        _check_output(path, bool(average), bool(overwrite))
    if checkpoint is None and outs:
        checkpoint = outs[0].with_name(outs[0].name + ".parts")
    quantities = ("E", "E_R", "E_T") if parts else ("E",)
    q = len(quantities)

    mi = mitsuba()
    points = grid.points
    n_mu, n_p = len(grid.mu), len(points)
    n_cells = n_mu * n_p + (n_p if average else 0)
    theta = np.degrees(np.arccos(grid.mu))
    names = ["specimen.alpha"] + (["specimen.eta"] if model == "glass" else [])
    identity = {"format": _FORMAT, "model": model, "distribution": distribution, "mu": grid.mu.tolist(),
                "alpha": grid.alpha.tolist(), "eta": None if grid.eta is None else grid.eta.tolist(),
                "epsilon": epsilon, "delta": delta, "bound": bound, "average": bool(average), "parts": bool(parts),
                "pilot_rays": n1, "seed": int(seed), "wavelength": float(wavelength), "version": __version__}
    # One run at a time on a checkpoint (a second refuses; it never touches the first's groups), and signals
    # acted on at safe points only: never inside a write (a KeyboardInterrupt inside xarray's file lock hung
    # the process, and left a temporary file)
    if checkpoint is not None:  # the parts' writer, imported here (a second or more), not between two safe points
        from virtspec_mi.results.io import warm_writer

        warm_writer()
    with (nullcontext() if checkpoint is None else locked(Path(checkpoint))), interrupts.deferred():
            store = _Store(None if checkpoint is None else Path(checkpoint), identity)
            scene = load_scene(_scene(grid))
            started = time.perf_counter()
            traced_seconds = 0.0
            groups = 0
            adaptive = BOUNDS[bound].adaptive
            bar = Progress(progress, n_cells * (2 if adaptive else 1), desc="albedo table")

            def run(label: str, beam: str, angles: Sequence[float], pts: np.ndarray, rays: int) -> Any:
                nonlocal traced_seconds, groups
                groups += 1
                result = store.load(label)
                if result is None:
                    with warnings.catch_warnings():  # a group's uncertified readings are reported once, for the table
                        warnings.simplefilter("ignore", RuntimeWarning)
                        result = sweep(scene, theta_i=list(angles), beam=beam, rays=int(rays), wavelengths=[wavelength],
                                       parameters={n: pts[:, k].tolist() for k, n in enumerate(names)}, points=True,
                                       seed=derived_seed(seed, label), sampling="random", progress=False,
                                       **({} if chunk_size is None else {"chunk_size": chunk_size}))
                    store.save(label, result)
                    interrupts.check()  # a safe point: the group is saved, none is being written
                traced_seconds += result.seconds
                bar.reach(bar.done + len(angles) * len(pts))
                return result

            def counts_of(result: Any) -> dict[str, np.ndarray]:  # (θ, point) arrays of one wavelength
                return {k: np.asarray(getattr(result, k))[0] for k in ("rays",) + _KEYS}

            beams = [("collimated", theta, n_mu)] + ([("diffuse", np.array([0.0]), 1)] if average else [])
            assembled: dict[str, dict[str, np.ndarray]] = {}
            try:  # an interrupt: at a kernel chunk of a group's sweep or between two groups, the finished ones kept
                pilots = {}
                for beam, angles, rows in beams:
                    shape = (rows, n_p)
                    totals = {k: np.zeros(shape, dtype=np.int64) for k in ("rays",) + _KEYS}
                    totals["pilot_rays"] = np.zeros(shape, dtype=np.int64)
                    totals["pilot_violations"] = np.zeros(shape, dtype=np.int64)
                    totals["interval_delta"] = np.full(shape, delta / (n_cells * q))
                    if not adaptive:
                        rays = union_hoeffding_rays(epsilon, delta, n_cells * q)
                        found = counts_of(run(f"hoeffding:{beam}", beam, angles, points, rays))
                        for k in found:
                            totals[k][:] = found[k]
                    else:
                        pilot = counts_of(run(f"pilot:{beam}", beam, angles, points, n1))
                        totals["pilot_rays"][:] = pilot["rays"]
                        totals["pilot_violations"][:] = (pilot["weight_violations"] + pilot["invalid_directions"]
                                                         + pilot["capped"])
                        hits = [pilot["reflected"] + pilot["transmitted"]]
                        if parts:
                            hits += [pilot["reflected"], pilot["transmitted"]]
                        pilots[beam] = [pilot_intervals(h, n1, delta / 10.0 / (n_cells * q)) for h in hits]
                    assembled[beam] = totals
                if adaptive:
                    shares = stage_two_shares({beam: intervals for beam, intervals in pilots.items()}, delta * 0.9)
                    for beam, angles, rows in beams:
                        totals = assembled[beam]
                        share = shares[beam]  # δ of each quantity's second batch, per cell
                        totals["interval_delta"] = share
                        need = np.max([binomial_rays(lo, hi, epsilon, share) for lo, hi in pilots[beam]], axis=0)
                        classes = np.minimum(np.ceil(_CLASS_STEP ** np.ceil(np.log(need) / np.log(_CLASS_STEP) - 1e-9)),
                                             union_hoeffding_rays_array(epsilon, share)).astype(np.int64)
                        for rays in np.unique(classes):
                            rows_in, cols_in = np.nonzero(classes == rays)
                            if len(np.unique(rows_in)) <= len(np.unique(cols_in)):  # fewer sweeps: one per θ row …
                                for row in np.unique(rows_in):
                                    members = cols_in[rows_in == row]
                                    label = f"stage2:{beam}:{int(rays)}:row{row}:" + ",".join(map(str, members.tolist()))
                                    found = counts_of(run(label, beam, [angles[row]], points[members], int(rays)))
                                    for k in found:
                                        totals[k][row, members] = found[k][0]
                            else:  # … or one per parameter point (a column of θ rows)
                                for col in np.unique(cols_in):
                                    members = rows_in[cols_in == col]
                                    label = f"stage2:{beam}:{int(rays)}:col{col}:" + ",".join(map(str, members.tolist()))
                                    found = counts_of(run(label, beam, angles[members], points[[col]], int(rays)))
                                    for k in found:
                                        totals[k][members, col] = found[k][:, 0]
            except interrupts.Interrupted as stop:
                stop.checkpoint = store.directory if store.directory is not None and store.saved else None
                raise
            finally:
                bar.close()
            if store.reused:
                bar.note(f"resumed from {store.directory}: {store.reused} finished group(s) reused")

            import mitsuba as _mitsuba_module

            collimated = {k: grid.canonical(v) for k, v in assembled["collimated"].items()}
            averaged = None
            if average:
                averaged = {k: grid.canonical_average(v[0]) for k, v in assembled["diffuse"].items()}
            provenance = {"seed": int(seed), "wavelength_nm": float(wavelength), "mitsuba": _mitsuba_module.__version__,
                          "variant": mi.variant(), "virtspec_mi": __version__, "pilot_rays": n1 if adaptive else 0,
                          "seconds_wall": round(time.perf_counter() - started, 3), "seconds_traced": round(traced_seconds, 3),
                          "groups": groups,
                          "created": datetime.now(timezone.utc).isoformat(timespec="seconds"),
                          "bsdf": "roughconductor (material none, Fresnel = 1)" if model == "conductor" else "roughdielectric",
                          "beam": "collimated (E), diffuse cosine-weighted (E_avg)",
                          "alpha_clamp": "Mitsuba clamps alpha >= 1e-4 (MicrofacetDistribution::configure)"}
            table = AlbedoTable(model, distribution, grid.mu, grid.alpha, grid.eta, grid.roughness, grid.engine, grid.order,
                                collimated, averaged, epsilon, delta, bound, quantities, provenance)
            if not table.certified:
                warnings.warn(f"albedo table: {table.statement()}", RuntimeWarning, stacklevel=2)
            interrupts.check()  # the last safe point before the outputs are written
            for path in outs:
                table.write(path, overwrite=overwrite)
            store.remove()  # the table is returned (and written to every out): its groups are safe
            return table

