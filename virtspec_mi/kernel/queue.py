"""
How the kernel queues a random-walk specimen's rays: :class:`WalkQueue` and :func:`walk_plan`
=============================================================================================

A walk specimen's rays are run by lanes that each work through a queue of the chunk's
rays (:meth:`virtspec_mi.kernel.tracer._Kernel.walk`): how many lanes, how a lane picks
its next ray, how often a finished lane is refilled and whether every ray's start is
computed ahead. Counts never depend on it; the defaults were chosen by measurement.

References
----------
Baranoski et al. (2001), Sect. 3 (one ray at a time through the specimen).
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["WalkQueue", "walk_plan", "WALK_GROUP", "WALK_QUEUES", "LONG_WALK_STEPS"]

WALK_GROUP: int = 16
"""Lanes that share one queue under ``queue = "group"`` (the widest SIMD packet, AVX-512)."""

WALK_QUEUES: tuple[str, ...] = ("counter", "group", "stride")
"""How a lane picks its next ray: ``counter`` — one atomic counter for all lanes hands out
the next ray of the chunk; ``group`` — each group of :data:`WALK_GROUP` lanes shares a
counter over its own contiguous range of the chunk's rays; ``stride`` — lane l runs rays
l, l + L, l + 2L, … (no atomics, but a packet waits for its lane with the longest queue)."""


@dataclass(frozen=True)
class WalkQueue:
    """
    How the kernel runs a random-walk specimen's steps (see :meth:`virtspec_mi.kernel.tracer._Kernel.walk`); counts
    never depend on it. The defaults were chosen by measurement (``benchmarks/walk_queue.py``,
    benchmarks/RESULTS.md, issue 14).

    - ``lanes``: SIMD lanes working through a chunk's rays (0: one ``sample()`` per ray,
      the walk as one loop). Dr.Jit's LLVM backend runs a kernel's packets of lanes one
      after another on each thread, so under the shared ``counter`` the first packet of
      each thread walks almost every ray and the others only their first one: a few
      packets per thread are enough (1024 lanes: 64 packets of 16, up to 64 threads).
    - ``queue``: how a lane picks its next ray (:data:`WALK_QUEUES`). The shared counter
      also balances the threads: all of them draw from one queue until it is empty.
    - ``refill``: loop iterations between two refills of a lane whose walk ended (a power
      of two). A refill (the finished ray's tally, the next ray's start) runs for a whole
      SIMD packet when any of its lanes needs it; refilling every P-th iteration divides
      that cost by P for about (P − 1)/2 iterations of idling per ray.
    - ``prestart``: every ray's start (incident ray and ``walk_start``: the generator's seeding,
      spectral look-ups …) computed in one kernel over the whole chunk before the walk
      loop, at full SIMD use; a refill then only gathers its ray's start state (a memory
      read per state array) instead of computing it for the whole packet.

    ``None`` (the default of both): from the specimen's declared mean walk length
    (:func:`walk_plan`, one rule for every walk specimen).
    """

    lanes: int = 1024
    queue: str = "counter"
    refill: int | None = None
    prestart: bool | None = None

    def __post_init__(self) -> None:
        if not (isinstance(self.lanes, int) and 0 <= self.lanes < 2**31):
            raise ValueError(f"lanes must be a whole number, 0 <= lanes < 2**31 (got {self.lanes!r})")
        if self.queue not in WALK_QUEUES:
            raise ValueError(f"queue must be one of {', '.join(WALK_QUEUES)} (got {self.queue!r})")
        if self.refill is not None and not (
                isinstance(self.refill, int) and 1 <= self.refill <= 1024 and self.refill & (self.refill - 1) == 0):
            raise ValueError(f"refill must be None or a power of two, 1 <= refill <= 1024 (got {self.refill!r})")
        if self.prestart not in (None, True, False):
            raise ValueError(f"prestart must be None, True or False (got {self.prestart!r})")

    def planned(self, walk_steps: float | None) -> WalkQueue:
        """This queue with ``refill`` and ``prestart`` that are ``None`` taken from :func:`walk_plan`."""

        refill, prestart = walk_plan(walk_steps)
        return WalkQueue(self.lanes, self.queue, refill if self.refill is None else self.refill,
                         prestart if self.prestart is None else self.prestart)


LONG_WALK_STEPS: float = 6.0
"""Mean events per walk from which a walk counts as long for :func:`walk_plan`."""


def walk_plan(walk_steps: float | None) -> tuple[int, bool]:
    """
    The queue's ``refill`` period and ``prestart`` for a specimen whose walks take
    ``walk_steps`` events on average (:func:`virtspec_mi.kernel.walk.walk_steps`; ``None``:
    not declared). Long walks (≥ :data:`LONG_WALK_STEPS`): refill every 4th iteration;
    short or undeclared: every 2nd; starts computed in the refill for both. Chosen by
    measurement (benchmarks/RESULTS.md, issues 14 and 25): on the ABM leaf (10.2 events per
    ray over the soybean spectrum, 15.7 at 800 nm) refill 4 saves up to 8 % against 2; on the
    MCML slab (3.2 events) refill 4 loses 5–7 %. Precomputed starts (``prestart``) saved
    8–11 % on the leaf while its walk generator was a TEA-seeded PCG32; with the hashed Weyl
    sequence of :func:`~virtspec_mi.kernel.walk.walk_rng` a start costs little more than
    gathering it: the soybean two-stage and corn spectra run 5 % and 11 % faster without, 800 nm
    4 % (issue 25), so no walk length gets it by default.
    """

    return (4 if walk_steps is not None and walk_steps >= LONG_WALK_STEPS else 2), False
