"""
Auditing an engine's published table against a certified table of the same model
=================================================================================

:func:`audit` reads a table an engine ships, in its native layout
(:func:`~virtspec_mi.applications.tables.engine_tables.read_engine_file`: Cycles' C header,
Filament's ``dfg.inc``, Unreal's G16R16 texture or PNG-16), and holds every cell to a
certified table of the same model on the same grid
(:func:`~virtspec_mi.applications.tables.engine_tables.engine_tables`): a published value v is
*outside* when |v − Ê| ≥ ε′ + r, with Ê the certified value, ε′ its certified tolerance
and r the published value's own rounding (Cycles six decimals: 5·10⁻⁷; Filament's half
float: half a unit in the last place of v; Unreal's 16-bit unorm: 0.5/65535). With
probability ≥ 1 − δ every certified value is within ε′ of the model's true value, so
every cell flagged is wrong by more than its rounding — by at least
(|v − Ê| − ε′ − r), which the report gives in units of ε (``excess``), beside the signed
discrepancy (v − Ê)/ε. A clean published table is flagged nowhere with probability
≥ 1 − δ.

:meth:`Audit.figure` draws each channel's discrepancy (v − Ê)/ε over (μ, roughness),
the flagged cells outlined.

References
----------
Kulla, C., Conty, A. (2017). Revisiting physically based shading at Imageworks. SIGGRAPH
course (the tables engines ship). Clopper, C.J., Pearson, E.S. (1934). Biometrika 26, 404–413.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ["ROUNDING", "ChannelAudit", "Audit", "audit", "check_finite"]


def _half_rounding(values: np.ndarray) -> np.ndarray:
    return np.spacing(np.abs(values).astype(np.float16)).astype(np.float64) / 2.0


ROUNDING: dict[str, Any] = {
    "cycles": lambda v: np.full(np.shape(v), 5e-7),
    "filament": _half_rounding,
    "unreal": lambda v: np.full(np.shape(v), 0.5 / 65535.0),
}
"""Each engine's rounding of a published value (a function of the values)."""


@dataclass(frozen=True, eq=False)
class ChannelAudit:
    """One channel of an audit (arrays in the engine's memory order)."""

    name: str
    published: np.ndarray
    certified: np.ndarray
    tolerance: np.ndarray
    rounding: np.ndarray
    epsilon: float
    coordinates: dict[str, np.ndarray]

    @property
    def discrepancy(self) -> np.ndarray:
        """(published − certified)/ε per cell."""

        return (self.published - self.certified) / self.epsilon

    @property
    def excess(self) -> np.ndarray:
        """(|published − certified| − ε′ − rounding)/ε: > 0 on a flagged cell (NaN where uncertified)."""

        return (np.abs(self.published - self.certified) - self.tolerance - self.rounding) / self.epsilon

    @property
    def outside(self) -> np.ndarray:
        """Cells outside their certified interval (uncertified cells are not counted)."""

        return np.nan_to_num(self.excess, nan=-1.0) >= 0.0

    @property
    def uncertified(self) -> int:
        return int(np.isnan(self.tolerance).sum())

    def cells(self, limit: int | None = None) -> list[dict[str, Any]]:
        """The flagged cells, worst (largest excess) first, with their coordinates."""

        index = np.argwhere(self.outside)
        order = np.argsort(-self.excess[tuple(index.T)], kind="stable") if len(index) else []
        rows = []
        for k in list(order)[:limit]:
            at = tuple(int(i) for i in index[k])
            row = {"channel": self.name, "index": at}
            row.update({name: float(values[at]) for name, values in self.coordinates.items()})
            row.update({"published": float(self.published[at]), "certified": float(self.certified[at]),
                        "tolerance": float(self.tolerance[at]), "rounding": float(self.rounding[at]),
                        "discrepancy_eps": float(self.discrepancy[at]), "excess_eps": float(self.excess[at])})
            rows.append(row)
        return rows


@dataclass(frozen=True, eq=False)
class Audit:
    """A published table held to a certified one (:func:`audit`)."""

    engine: str
    source: str
    channels: dict[str, ChannelAudit]
    certificate: str

    @property
    def outside(self) -> int:
        """Flagged cells over all channels."""

        return int(sum(c.outside.sum() for c in self.channels.values()))

    @property
    def cells(self) -> int:
        return int(sum(c.published.size for c in self.channels.values()))

    def worst(self, limit: int = 10) -> list[dict[str, Any]]:
        """The ``limit`` worst flagged cells over all channels (largest excess first)."""

        rows = [row for c in self.channels.values() for row in c.cells()]
        return sorted(rows, key=lambda row: -row["excess_eps"])[:limit]

    def summary(self, limit: int = 10) -> str:
        lines = [f"audit of {self.source} ({self.engine}): {self.outside:,} of {self.cells:,} published cells outside "
                 "the certified interval (|published - certified| >= epsilon' + rounding)",
                 f"  certified table: {self.certificate}"]
        for name, c in self.channels.items():
            d = c.discrepancy
            lines.append(f"  {name}: {int(c.outside.sum()):,} of {c.published.size:,} outside; "
                         f"(published - certified)/epsilon from {np.nanmin(d):+.2f} to {np.nanmax(d):+.2f}"
                         + (f"; {c.uncertified} uncertified cells not judged" if c.uncertified else ""))
        worst = self.worst(limit)
        if worst:
            names = [k for k in worst[0] if k not in ("channel", "index", "published", "certified", "tolerance",
                                                      "rounding", "discrepancy_eps", "excess_eps")]
            lines.append("  worst cells: channel  " + "  ".join(f"{n:>9}" for n in names)
                         + "  published  certified  (pub-cert)/eps  excess/eps")
            for row in worst:
                lines.append(f"    {row['channel']:>6}  " + "  ".join(f"{row[n]:9.5g}" for n in names)
                             + f"  {row['published']:9.6f}  {row['certified']:9.6f}  {row['discrepancy_eps']:+14.2f}"
                             f"  {row['excess_eps']:10.2f}")
        return "\n".join(lines)

    def figure(self, path: str | os.PathLike | None = None) -> Any:
        """
        A heat map per channel of (published − certified)/ε over μ (x) and roughness (y),
        flagged cells outlined; written to ``path`` when given. Returns the figure.
        """

        if path is not None:  # never over the table audited
            from virtspec_mi.base.files import check_distinct

            check_distinct([("path", path)], [("the audited table", None if self.source == "arrays" else self.source)])
        import matplotlib

        matplotlib.use("Agg", force=False)
        import matplotlib.pyplot as plt

        maps = [(name, c) for name, c in self.channels.items() if c.published.ndim == 2]
        fig, axes = plt.subplots(1, len(maps), figsize=(4.6 * len(maps), 4.0), squeeze=False)
        for ax, (name, c) in zip(axes[0], maps):
            d = c.discrepancy
            mu, rough = c.coordinates["mu"], c.coordinates["roughness"]
            limit = max(3.0, float(np.nanmax(np.abs(d))))
            image = ax.pcolormesh(mu, rough, d, cmap="RdBu_r", vmin=-limit, vmax=limit, shading="nearest")
            rows, cols = np.nonzero(c.outside)
            ax.scatter(mu[rows, cols], rough[rows, cols], s=14, facecolors="none", edgecolors="k", linewidths=0.7)
            ax.set_xlabel("mu = cos theta_i")
            ax.set_ylabel("roughness (alpha = roughness^2)")
            ax.set_title(f"{self.engine} {name}: {len(rows)} outside")
            fig.colorbar(image, ax=ax, label="(published - certified) / epsilon")
        fig.tight_layout()
        if path is not None:
            fig.savefig(path, dpi=120)
        return fig


def _coordinates(table: Any) -> dict[str, np.ndarray]:
    """μ and roughness of every cell of ``table``'s layout (2-D, the engine's memory order)."""

    rough = np.sqrt(table.alpha) if table.roughness is None else table.roughness
    axes = {"mu": table.mu, "alpha": rough}
    first, second = np.meshgrid(axes[table.order[0]], axes[table.order[1]], indexing="ij")
    mu, roughness = (first, second) if table.order[0] == "mu" else (second, first)
    return {"mu": mu, "roughness": roughness}


def check_finite(values: np.ndarray, what: str) -> None:
    """Refuse (``ValueError``) NaN or infinite cells of ``values``, naming ``what``, how many and the first one."""

    bad = np.argwhere(~np.isfinite(values))
    if len(bad):
        first = tuple(int(i) for i in bad[0])
        raise ValueError(f"{what}: {len(bad):,} cell{'s' if len(bad) > 1 else ''} not a finite number (the first "
                         f"at index {first}: {values[first]!r}); a published table holds numbers in every cell")


def audit(published: str | os.PathLike | dict[str, np.ndarray], certified: Any, *,
          engine: str | None = None, rounding: float | None = None) -> Audit:
    """
    Hold a published table to certified tables of the same model and grid (module docstring).

    Parameters
    ----------
    published
        A file in the engine's native layout, or arrays by channel (engine memory order).
    certified
        :class:`~virtspec_mi.applications.tables.engine_tables.EngineTables` of that engine (or a
        Cycles :class:`~virtspec_mi.applications.tables.table.AlbedoTable`: channel ``E`` and ``E_avg``).
    engine
        ``cycles``, ``filament`` or ``unreal`` (default: the certified table's).
    rounding
        The published values' rounding (default :data:`ROUNDING` of the engine).

    Returns
    -------
    Audit
    """

    from virtspec_mi.applications.tables.engine_tables import EngineTables, engine_layout, read_engine_file

    if not isinstance(certified, EngineTables):
        if getattr(certified, "engine", None) != "cycles" or getattr(certified, "model", None) != "conductor":
            raise ValueError("certified must be EngineTables (engine_tables(...)) or a Cycles conductor AlbedoTable")
        certified = EngineTables("cycles", certified, {"E": "E"})
    engine = certified.engine if engine is None else engine
    if engine != certified.engine:
        raise ValueError(f"engine {engine!r} does not match the certified tables' engine {certified.engine!r}")
    if rounding is not None and not (np.isfinite(rounding) and rounding >= 0):
        raise ValueError(f"rounding must be a finite number >= 0 (got {rounding!r})")
    source = "arrays" if isinstance(published, dict) else str(published)
    values = published if isinstance(published, dict) else read_engine_file(published, engine)
    shapes = engine_layout(engine)
    for key, given in values.items():  # every channel published is whole, judged or not
        if key in shapes and np.shape(given) != shapes[key]:
            raise ValueError(f"{source}: channel {key!r} has shape {np.shape(given)}; {engine} lays it out as "
                             f"{shapes[key]}")
    table = certified.table
    channels: dict[str, ChannelAudit] = {}
    for name in certified.channels:
        for key, average in ((name, False), ("E_avg", True)):
            if average and (engine != "cycles" or table.E_avg is None or "E_avg" not in values):
                continue
            if key not in values:
                raise ValueError(f"the published table has no channel {key!r} (it has: {', '.join(values)})")
            try:
                pub = np.asarray(values[key], dtype=np.float64)
            except (TypeError, ValueError):
                raise ValueError(f"{source}: channel {key!r} must hold numbers only, in {engine}'s layout "
                                 f"{shapes[key]}") from None
            if pub.shape != shapes[key]:
                raise ValueError(f"channel {key!r}: shape {pub.shape}, {engine} lays it out as {shapes[key]}")
            check_finite(pub, f"{source}: channel {key!r}")
            mine, tol = certified.values(name, average), certified.tolerance(name, average)
            r = ROUNDING[engine](pub) if rounding is None else np.full(pub.shape, float(rounding))
            if average:
                rough = np.sqrt(table.alpha) if table.roughness is None else table.roughness
                coords = {"roughness": rough}
            else:
                coords = _coordinates(table)
            channels[key] = ChannelAudit(key, pub, mine, tol, r, table.epsilon, coords)
    return Audit(engine, source, channels, certified.statement())
