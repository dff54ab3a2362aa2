"""
What a run returns: the exact tallies of every reading
======================================================

A :class:`Tally` holds, over a run's flat readings (:mod:`virtspec_mi.engine.plan`), the
exact fate counts, the two-stage pilot's counts, the exit hook's bins and per-reading
sums, and the seconds spent. An instrument turns it into its result; the engine never
looks at what the bins mean.

References
----------
Baranoski et al. (2001), eq. (2) (ρ = m/N from exact counts).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from virtspec_mi.kernel.counts import Counts

__all__ = ["Tally"]


@dataclass(frozen=True, eq=False)
class Tally:
    """
    Exact tallies of readings (every array indexed by reading first).

    Attributes
    ----------
    counts : Counts
        The fate counts (of the second batch, for two-stage).
    pilot : Counts or None
        The two-stage pilot's counts (kept apart), else ``None``.
    bins : ndarray or None
        The hook's ``int64`` bin counts, shape (readings, K), else ``None``.
    sums : dict
        The hook's per-reading sums by name, ``int64`` arrays of shape (readings,).
    seconds : float
        Tracing time (summed over batches and workers).
    """

    counts: Counts
    pilot: Counts | None = None
    bins: np.ndarray | None = None
    sums: dict[str, np.ndarray] = field(default_factory=dict)
    seconds: float = 0.0

    @classmethod
    def zeros(cls, size: int, bins: int | None = None, sums: tuple[str, ...] = (), pilot: bool = False) -> "Tally":
        """The tallies of ``size`` readings that have traced nothing yet."""

        return cls(Counts.zeros(size), Counts.zeros(size) if pilot else None,
                   None if bins is None else np.zeros((size, bins), dtype=np.int64),
                   {name: np.zeros(size, dtype=np.int64) for name in sums})

    def take(self, index: Any) -> "Tally":
        """The tallies of readings ``index`` (an index array), in that order."""

        return Tally(self.counts.map(lambda v: v[index]), None if self.pilot is None else self.pilot.map(lambda v: v[index]),
                     None if self.bins is None else self.bins[index],
                     {name: value[index] for name, value in self.sums.items()}, self.seconds)

    def put(self, index: Any, other: "Tally") -> None:
        """Write ``other``'s tallies into readings ``index`` of these (in place; seconds are the caller's)."""

        self.counts.put(index, other.counts)
        if self.pilot is not None and other.pilot is not None:
            self.pilot.put(index, other.pilot)
        if self.bins is not None:
            self.bins[index] = other.bins
        for name, value in self.sums.items():
            value[index] = other.sums[name]

    @classmethod
    def concatenate(cls, parts: "list[Tally]") -> "Tally":
        """The readings of ``parts`` one after the other (their seconds added)."""

        if len(parts) == 1:
            return parts[0]
        first = parts[0]
        return cls(Counts.concatenate([p.counts for p in parts]),
                   None if first.pilot is None else Counts.concatenate([p.pilot for p in parts]),
                   None if first.bins is None else np.concatenate([p.bins for p in parts]),
                   {name: np.concatenate([p.sums[name] for p in parts]) for name in first.sums},
                   sum(p.seconds for p in parts))

    def with_seconds(self, seconds: float) -> "Tally":
        """These tallies with ``seconds``."""

        return Tally(self.counts, self.pilot, self.bins, self.sums, float(seconds))
