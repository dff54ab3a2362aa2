"""
Certified directional-albedo tables: :class:`AlbedoTable`, its files and its comparison
=======================================================================================

A table of E(μ, α[, η]) (and E_avg) measured by :func:`virtspec_mi.applications.tables.albedo.albedo_table`:
its exact counts per cell, the certificate they give (each value within ε, the whole table
at once with probability ≥ 1 − δ), its files — NetCDF (read back by
:func:`read_albedo_table`, checked as strictly as result files), ``.npy`` with its JSON
sidecar, a C header in Cycles' layout — and :class:`TableComparison`, a published table
held to the certified intervals.

References
----------
Kulla, C., Conty, A. (2017). Revisiting physically based shading at Imageworks. SIGGRAPH
course *Physically Based Shading in Theory and Practice*: E(μ), E_avg.
Clopper, C.J., Pearson, E.S. (1934). Biometrika 26, 404–413.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, ClassVar, Mapping

import numpy as np

from virtspec_mi.base.surface import spoken
from virtspec_mi.budgets.intervals import clopper_pearson_each
from virtspec_mi.exchange.common import check_companions
from virtspec_mi.results.integrity import CountRules, field_value, finite_labels, optional_numbers, whole_counts
from virtspec_mi.results.records import Record, plain_floats

__all__ = ["MODELS", "DISTRIBUTIONS", "BOUNDS", "SIDES", "TableBudget", "AlbedoTable", "TableComparison",
           "read_albedo_table"]


MODELS: dict[str, str] = {
    "conductor": "virtspec-mi microfacet reflector (sampling consistent with eval): E = reflected",
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
"""Ray budgets of a table, by name (:mod:`virtspec_mi.budgets.binomial`)."""

SIDES: tuple[str, ...] = ("outside", "inside")
"""Glass: light arriving from outside (relative index η) or from inside (1/η)."""

_FORMAT = "virtspec-mi albedo table 1"
"""The format tag of an albedo table's files (:attr:`AlbedoTable.FORMAT`)."""


# ----------------------------------------------------------------------------- the table

_COUNTS = ("rays", "reflected", "transmitted", "rounded_weights", "weight_violations", "invalid_directions", "capped",
           "pilot_rays", "pilot_violations")
"""A cell's exact counts (its estimating batch's, and its pilot's rays and violations)."""
_CELL_RULES = CountRules("rays", parts={"reflected": "rays", "transmitted": "rays", "rounded_weights": "rays",
                                        "weight_violations": "rays", "invalid_directions": "rays", "capped": "rays",
                                        "pilot_violations": "pilot_rays"},
                         sums=((("reflected", "transmitted"), "rays", False),))
"""How a cell's counts add up: every part within its rays, reflected + transmitted within the rays."""
_WORDS = {"E": "directional albedo E", "E_R": "reflected part of E", "E_T": "transmitted part of E"}


def _table_variables() -> dict[str, tuple[str, str]]:
    """``(units, long_name)`` of every variable and coordinate an albedo table's Dataset may hold."""

    table = {"mu": ("1", "cosine of the incidence angle"), "alpha": ("1", "Mitsuba microfacet roughness alpha"),
             "roughness": ("1", "the engine's roughness (alpha = roughness^2)"), "side": ("1", "side of incidence"),
             "eta": ("1", "relative index of refraction, light from outside"),
             "relative_eta": ("1", "relative index of refraction of the side")}
    for average, suffix in (("", ""), ("_avg", " (diffuse beam: E_avg)")):
        for name, words in _WORDS.items():
            table[f"{name}{average}"] = ("1", words + suffix)
            for side in ("lower", "upper"):
                table[f"{name}{average}_{side}"] = ("1", f"Clopper-Pearson {side} bound of {words}{suffix}")
        table[f"certified_epsilon{average}"] = ("1", f"certified tolerance of the cell (NaN: not certified){suffix}")
    for prefix, suffix in (("", ""), ("avg_", " (diffuse beam: E_avg)")):
        for name in _COUNTS:
            table[f"{prefix}{name}"] = ("1", f"{name.replace('_', ' ')} of the cell{suffix}")
        table[f"{prefix}interval_delta"] = ("1", f"failure probability of the cell's interval{suffix}")
    return table


@dataclass(frozen=True, eq=False)
class AlbedoTable(Record):
    """
    A certified table of E(μ, α[, η]) and E_avg(α[, η]) (see the module docstring); a
    result kind (format ``"virtspec-mi albedo table 1"``): its Dataset holds the counts of
    every cell, E with its intervals and the certificate over the canonical dims, the
    settings as attributes; files ``.nc``, ``.json`` and its exports ``.npy`` (with its
    sidecar ``NAME.json``, which :func:`virtspec_mi.read_result` reads) and ``.h``/``.hpp``.

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
        Seed, wavelength, Mitsuba and virtspec-mi versions, seconds, creation time, rays,
        and ``bsdf_model``: the model in words (which G₂, which G₁, which F).
    bsdf : dict
        Conductor: ``shadowing``, ``g1``, ``fresnel`` of the ``microfacet`` plugin (empty
        for glass: Mitsuba's ``roughdielectric``).
    count_scale : float
        c: each value is c × count/N (c = 1 except Beckmann ``g1="walter"``, whose weights
        are divided by c = 1.0032 to stay ≤ 1); intervals and tolerances scale with it.
    """

    FORMAT: ClassVar[str] = "virtspec-mi albedo table 1"
    KIND: ClassVar[str] = "albedo table"
    VARIABLES: ClassVar[dict[str, tuple[str, str]]] = _table_variables()

    model: str
    distribution: str
    mu: np.ndarray = field()
    alpha: np.ndarray
    eta: np.ndarray | None
    roughness: np.ndarray | None
    engine: str
    order: tuple[str, ...]
    counts: dict[str, np.ndarray]
    average_counts: dict[str, np.ndarray] | None
    epsilon: float
    delta: float = field()
    bound: str
    quantities: tuple[str, ...] = ("E",)
    provenance: dict[str, Any] = field(default_factory=dict)
    bsdf: dict[str, str] = field(default_factory=dict)
    count_scale: float = 1.0

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
        ``two-stage`` the cell's share of 0.9δ (:func:`~virtspec_mi.budgets.binomial.stage_two_shares`,
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
        return self.count_scale * hits / counts["rays"]

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
        bias = self.count_scale * counts["rounded_weights"] * WEIGHT_ROUNDING / counts["rays"]
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
        values = self.quantity(quantity, average) / self.count_scale
        hits = np.rint(values * counts["rays"]).astype(np.int64)
        lower, upper = clopper_pearson_each(hits, counts["rays"], counts["interval_delta"])
        return self.count_scale * lower, self.count_scale * upper

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

    @property
    def _parts_names(self) -> tuple[str, ...]:
        """The quantities a file carries: E, and E_R, E_T for glass or a ``split`` conductor."""

        return ("E", "E_R", "E_T") if self.model == "glass" or "E_R" in self.quantities else ("E",)

    def _stored(self) -> Any:
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
        for name in self._parts_names:
            data[name] = (dims, self.quantity(name))
            lower, upper = self.interval(name)
            data[f"{name}_lower"], data[f"{name}_upper"] = (dims, lower), (dims, upper)
        data["certified_epsilon"] = (dims, self.certified_epsilon())
        for key, value in self.counts.items():
            data[key] = (dims, value)
        if self.average_counts is not None:
            for name in self._parts_names:
                data[f"{name}_avg"] = (adims, self.quantity(name, average=True))
                lower, upper = self.interval(name, average=True)
                data[f"{name}_avg_lower"], data[f"{name}_avg_upper"] = (adims, lower), (adims, upper)
            data["certified_epsilon_avg"] = (adims, self.certified_epsilon(average=True))
            for key, value in self.average_counts.items():
                data[f"avg_{key}"] = (adims, value)
        attrs = {"model": self.model, "distribution": self.distribution, "engine": self.engine,
                 "order": " ".join(self.order), "epsilon": self.epsilon, "delta": self.delta, "bound": self.bound,
                 "quantities": " ".join(self.quantities),
                 "certificate": self.statement(), "rays_total": self.rays,
                 "provenance": json.dumps(self.provenance, sort_keys=True),
                 "bsdf": json.dumps(self.bsdf, sort_keys=True), "count_scale": self.count_scale}
        return xr.Dataset(data, coords=coords, attrs=attrs)

    @classmethod
    def _from_legacy(cls, dataset: Any) -> "AlbedoTable":
        """A table's dataset (an ``.nc`` of an earlier release, or any of its ``.nc`` files), checked by :meth:`_check_read`."""

        attrs = dataset.attrs
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
        A table file read as strictly as a result file (:mod:`virtspec_mi.results.integrity`): its rules
        (:meth:`_check`), and every value it shows besides its counts — E, the intervals, ε' per cell, the
        certificate — equal to what the counts and settings give (an edited value is refused, not stated as certified).
        """

        self._check()
        shown = self.data
        for name in shown.data_vars:
            if name in dataset and not np.array_equal(np.asarray(dataset[name].values), np.asarray(shown[name].values),
                                                      equal_nan=True):
                raise ValueError(f"albedo table: '{name}' disagrees with the counts and settings it is made from "
                                 "(edited?)")
        for name in ("certificate", "rays_total"):
            if str(dataset.attrs.get(name)) != str(shown.attrs[name]):
                raise ValueError(f"albedo table: the attribute '{name}' disagrees with the counts and settings "
                                 "(edited?)")

    def _check(self) -> None:
        """
        The table's rules: every cell's counts add up (each part within its rays, rays >= 1:
        :meth:`_count_groups`), an ε the rays can hold (N > 1/ε: no N smaller holds a
        fraction within ε), each cell's δ in (0, δ].
        """

        for group, counts, rules, dims in self._count_groups():
            prefix = "avg_" if group else ""
            rays = counts["rays"]
            if np.any(rays < 1):
                raise ValueError(f"albedo table: '{prefix}rays' holds {int(rays.min())}: every cell needs rays >= 1")
            for part, whole in rules.parts.items():
                if np.any(counts[part] > counts[whole]):
                    raise ValueError(f"albedo table: '{prefix}{part}' holds a count above '{prefix}{whole}'")
            if np.any(counts["reflected"] + counts["transmitted"] > rays):
                raise ValueError(f"albedo table: '{prefix}reflected' + '{prefix}transmitted' exceed '{prefix}rays'")
            if np.any(rays * self.epsilon <= 1.0):
                raise ValueError(f"albedo table: epsilon = {self.epsilon:g} cannot be certified with "
                                 f"{int(rays.min()):,} rays a cell (N > 1/epsilon is needed)")
            delta = (self.average_counts if group else self.counts)["interval_delta"]
            if not np.all((delta > 0) & (delta <= self.delta)):
                raise ValueError(f"albedo table: '{prefix}interval_delta' must lie in (0, delta = {self.delta:g}]")

    def _count_groups(self) -> list[tuple[str, Any, CountRules, tuple[str, ...]]]:
        groups = [("", {k: self.counts[k] for k in _COUNTS}, _CELL_RULES, self.dims)]
        if self.average_counts is not None:
            groups.append(("average", {k: self.average_counts[k] for k in _COUNTS}, _CELL_RULES, self.average_dims))
        return groups

    def _agreement(self, kind: str, content: Any) -> None:
        """Rule 6 for a table's ``.nc`` file: its counts, values and certificate are the ones its result_json gives."""

        if kind == "dataset":
            legacy = type(self)._from_legacy(content)  # the file's own counts by the rules, its values by its counts
            for ours, theirs, prefix in ((self.counts, legacy.counts, ""),
                                         (self.average_counts or {}, legacy.average_counts or {}, "avg_")):
                for name in _COUNTS:
                    if name in ours and not np.array_equal(ours[name], theirs.get(name)):
                        raise ValueError(f"albedo table: '{prefix}{name}' disagrees with the table the file holds "
                                         "(edited?)")
            self._check_read(content)

    def as_dict(self) -> dict[str, Any]:
        """
        The table as plain data: its :meth:`description` (provenance, layout, certificate) with
        its exact counts (``counts``, ``average_counts``: each cell's, canonical dims).
        """

        def plain(counts: dict[str, np.ndarray] | None) -> dict[str, Any] | None:
            if counts is None:
                return None
            return {**{k: np.asarray(counts[k]).tolist() for k in _COUNTS},
                    "interval_delta": plain_floats(counts["interval_delta"])}

        return {**self.description(), "counts": plain(self.counts), "average_counts": plain(self.average_counts)}

    @classmethod
    def _from_dict(cls, data: Mapping[str, Any]) -> "AlbedoTable":
        if "counts" not in data:
            raise ValueError("holds an albedo table's description without its counts (a .npy's sidecar of an earlier "
                             "release): read the table's .nc file, which holds them")

        def counts(values: Any, prefix: str) -> dict[str, np.ndarray] | None:
            if values is None:
                return None
            out = {k: whole_counts(values[k], f"{prefix}{k}") for k in _COUNTS}
            out["interval_delta"] = optional_numbers(values["interval_delta"], f"{prefix}interval_delta")
            return out

        model = field_value(data, "model", "text")
        if model not in MODELS:
            raise ValueError(f"'model' must be one of {', '.join(MODELS)} (got {model!r})")
        order = [d for d in data["order"] if d != "side"]
        return cls(model, field_value(data, "distribution", "text"), finite_labels(data["mu"], "mu"),
                   finite_labels(data["alpha"], "alpha"),
                   None if data["eta_outside"] is None else finite_labels(data["eta_outside"], "eta_outside"),
                   None if data["roughness"] is None else finite_labels(data["roughness"], "roughness"),
                   field_value(data, "engine", "text"), tuple(order), counts(data["counts"], ""),
                   counts(data["average_counts"], "avg_"), float(data["epsilon"]), float(data["delta"]),
                   field_value(data, "bound", "text"), tuple(data["quantities"]), field_value(data, "provenance", "object"),
                   field_value(data, "bsdf", "object"), float(data["count_scale"]))

    def _check_stored(self, data: Mapping[str, Any]) -> None:
        """The certificate and the rays a table's JSON states are the ones its counts give."""

        for name, ours in (("certificate", self.statement()), ("rays_total", self.rays)):
            if data.get(name) != ours:
                raise ValueError(f"albedo table: '{name}' disagrees with the counts and settings (edited?)")

    @classmethod
    def _built(cls, dataset: Any, attrs: Any, model: str, counts: dict, average: dict | None) -> "AlbedoTable":
        return cls(model, str(attrs["distribution"]), np.asarray(dataset["mu"].values, dtype=np.float64),
                   np.asarray(dataset["alpha"].values, dtype=np.float64),
                   np.asarray(dataset["eta"].values, dtype=np.float64) if model == "glass" else None,
                   np.asarray(dataset["roughness"].values, dtype=np.float64) if "roughness" in dataset.coords else None,
                   str(attrs["engine"]), tuple(str(attrs["order"]).split()), counts, average,
                   float(attrs["epsilon"]), float(attrs["delta"]), str(attrs["bound"]),
                   tuple(str(attrs["quantities"]).split()), json.loads(str(attrs["provenance"])),
                   json.loads(str(attrs.get("bsdf", "{}"))), float(attrs.get("count_scale", 1.0)))

    def check_output(self, path: str | os.PathLike, overwrite: bool = False) -> None:
        """Refuse companions of ``path`` that would replace a file not written by this format (see :meth:`write`)."""

        _check_output(Path(path), self.E_avg is not None, overwrite)

    def write(self, path: str | os.PathLike, overwrite: bool = False) -> Path:
        """
        Write the table by the one writer (:meth:`ResultBase.write <virtspec_mi.results.base.ResultBase.write>`):
        ``.nc`` (NetCDF of :meth:`to_dataset`) or ``.json`` (:meth:`as_dict`), or one of its
        exports (:attr:`EXPORTS`): ``.npy`` (Ê as float32 in the engine's memory order; E_avg
        in ``NAME_avg.npy``; the whole table — provenance, certificate, counts — in
        ``NAME.json``, which :func:`virtspec_mi.read_result` reads) or ``.h`` / ``.hpp`` (a C
        header in Cycles' layout, :mod:`virtspec_mi.exchange.header`). A ``.npy``'s
        companions replace files of their names only when those are an albedo table's (its
        ``NAME.json`` says so) or with ``overwrite=True`` (else ``ValueError``, before
        anything is written).
        """

        path = Path(path)
        if path.suffix.lower() not in (*self.SUFFIXES, *self.EXPORTS):
            raise ValueError(f"path must end in .nc, .json, .npy, .h or .hpp (got {path.name!r})")
        self.check_output(path, overwrite)
        return super().write(path)

    def description(self) -> dict[str, Any]:
        """Provenance, layout and certificate as plain data (the ``.npy`` sidecar, the header's comment)."""

        return {"format": self.FORMAT, "model": self.model, "model_description": MODELS[self.model],
                "distribution": self.distribution, "engine": self.engine,
                "order": list((["side"] if self.model == "glass" else []) + list(self.order)),
                "average_order": list(self.average_dims), "shape": list(self.layout().shape),
                "mu": self.mu.tolist(), "alpha": self.alpha.tolist(),
                "roughness": None if self.roughness is None else self.roughness.tolist(),
                "eta_outside": None if self.eta is None else self.eta.tolist(),
                "epsilon": self.epsilon, "delta": self.delta, "bound": self.bound, "quantities": list(self.quantities),
                "certificate": self.statement(), "rays_total": self.rays,
                "worst_certified_epsilon": float(np.nanmax(self.certified_epsilon())),
                "bsdf": self.bsdf, "count_scale": self.count_scale, "provenance": self.provenance}

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
        own = _own_table(published)
        if own is not None:  # an albedo table's .nc: canonical (mu, alpha) order, put in this table's memory order
            values = self.layout(_own_quantity(own, published, array, average), average=average)
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
        from virtspec_mi.applications.tables.comparison import TableComparison

        return TableComparison(self, values, tuple(dims), flagged, int(mine.size), average, side, rounding)


def read_albedo_table(path: str | os.PathLike) -> AlbedoTable:
    """
    An :class:`AlbedoTable` from a file written by :meth:`AlbedoTable.write` (``.nc``, ``.json``,
    a ``.npy`` with its sidecar): :func:`virtspec_mi.read_result` that refuses another kind.
    """

    path = Path(path)
    if path.suffix.lower() == ".nc":
        from virtspec_mi.base.files import read_netcdf

        read_netcdf(path, "albedo table")  # a file that is not NetCDF, named as a table's
    try:
        return AlbedoTable.read(path)
    except ValueError as error:
        text = str(error).replace("albedo table: ", "", 1)
        raise ValueError(text.replace("result file", "albedo table", 1)) from None


def _own_quantity(own: "AlbedoTable", published: Any, array: str | None, average: bool) -> np.ndarray | None:
    """
    The quantity ``array`` names (default ``E``, ``E_avg`` with ``average``) of an albedo
    table read from its ``.nc`` (canonical dims, whatever variable is asked for: never the
    file's raw array reshaped into a memory order).
    """

    name = array or ("E_avg" if average else "E")
    base = name[:-len("_avg")] if name.endswith("_avg") else name
    if base not in ("E", "E_R", "E_T") or name.endswith("_avg") != bool(average):
        allowed = "E_avg, E_R_avg, E_T_avg (average=True)" if average else "E, E_R, E_T"
        raise ValueError(f"array {name!r} is not a quantity of the albedo table {published}: one of {allowed}")
    if base != "E" and base not in own.quantities:
        raise ValueError(f"array {name!r}: the albedo table {published} holds {', '.join(own.quantities)} only")
    if average and own.E_avg is None:
        return None
    return own.quantity(base, average)


def _own_table(published: Any) -> "AlbedoTable | None":
    """The :class:`AlbedoTable` of a published ``.nc`` written by :meth:`AlbedoTable.write` (else ``None``)."""

    if not isinstance(published, (str, os.PathLike)) or Path(published).suffix.lower() != ".nc":
        return None
    if not Path(published).is_file():
        return None
    import xarray as xr

    try:
        with xr.open_dataset(published) as dataset:
            if dataset.attrs.get("format") != AlbedoTable.FORMAT:
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
                     flag=spoken("overwrite=True", "--overwrite"))


def _ours(npy: Path) -> bool:
    """Whether ``NAME.json`` beside a table's ``NAME.npy`` is an albedo table's sidecar (so are its companions)."""

    try:
        return json.loads(npy.with_suffix(".json").read_text(encoding="utf-8")).get("format") == AlbedoTable.FORMAT
    except (OSError, ValueError, AttributeError):
        return False


from virtspec_mi.applications.tables.files import _sidecar, _values_only, _write_header, _write_npy  # noqa: E402

AlbedoTable.EXPORTS = {".npy": _write_npy, ".h": _write_header, ".hpp": _write_header}
AlbedoTable.COMPANIONS = {".npy": _sidecar, ".h": _values_only, ".hpp": _values_only}

from virtspec_mi.applications.tables.comparison import TableComparison  # noqa: E402  (it holds an AlbedoTable)
