"""
A published table held to a certified one: :class:`TableComparison`
===================================================================

What :meth:`AlbedoTable.compare <virtspec_mi.applications.tables.table.AlbedoTable.compare>`
returns: every cell where a published table (an engine's, a paper's) falls outside the
certified interval of an albedo table, with the certificate. A result kind of the one family
(:class:`~virtspec_mi.results.records.Record`, format ``"virtspec-mi table comparison 1"``):
its files hold the certified table and the published values, and reading one compares them
again.

References
----------
Clopper, C.J., Pearson, E.S. (1934). Biometrika 26, 404–413.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, ClassVar, Mapping

import numpy as np

from virtspec_mi.results.integrity import field_value, optional_numbers
from virtspec_mi.results.records import Record, plain_floats

__all__ = ["TableComparison"]


@dataclass(frozen=True, eq=False)
class TableComparison(Record):
    """
    A published table against a certified one (:meth:`AlbedoTable.compare`); a result kind
    (format ``"virtspec-mi table comparison 1"``): its Dataset has the published values and
    the cells flagged over the table's dims; its files hold the certified table and the
    published values, and reading one compares them again (the flagged cells it states must
    be the ones they give).
    """

    FORMAT: ClassVar[str] = "virtspec-mi table comparison 1"
    KIND: ClassVar[str] = "table comparison"
    VARIABLES: ClassVar[dict[str, tuple[str, str]]] = {
        "mu": ("1", "cosine of the incidence angle"), "alpha": ("1", "Mitsuba microfacet roughness alpha"),
        "eta": ("1", "relative index of refraction of the side compared"), "published": ("1", "published value"),
        "flagged": ("1", "the published value lies outside the certified interval + rounding (1) or not (0)")}

    table: Any
    published: np.ndarray
    dims: tuple[str, ...] = field()
    outside: list[dict[str, Any]]
    cells: int
    average: bool
    side: str
    rounding: float

    def as_dict(self) -> dict[str, Any]:
        """The certified table (its :meth:`AlbedoTable.as_dict`), the published values and the cells flagged."""

        return {"format": self.FORMAT, "table": self.table.as_dict(), "published": plain_floats(self.published),
                "dims": list(self.dims), "outside": [{**cell, "index": list(cell["index"])} for cell in self.outside],
                "cells": self.cells, "average": bool(self.average), "side": self.side, "rounding": self.rounding,
                "share_outside": self.share_outside}

    @classmethod
    def _from_dict(cls, data: Mapping[str, Any]) -> "TableComparison":
        from virtspec_mi.results.kinds import kind_of

        table = kind_of("virtspec-mi albedo table 1").from_dict(field_value(data, "table", "object"))
        again = table.compare(np.asarray(optional_numbers(data["published"], "published")),
                              average=field_value(data, "average", "flag"), side=field_value(data, "side", "text"),
                              rounding=float(data["rounding"]))
        stated = [{**cell, "index": tuple(cell["index"])} for cell in data["outside"]]
        if stated != again.outside or data["cells"] != again.cells:
            raise ValueError("'outside' disagrees with the table and the published values the file holds (edited?)")
        return again

    def _stored(self) -> Any:
        import xarray as xr

        labels = {"mu": self.table.mu, "alpha": self.table.alpha,
                  "eta": None if self.table.eta is None else (self.table.eta if self.side == "outside"
                                                             else 1.0 / self.table.eta)}
        flagged = np.zeros(np.shape(self.published), dtype=np.int8)
        for cell in self.outside:
            flagged[tuple(cell["index"])] = 1
        return xr.Dataset({"published": (self.dims, self.published), "flagged": (self.dims, flagged)},
                          coords={d: labels[d] for d in self.dims if labels.get(d) is not None},
                          attrs={"average": int(self.average), "side": self.side, "rounding": self.rounding,
                                 "cells": self.cells, "certificate": self.table.statement()})

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
