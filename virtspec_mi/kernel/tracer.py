"""
The ray kernel: rays → specimen BSDF → fate → exact integer counts
==================================================================

One reading = one (wavelength, θi, φi) with its own N independent rays. All readings
of a call run in chunks of one fused Dr.Jit kernel each: counter-based random numbers
(:mod:`virtspec_mi.kernel.rng`) → emitter and specimen points
(:mod:`virtspec_mi.kernel.disk`) → incident direction → the specimen BSDF's ``sample``
(:class:`virtspec_mi.plugins` specimens or Mitsuba built-ins) → :class:`~virtspec_mi.kernel.counts.Fate`
→ exact integer tallies by name (:class:`~virtspec_mi.kernel.counts.Counts`).
:func:`virtspec_mi.engine.readings.trace_readings` drives it.

A specimen whose random walk is declared as steps
(:class:`~virtspec_mi.kernel.walk.RandomWalk`: ``abm_b``, ``abm_u``, ``turbid_slab``) is
not sampled one ``sample()`` per lane: the kernel drives its steps in one symbolic loop
on queued SIMD lanes (:class:`WalkQueue`), a lane whose walk ends tallying that ray's fate
and starting the next ray, so a packet no longer waits for its longest walk. The fate of
every ray is the one ``sample()`` gives it (same random numbers, same rules below).

Conventions
-----------
- Fates are judged in the specimen frame: a ray leaving with wo·n > 0 is reflected
  (upper hemisphere), wo·n < 0 transmitted; one leaving exactly in the plane
  (wo·n = 0, grazing) counts on the far side of the specimen if the BSDF sampled a
  transmission, else on the side it came from. A zero BSDF weight is absorption.
- A reflected (transmitted) ray whose sampled event is a delta event
  (``DeltaReflection`` or ``DeltaTransmission``) also counts as specular reflection
  (regular transmission). They are counted per ray for a BSDF whose flags hold both
  delta and non-delta lobes; for one with only delta lobes they equal R and T, for one
  without delta lobes they are 0 (Mitsuba's flag contract).
- A walk that reached its step cap (``bs.sampled_component`` ==
  :data:`virtspec_mi.kernel.walk.CAPPED_COMPONENT`) is :attr:`Fate.CAPPED`.
- An outgoing direction with a NaN or infinite component, or a length off 1 by more
  than :data:`~virtspec_mi.kernel.counts.DIRECTION_TOLERANCE`, sampled with a weight w > 0 is
  :attr:`Fate.INVALID` (``invalid_directions``): it cannot be judged reflected or
  transmitted, and counts in no fate, like a capped walk.
- Per-ray values a BSDF returns at width 1 (a constant weight, say) are broadcast to
  the chunk, so every per-ray flag is counted once per ray.
- A BSDF weight w ∈ [0, 1] survives with probability w (Russian roulette), so each ray
  stays a Bernoulli trial. Weights within :data:`~virtspec_mi.kernel.counts.WEIGHT_ROUNDING`
  of [0, 1] are rounding (counted in ``rounded_weights``; the roulette uses them as 1 or
  0 by construction); weights beyond, or NaN, are ``weight_violations`` and the largest
  is kept.
- Rays are traced in ``TransportMode.Importance`` (light travels from the emitter).
- One tally path with an optional **exit hook** (:mod:`virtspec_mi.kernel.hooks`): a
  call with a hook also gives every ray a bin code in [0, K) (K: not binned), tallied per
  reading into an exact ``int64`` histogram of K bins, and per-ray values summed per
  reading. A goniophotometer's :class:`~virtspec_mi.instruments.goniophotometer.hook.BinLayout` bins every
  reflected or transmitted ray by its outgoing direction in the same fused kernel (a
  random walk on queued lanes: when its walk ends, the bin kept in the ray's slot and
  tallied after the walk loop); an integrating sphere's
  :class:`~virtspec_mi.instruments.sphere.walk.SphereLayout` continues every ray's first
  interaction through the sphere. Without a hook none of this is compiled: the plain
  kernel and its counts are unchanged.
- The kernel takes plain values (the bench, the readings, seed, chunk size, beam,
  sampling, offsets, a hook) and trusts them: the engine
  (:mod:`virtspec_mi.engine.readings`) validates at the boundary.
- The emitter disk neither occludes nor self-intersects its rays, and no general
  intersection is needed: each conical ray is aimed at a sampled specimen point and hits
  it by construction; a collimated ray hits the specimen centre.

References
----------
Baranoski et al. (2001), eqs. (2)–(4), Sect. 3.2.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any, Callable

import drjit as dr
import mitsuba as mi
import numpy as np

from virtspec_mi.kernel.counts import DIRECTION_TOLERANCE, WEIGHT_ROUNDING, Counts, Fate
from virtspec_mi.kernel.hooks import ChunkRays, ExitHook
from virtspec_mi.kernel.incidence import incidence_frame
from virtspec_mi.kernel.queue import LONG_WALK_STEPS, WALK_GROUP, WALK_QUEUES, WalkQueue, walk_plan
from virtspec_mi.kernel.sources import WAVELENGTH, WORD, RaySource, full, gather_tree, segment_sums
from virtspec_mi.kernel.walk import CAPPED_COMPONENT, is_random_walk, walk_steps

__all__ = ["CHUNK_SECONDS", "FIRST_CHUNK", "KernelTally", "LONG_WALK_STEPS", "ReadingPlan", "WALK_GROUP",
           "WALK_QUEUES", "WalkQueue", "first_interactions", "tally_readings", "trace_rays", "walk_plan"]

# Bits of the per-ray code of rare events (almost always all zero: one reduction skips them).
_VIOLATION, _CAPPED, _ROUNDED, _INVALID = 1, 2, 4, 8
_RARE_COUNTS = (("weight_violations", _VIOLATION), ("capped", _CAPPED), ("rounded_weights", _ROUNDED),
                ("invalid_directions", _INVALID))
# Squared lengths of a valid outgoing direction.
_LENGTH2 = ((1.0 - DIRECTION_TOLERANCE) ** 2, (1.0 + DIRECTION_TOLERANCE) ** 2)


CHUNK_SECONDS: float = 0.5
"""
The longest a kernel launch (one chunk) should last, in seconds. A Dr.Jit kernel cannot
be stopped, so a signal (Ctrl-C, SIGTERM) waits for the chunk under way; chunks are
sized from the measured ray rate to end within this (see :class:`_Pace`).
"""

FIRST_CHUNK: int = 1 << 14
"""Rays of a call's first chunk, before any rate is measured (and the smallest a chunk is made)."""

@dataclass(frozen=True)
class ReadingPlan:
    """One reading for the kernel: wavelength (nm), incidence (degrees) and its rays."""

    wavelength: float
    theta_i: float
    phi_i: float
    rays: int


@dataclass(frozen=True, eq=False)
class KernelTally:
    """
    What one :func:`tally_readings` call returns, per reading (in the order of its plans).

    Attributes
    ----------
    counts : Counts
        The exact fate counts of every reading.
    bins : ndarray or None
        With a hook: the exact ``int64`` histogram of its bin codes, shape (readings, K).
    sums : dict
        With a hook: each per-ray value it names (:attr:`ExitHook.sums`) summed per
        reading, ``int64`` arrays of shape (readings,).
    """

    counts: Counts
    bins: np.ndarray | None = None
    sums: dict[str, np.ndarray] = field(default_factory=dict)


def tally_readings(
    bench: Any, plans: list[ReadingPlan], *, seed: int, chunk_size: int, beam: str, sampling: str,
    offsets: Any = None, hook: ExitHook | None = None, on_chunk: Callable[[int], None] | None = None,
    walk: WalkQueue = WalkQueue(), walk_stats: dict | None = None, chunk_seconds: float | None = CHUNK_SECONDS,
    safe_point: Callable[[], None] | None = None,
) -> KernelTally:
    """
    Trace every reading of ``plans`` on ``bench`` (an object with ``bsdf``, ``geometry``
    — ``emitter_radius``, ``specimen_radius``, ``distance`` — and ``to_world``, 4×4) and
    return their exact tallies (:class:`KernelTally`, one entry per plan).

    Reading k's rays are the global ray indices [offsets[k], offsets[k] + rays_k);
    ``offsets`` defaults to consecutive ranges (0, rays_0, rays_0 + rays_1, …) and may
    leave gaps (a keyed run numbers each reading by its key, so a reading gets the same
    rays whichever other readings share the call). Ranges must not overlap; each reading
    has 1 … 2³² − 1 rays (the engine sees to both). The readings' rays are packed into
    lanes in list order and cut into chunks of at most ``chunk_size`` rays (never
    straddling a 2³² boundary of the global index); each chunk runs as one kernel, so
    memory stays bounded and counts do not depend on chunking. Chunks are also bounded
    in time: sized from the ray rate of the previous chunk to last at most about
    ``chunk_seconds`` (default :data:`CHUNK_SECONDS`; ``None``: every chunk
    ``chunk_size``), so that ``on_chunk`` — where the engine honours an interrupt — is
    reached within about a second even for slow walks. ``seed``, ``beam``
    (``conical``, ``collimated``, ``diffuse``) and ``sampling`` (``jittered``,
    ``random``, ``concentric``) are the settings of those names. ``on_chunk`` (optional)
    is called after every chunk with the number of readings completed so far (a float:
    the reading under way counts by its share of rays traced);
    ``safe_point`` (optional) is handed to a hook that launches kernels of its own within a
    chunk (:attr:`~virtspec_mi.kernel.hooks.ChunkRays.safe_point`: a sphere walk's parts).

    ``hook`` (optional, :mod:`virtspec_mi.kernel.hooks`): every ray also gets the hook's
    bin code, tallied per reading into ``bins`` (readings, K) without atomics (32-bit
    fields, two to a 64-bit word, in one copy of the table per CPU thread —
    Dr.Jit's ``ReduceMode.Expand`` — summed into ``int64`` on the host: memory is
    readings × K, × threads during a chunk, whatever the number of rays), and the hook's
    per-ray values are summed per reading into ``sums``.

    A specimen that declares its random walk as steps
    (:class:`~virtspec_mi.kernel.walk.RandomWalk`) runs on queued lanes as ``walk`` says
    (:class:`WalkQueue`; ``lanes = 0``: one ``sample()`` per ray, the walk as one loop),
    unless the hook needs every ray's lanes (``needs_rays``); no count depends on it.
    ``walk_stats`` (diagnostics, optional): a dict that receives, per chunk, each lane's
    loop iterations (``iterations``) and those that stepped a walk (``busy``).
    """

    rays = np.array([plan.rays for plan in plans], dtype=np.int64)
    starts = np.concatenate([[0], np.cumsum(rays)])  # packed (lane) position of each reading
    offsets = starts[:-1].copy() if offsets is None else _check_offsets(offsets, rays)
    cuts = _cuts(starts, offsets, rays)
    counts = Counts.zeros(len(plans))
    counts.rays[:] = rays
    kernel = _Kernel(bench, plans, seed, beam, sampling, hook, walk, walk_stats)
    tally = KernelTally(counts, None if hook is None else np.zeros((len(plans), hook.size), dtype=np.int64),
                        {name: np.zeros(len(plans), dtype=np.int64) for name in (hook.sums if hook else ())})
    pace = _Pace(chunk_size, chunk_seconds, (id(bench.bsdf), type(hook).__name__, beam, sampling, kernel.queued))
    first = 0
    while first < starts[-1]:
        size = int(min(pace.size, cuts[np.searchsorted(cuts, first, side="right")] - first))
        slots = np.arange(
            np.searchsorted(starts, first, side="right") - 1,
            np.searchsorted(starts, first + size, side="left"),
        )
        began = time.perf_counter()
        kernel.run(RaySource(kernel, first, size, slots, starts, offsets), tally, safe_point)
        pace.update(size, time.perf_counter() - began)
        first += size
        if on_chunk is not None:  # how many readings are complete, the one under way in part (a progress bar)
            on_chunk(float(np.interp(first, starts, np.arange(len(starts)))))
    return tally


_PACES: dict[tuple, int] = {}
"""The chunk size last reached by each kind of kernel (specimen, hook, beam, sampling): the next call's start."""


class _Pace:
    """
    Chunk sizes bounded in time (:data:`CHUNK_SECONDS`): powers of two (a queued walk
    compiles its kernel once per chunk size) from :data:`FIRST_CHUNK` — or a quarter of
    what the same kind of kernel last reached — growing ×4 while a chunk takes less than
    a quarter of the time, shrinking to the measured rate when one takes longer, never
    above ``chunk_size``. Counts do not depend on it (rays are keyed on their index).
    """

    def __init__(self, cap: int, seconds: float | None, key: tuple) -> None:
        self.cap, self.seconds, self.key = cap, seconds, key
        learned = _PACES.get(key, 0) // 4
        self.size = cap if seconds is None else min(cap, max(FIRST_CHUNK, learned))

    def update(self, size: int, elapsed: float) -> None:
        """After a chunk of ``size`` rays took ``elapsed`` seconds: the next chunk's size."""

        if self.seconds is None or size < self.size:  # fixed, or a tail chunk (says little)
            return
        if elapsed < self.seconds / 4:
            self.size = min(self.cap, 4 * size)
        elif elapsed > self.seconds:
            rate_size = size * self.seconds / elapsed
            self.size = min(self.cap, max(FIRST_CHUNK, 1 << max(0, int(rate_size).bit_length() - 1)))
        _PACES[self.key] = self.size


def _cuts(starts: np.ndarray, offsets: np.ndarray, rays: np.ndarray) -> np.ndarray:
    """
    Packed positions where the high word of the global ray index changes (chunks are cut
    there), and the end: inside a reading that crosses a 2³² boundary (at most one, as
    rays ≤ 2³² − 1), and where a reading starts in another 2³² block than the one the
    previous reading ended in. O(readings), NumPy only.
    """

    first_block, last_block = offsets // WORD, (offsets + rays - 1) // WORD
    crossing = last_block > first_block
    inside = starts[:-1][crossing] + (first_block[crossing] + 1) * WORD - offsets[crossing]
    new_block = starts[1:-1][first_block[1:] != last_block[:-1]]
    return np.unique(np.concatenate([starts[-1:], inside, new_block]).astype(np.int64))


def _check_offsets(offsets: Any, rays: np.ndarray) -> np.ndarray:
    """
    Per-reading starts of the global ray index: whole numbers ≥ 0, ranges disjoint, < 2⁶³
    (the engine's contract, asserted here: the kernel's random numbers rely on it).
    """

    offsets = np.asarray(offsets)
    if offsets.shape != rays.shape or (offsets.size and not np.issubdtype(offsets.dtype, np.integer)):
        raise ValueError(f"offsets must be {len(rays)} whole numbers, one per reading")
    offsets = offsets.astype(np.int64)
    order = np.argsort(offsets, kind="stable")
    ends = offsets[order] + rays[order]
    if offsets.size and (offsets.min() < 0 or np.any(offsets[order][1:] < ends[:-1])):
        raise ValueError("offsets must be >= 0 and the readings' ray ranges [offset, offset + rays) disjoint")
    return offsets


def trace_rays(bench: Any, plan: ReadingPlan, count: int, *, seed: int, beam: str, sampling: str,
               hook: ExitHook | None = None) -> dict:
    """
    The first ``count`` rays of one reading, ray by ray, through the same kernel code
    as :func:`tally_readings` (for tests and diagnostics; a random walk runs as one
    ``sample()`` per ray, whose fates the queued lanes reproduce): NumPy arrays of emitter
    points ``origin`` (specimen frame), specimen points ``target``, incident
    directions ``wi`` (towards the emitter), outgoing ``wo``, ``fate`` (a
    :class:`~virtspec_mi.kernel.counts.Fate` code) and the BSDF ``weight``; with a hook
    whose :meth:`~virtspec_mi.kernel.hooks.ExitHook.bin` runs per ray (goniophotometer
    bins), also each ray's ``bin`` (the hook's K: not binned).
    """

    kernel = _Kernel(bench, [plan], seed, beam, sampling, hook)
    source = RaySource(kernel, 0, count, np.array([0]), np.array([0, plan.rays]), np.array([0]))
    lanes = kernel.trace(source)
    dr.eval(lanes)
    return {name: np.array(value).T if np.ndim(value) > 1 else np.array(value)
            for name, value in lanes.items() if value is not None}


def first_interactions(bench: Any, plan: ReadingPlan, first: int, size: int, offset: int, *, seed: int,
                       beam: str, sampling: str) -> dict:
    """
    Symbolic per-lane first interactions (nothing evaluated) of rays [first, first + size) of
    one reading whose rays start at global index ``offset``: the same random numbers, beam
    and specimen ``sample`` as :func:`tally_readings` gives that reading (for tests and
    diagnostics: a hook with ``needs_rays`` receives these very lanes). The chunk must not
    cross a 2³² boundary of the global index. Returns the lanes of :meth:`_Kernel.trace`
    (``wo``, ``target``, ``fate``, ``rare`` …): a random-walk specimen runs here as one
    ``sample()`` per lane (its walk as one loop, not on queued lanes), whose fates the
    queued lanes of :func:`tally_readings` reproduce.
    """

    kernel = _Kernel(bench, [plan], seed, beam, sampling)
    source = RaySource(kernel, first, size, np.array([0]), np.array([0, plan.rays]),
                        np.array([offset], dtype=np.int64))
    return kernel.trace(source)


class _Kernel:
    """The per-chunk ray kernel of one :func:`tally_readings` call."""

    def __init__(self, bench: Any, plans: list[ReadingPlan], seed: int, beam: str, sampling: str,
                 hook: ExitHook | None = None, walk: WalkQueue = WalkQueue(lanes=0),
                 walk_stats: dict | None = None) -> None:
        self.hook = hook
        self.specimen = bench.bsdf
        self.bsdf = bench.bsdf if hook is None else hook.beam_bsdf(bench.bsdf)
        self.seed, self.beam, self.sampling = seed, beam, sampling
        self.phi_i = np.array([plan.phi_i for plan in plans], dtype=np.float64)
        self.pairing = np.array([0 if hook is None else hook.pairing(phi) for phi in self.phi_i], dtype=np.uint32)
        # A random-walk specimen's steps run on queued lanes (walk.lanes = 0: sample() per ray),
        # unless the hook continues every ray's own lane.
        self.queued = walk.lanes > 0 and is_random_walk(self.bsdf) and not (hook is not None and hook.needs_rays)
        self.walk_queue, self.walk_stats = walk.planned(walk_steps(self.bsdf)), walk_stats
        # Specular/regular counts: per ray only for a BSDF with both delta and other lobes.
        flags = self.bsdf.flags()
        delta = mi.has_flag(flags, mi.BSDFFlags.Delta)
        smooth = mi.has_flag(flags, mi.BSDFFlags.Smooth) or mi.has_flag(flags, mi.BSDFFlags.Null)
        self.delta_lobes = "mixed" if delta and smooth else "all" if delta else "none"
        geometry = bench.geometry
        self.emitter_radius = dr.opaque(mi.Float, geometry.emitter_radius)
        self.specimen_radius = dr.opaque(mi.Float, geometry.specimen_radius)
        self.distance = dr.opaque(mi.Float, geometry.distance)
        frame = bench.to_world
        self.frame = mi.Frame3f(*(mi.Vector3f(*map(float, frame[:3, i])) for i in range(3)))
        self.centre = mi.Point3f(*map(float, frame[:3, 3]))
        # Per-reading parameters on the host, one row per reading; a chunk picks its rows.
        rows = []
        for plan in plans:
            omega, e_u, e_v = incidence_frame(plan.theta_i, plan.phi_i)
            strata = np.floor(np.sqrt(plan.rays))
            rows.append([plan.wavelength, *(omega * geometry.distance), *e_u, *e_v, *omega, strata])
        self.readings = np.array(rows, dtype=np.float64)

    # -- one chunk ---------------------------------------------------------------------

    def run(self, source: RaySource, tally: KernelTally, safe_point: Callable[[], None] | None = None) -> None:
        """
        Add the tallies of the chunk's packed lanes (``source``) to its readings
        (``source.slots``) of ``tally``: fate counts, and with a hook its bins and sums.
        """

        hook, slots, counts = self.hook, source.slots, tally.counts
        lanes = (self.walk if self.queued else self.trace)(source)
        exits = None
        if hook is not None and hook.needs_rays:
            # The hook continues the traced lanes: evaluate them once (one kernel), then both
            # the fate counts and the hook read them (a violating weight, rare, is traced again).
            dr.eval(*(lanes[name] for name in ("wo", "target", "fate", "rare", "specular", "regular")))
            slot = lanes["slot"]
            exits = hook.exits(ChunkRays(lanes=lanes, slot=slot, root=source.root,
                                         wavelengths=source.rows[:, WAVELENGTH], specimen=self.specimen,
                                         column=source.column, ray_index=source.ray_index,
                                         safe_point=safe_point))
            lanes["bin"], sums = exits
        fate = lanes["fate"]
        # Two 32-bit counts per UInt64 lane: (reflected, transmitted), (specular, regular).
        code = dr.select(fate == int(Fate.REFLECTED), mi.UInt64(1), mi.UInt64(0)) | dr.select(
            fate == int(Fate.TRANSMITTED), mi.UInt64(WORD), mi.UInt64(0)
        )
        rare = lanes["rare"]
        packed_codes = {("reflected", "transmitted"): code}
        if self.delta_lobes == "mixed":
            packed_codes[("specular_reflected", "regular_transmitted")] = dr.select(
                lanes["specular"], mi.UInt64(1), mi.UInt64(0)) | dr.select(lanes["regular"], mi.UInt64(WORD), mi.UInt64(0))
        if hook is None:
            dr.eval(*packed_codes.values(), rare)  # the one fused ray kernel
        else:
            # The same kernel also adds each ray to its reading's bin (a queued walk: the kernel
            # after the walk loop, from each ray's kept bin).
            table = self._bin_table(source, lanes["bin"], lanes["slot"])
            per_ray = {} if exits is None else {name: sums[name] for name in hook.sums}
            totals = {name: self._per_reading(value, lanes["slot"], len(slots)) for name, value in per_ray.items()}
            dr.eval(*packed_codes.values(), rare, table, *totals.values())
            tally.bins[slots] += self._unpacked(table, slots)
            for name, total in totals.items():
                tally.sums[name][slots] += np.array(total, dtype=np.uint64).astype(np.int64)
        bounds, ends = source.bounds, np.append(source.bounds[1:], source.size)
        for (low, high), packed_code in packed_codes.items():
            if len(slots) == 1:
                packed = np.array([int(dr.sum(packed_code).numpy()[0])], dtype=np.uint64)
            else:
                packed = segment_sums(dr.cumsum(packed_code), bounds, ends)
            getattr(counts, low)[slots] += (packed & np.uint64(WORD - 1)).astype(np.int64)
            getattr(counts, high)[slots] += (packed >> np.uint64(32)).astype(np.int64)
        if self.delta_lobes == "all":  # every event is a delta event: nothing to count
            counts.specular_reflected[slots] = counts.reflected[slots]
            counts.regular_transmitted[slots] = counts.transmitted[slots]
        if int(dr.max(rare).numpy()[0]) == 0:  # the usual case: one reduction, nothing rare
            return
        for name, bit in _RARE_COUNTS:
            flags = mi.UInt64(dr.select((rare & bit) != 0, 1, 0))
            getattr(counts, name)[slots] += segment_sums(dr.cumsum(flags), bounds, ends).astype(np.int64)
        self._largest_weights(lanes["weight"], rare, bounds, slots, counts)

    def _bin_table(self, source: RaySource, code: Any, slot: Any) -> Any:
        """
        The chunk's histogram of the hook's codes (symbolic): two bins per UInt64 word
        (32-bit fields: a chunk holds < 2³² rays, so no field overflows), scatter-added into
        per-thread copies of the table (``ReduceMode.Expand``: no atomics; Dr.Jit sums the
        copies). A SIMD packet costs one read-modify-write per distinct word its rays hit,
        so neighbouring bins share a word, paired as the hook says for each reading
        (:meth:`~virtspec_mi.kernel.hooks.ExitHook.pairing`: each reading's block holds
        K + 1 fields, its bins from field ``pairing`` on). Measured the fastest of
        32-bit/64-bit tallies × Local/Expand/Direct (benchmarks/gonio.py).
        """

        readings, block = len(source.slots), self.hook.size + 1
        table = dr.zeros(mi.UInt64, (readings * block + 1) // 2)
        shift = source.column(self.pairing[source.slots], mi.UInt32, slot)
        where = code + shift if readings == 1 else slot * block + code + shift
        value = dr.select((where & 1) != 0, mi.UInt64(WORD), mi.UInt64(1))
        dr.scatter_reduce(dr.ReduceOp.Add, table, value, where >> 1, code < self.hook.size,
                          mode=dr.ReduceMode.Expand)
        return table

    def _unpacked(self, table: Any, slots: np.ndarray) -> np.ndarray:
        """The evaluated :meth:`_bin_table` of readings ``slots`` as ``int64`` counts, shape (readings, K)."""

        size = self.hook.size
        words = np.array(table, dtype=np.uint64)
        fields = np.stack([words & np.uint64(WORD - 1), words >> np.uint64(32)], axis=1).reshape(-1)
        blocks = fields[: len(slots) * (size + 1)].astype(np.int64).reshape(len(slots), size + 1)
        first = self.pairing[slots].astype(np.int64)
        return blocks[np.arange(len(slots))[:, None], first[:, None] + np.arange(size)[None, :]]

    @staticmethod
    def _per_reading(value: Any, slot: Any, readings: int) -> Any:
        """Per-ray whole numbers summed per reading of the chunk (symbolic ``UInt64``, one per reading)."""

        total = dr.zeros(mi.UInt64, readings)
        dr.scatter_reduce(dr.ReduceOp.Add, total, mi.UInt64(value), mi.UInt32(0) if slot is None else slot)
        return total

    @staticmethod
    def _largest_weights(weight: Any, rare: Any, bounds: np.ndarray, slots: np.ndarray, counts: Counts) -> None:
        """Keep the largest violating weight of each reading (rare: only lanes that violate)."""

        lanes = dr.compress((rare & _VIOLATION) != 0)
        if dr.width(lanes) == 0:
            return
        values = np.array(dr.gather(mi.Float, weight, lanes), dtype=np.float64)
        where = np.searchsorted(bounds.astype(np.int64), np.array(lanes, dtype=np.int64), side="right") - 1
        np.fmax.at(counts.largest_weight, slots[where], values)  # fmax skips NaN weights

    def trace(self, source: RaySource) -> dict:
        """Symbolic per-lane quantities of the chunk's packed lanes (nothing evaluated)."""

        size = source.size
        lane = dr.arange(mi.UInt32, size)
        slot = source.slot(lane)
        ray = source.incident(lane, slot)
        bs, weight = self._sample(ray["si"], ray["sample1"], ray["sample2"])
        wi = ray["si"].wi
        judged = self._judge(wi.z >= 0.0, bs, weight, ray["survival"], size)
        lanes = {"origin": ray["origin"], "target": ray["target"], "wi": wi, **judged, "slot": slot}
        if self.hook is not None and not self.hook.needs_rays:
            lanes["bin"] = self._reading_bin(source, slot, judged["wo"], judged["fate"])
        return lanes

    def walk(self, source: RaySource) -> dict:
        """
        The packed lanes [first, first + size) of a :class:`~virtspec_mi.kernel.walk.RandomWalk`
        specimen, with rays queued on SIMD lanes (see :class:`WalkQueue`).

        One symbolic loop drives the walk one event per iteration; a lane whose walk
        ended writes that ray's fate to the ray's slot and starts the next ray of its queue
        (by default the next ray handed out by one atomic counter; see :class:`WalkQueue`).
        Every ray's random numbers are keyed on its global index, so the fates — and the
        counts — are those of
        :meth:`trace`, whichever lane ran the ray. Returns the per-ray ``fate``, ``rare``,
        ``weight`` (of violating rays), ``specular`` and ``regular`` (evaluated); with bins
        (a goniophotometer reading) also each ray's ``bin`` (:meth:`_bin` of its ``wo`` and
        fate when its walk ended, kept in its slot) and its reading's ``slot`` (symbolic).
        """

        size = source.size
        bsdf = self.bsdf
        width, queue = min(size, self.walk_queue.lanes), self.walk_queue.queue
        codes = dr.zeros(mi.UInt32, size)  # fate | rare << 4 | delta << 8, per ray
        weights = dr.zeros(mi.Float, size)
        # A goniophotometer reading keeps each ray's bin (tallied after the loop).
        ray_bins = dr.zeros(mi.UInt32, size) if self.hook is not None else None
        # Queues: "stride" — lane l runs positions l, l + L, …; "counter" — one shared counter
        # hands out the next position; "group" — each group of WALK_GROUP lanes (a SIMD packet,
        # run by one thread) shares a counter over its own contiguous range of positions.
        if queue == "group" and width >= WALK_GROUP:
            width -= width % WALK_GROUP  # whole groups
        groups = width // WALK_GROUP if queue == "group" and width >= WALK_GROUP else 1
        share = -(-size // groups)  # positions per queue
        counter = dr.zeros(mi.UInt32, groups) if queue != "stride" else None
        step = width // groups  # lanes per queue

        # A lane's cursor: its ray's position in the chunk and, for several readings, that
        # reading's slot and end. Positions only grow along a queue, so the slot moves forward.
        def cursor_at(position: Any, group: Any, before: dict | None = None) -> dict:
            cursor = {"position": position}
            if groups > 1:
                cursor["group"] = group
            if source.single or (self.walk_queue.prestart and ray_bins is None):  # no reading needed
                return cursor
            if before is None:
                slot = source.slot(position)
                end = dr.gather(mi.UInt32, source.ends, slot)
            else:
                slot, end = dr.while_loop((before["slot"], before["end"]), lambda s, e: e <= position,
                                          lambda s, e: (s + 1, dr.gather(mi.UInt32, source.ends, s + 1)),
                                          label="walk_reading")
            return {**cursor, "slot": slot, "end": end}

        def queue_end(group: Any) -> Any:
            return dr.minimum(group * share + share, size) if groups > 1 else mi.UInt32(size)

        def begin(position: Any, slot: Any) -> tuple[Any, Any, Any]:
            ray = source.incident(position, slot)
            state = self._walk_start(ray["si"], ray["sample1"], ray["sample2"])
            return state, ray["si"].wi.z >= 0.0, ray["survival"]

        if self.walk_queue.prestart:
            # Every ray's start (incident ray, walk_start) in one kernel over the whole chunk at
            # full SIMD use; a refill then only gathers its ray's start from it.
            everyone = dr.arange(mi.UInt32, size)
            started = begin(everyone, source.slot(everyone))
            dr.eval(started)

            def start(cursor: dict) -> tuple[Any, Any, Any]:
                return gather_tree(started, cursor["position"])
        else:
            def start(cursor: dict) -> tuple[Any, Any, Any]:
                return begin(cursor["position"], None if source.single else cursor["slot"])

        def next_ray(position: Any, group: Any) -> Any:
            if counter is None:
                return position + width
            if groups == 1:
                return dr.scatter_inc(counter, mi.UInt32(0)) + step
            return group * share + dr.scatter_inc(counter, group) + step

        def finish(cursor: dict, state: Any, lit_above: Any, survival: Any) -> tuple:
            position = cursor["position"]
            bs, weight = bsdf.walk_sample(state)
            judged = self._judge(lit_above, bs, weight, survival, width)
            delta = mi.has_flag(judged["sampled_type"], mi.BSDFFlags.Delta)
            code = judged["fate"] | (judged["rare"] << 4) | dr.select(delta, mi.UInt32(256), mi.UInt32(0))
            dr.scatter(codes, code, position)
            dr.scatter(weights, judged["weight"], position, (judged["rare"] & _VIOLATION) != 0)
            if ray_bins is not None:
                slot = None if source.single else cursor["slot"]
                dr.scatter(ray_bins, self._reading_bin(source, slot, judged["wo"], judged["fate"]), position)
            group = cursor.get("group")
            position = next_ray(position, group)

            def restart(cursor: dict, *_: Any) -> tuple:
                cursor = cursor_at(position, group, cursor)
                return (cursor, *start(cursor))

            return dr.if_stmt(({**cursor, "position": position}, state, lit_above, survival),
                              position < queue_end(group), restart, lambda *args: args, label="walk_restart")

        refill = self.walk_queue.refill
        stats = self.walk_stats

        def body(cursor: dict, state: Any, lit_above: Any, survival: Any, iteration: Any, busy: Any) -> tuple:
            walking = ~bsdf.walk_done(state)
            state = dr.if_stmt((state,), walking, lambda s: (bsdf.walk_step(s),), lambda s: (s,),
                               label="walk_step")[0]
            due = bsdf.walk_done(state)
            if refill > 1:
                due &= (iteration & (refill - 1)) == 0
            if stats is not None:
                busy = busy + dr.select(walking, mi.UInt32(1), mi.UInt32(0))
            return (*dr.if_stmt((cursor, state, lit_above, survival), due, finish,
                                lambda *args: args, label="walk_finish"), iteration + 1, busy)

        lane = dr.arange(mi.UInt32, width)
        group = lane // WALK_GROUP if groups > 1 else None
        position = group * share + lane % WALK_GROUP if groups > 1 else lane
        cursor = cursor_at(position, group)
        loop = dr.while_loop((cursor, *start(cursor), mi.UInt32(0), mi.UInt32(0)),
                             lambda c, *_: c["position"] < queue_end(c.get("group")), body, label="walk_queue")
        if stats is not None:  # diagnostics: per lane, loop iterations and iterations that stepped a walk
            iterations, busy = loop[-2:]
            dr.eval(iterations, busy)
            stats.setdefault("iterations", []).append(np.array(iterations))
            stats.setdefault("busy", []).append(np.array(busy))
        dr.eval(codes, weights, ray_bins)
        fate = codes & 15
        rare = (codes >> 4) & 15
        delta = (codes & 256) != 0
        lanes = {"fate": fate, "rare": rare, "weight": weights,
                 "specular": (fate == int(Fate.REFLECTED)) & delta, "regular": (fate == int(Fate.TRANSMITTED)) & delta,
                 "slot": source.slot(dr.arange(mi.UInt32, size))}
        if ray_bins is not None:
            lanes["bin"] = ray_bins
        return lanes

    def _walk_start(self, si: Any, sample1: Any, sample2: Any) -> Any:
        """The specimen's ``walk_start``; a feature it needs that the instrument lacks is a ``ValueError``."""

        return self._unsupported(lambda: self.bsdf.walk_start(si, sample1, sample2, True))

    def _judge(self, lit_above: Any, bs: Any, weight: Any, survival: Any, size: int) -> dict:
        """
        The fate of each ray from its BSDF sample (see the module's conventions): ``fate``,
        ``rare`` bits, the broadcast ``weight``, ``wo``, ``sampled_type``, ``specular`` and
        ``regular``. ``lit_above``: wi·n ≥ 0; ``survival``: the ray's roulette uniform.
        """

        # Per ray, at the chunk's width (a BSDF may return width-1 literals).
        w = full(mi.Spectrum(weight)[0], size)
        wo = mi.Vector3f(*(full(c, size) for c in (bs.wo.x, bs.wo.y, bs.wo.z)))
        sampled_type, component = full(bs.sampled_type, size), full(bs.sampled_component, size)
        survives = survival < w
        # wo·n = 0 exactly (grazing exit): the sampled event decides — transmission crosses.
        crossed = mi.has_flag(sampled_type, mi.BSDFFlags.Transmission)
        upper = dr.select(wo.z != 0.0, wo.z > 0.0, crossed ^ lit_above)
        fate = dr.select(survives, dr.select(upper, mi.UInt32(int(Fate.REFLECTED)), mi.UInt32(int(Fate.TRANSMITTED))),
                         mi.UInt32(int(Fate.ABSORBED)))
        # NaN, infinite or not unit length (NaN fails both comparisons): no hemisphere to judge.
        length2 = dr.squared_norm(wo)
        invalid = ~((length2 >= _LENGTH2[0]) & (length2 <= _LENGTH2[1])) & (w > 0.0)
        fate = dr.select(invalid, mi.UInt32(int(Fate.INVALID)), fate)
        capped = component == CAPPED_COMPONENT
        fate = dr.select(capped, mi.UInt32(int(Fate.CAPPED)), fate)
        invalid &= ~capped
        # u < w makes a weight in (1, 1 + ε] always survive and one in [−ε, 0) never: rounding.
        exact = (w >= 0.0) & (w <= 1.0)
        rounded = ~exact & (w >= -WEIGHT_ROUNDING) & (w <= 1.0 + WEIGHT_ROUNDING)
        violation = ~exact & ~rounded
        rare = (dr.select(violation, mi.UInt32(_VIOLATION), 0) | dr.select(capped, mi.UInt32(_CAPPED), 0)
                | dr.select(rounded, mi.UInt32(_ROUNDED), 0) | dr.select(invalid, mi.UInt32(_INVALID), 0))
        delta = mi.has_flag(sampled_type, mi.BSDFFlags.Delta)
        specular, regular = (fate == int(Fate.REFLECTED)) & delta, (fate == int(Fate.TRANSMITTED)) & delta
        return {"wo": wo, "fate": fate, "weight": w, "rare": rare, "sampled_type": sampled_type,
                "specular": specular, "regular": regular}

    def _reading_bin(self, source: RaySource, slot: Any, wo: Any, fate: Any) -> Any:
        """
        The hook's bin of rays of readings ``slot`` of the chunk (``None``: a single reading), with their φi
        (and, for a hook with ``incidence``, their reading's incidence direction ω).
        """

        phi_i = source.column(self.phi_i[source.slots].astype(np.float32), mi.Float, slot)
        if not self.hook.incidence:
            return self.hook.bin(wo, fate, phi_i)
        omega = self.readings[source.slots, 10:13].astype(np.float32)  # each reading's ω (towards the emitter)
        wi = mi.Vector3f(*(source.column(omega[:, c], mi.Float, slot) for c in range(3)))
        return self.hook.bin(wo, fate, phi_i, wi)

    def _sample(self, si: Any, sample1: Any, sample2: Any) -> tuple[Any, Any]:
        """The specimen BSDF's ``sample`` (importance transport)."""

        context = mi.BSDFContext(mi.TransportMode.Importance)
        return _sample_pair(self.bsdf, self._unsupported(lambda: self.bsdf.sample(context, si, sample1, sample2, True)))

    def _unsupported(self, call: Callable[[], Any]) -> Any:
        """``call()``; a feature the specimen needs that the instrument lacks is a ``ValueError``."""

        try:
            return call()
        except RuntimeError as error:
            if "not implemented" not in str(error):
                raise
            raise ValueError(
                f"the specimen BSDF {self.bsdf.class_name() if hasattr(self.bsdf, 'class_name') else self.bsdf} "
                f"cannot be sampled by the instrument ({error}): its surface interaction holds a position, "
                "normal, shading frame, uv and wavelength, but no uv partials (dp_du, dp_dv) and no ray "
                "differentials, so features that differentiate a texture over the surface — bumpmap, or "
                "normalmap and textures that need gradients or footprints — are not supported") from None


def _sample_pair(bsdf: Any, sampled: Any) -> tuple[Any, Any]:
    """
    What a BSDF's ``sample()`` returned, as Mitsuba's ``(BSDFSample3f, weight)`` pair; another value (a Python
    BSDF that returns the sample alone, or three values) is a ``ValueError`` naming the BSDF and the fix.
    """

    if isinstance(sampled, (tuple, list)) and len(sampled) == 2 and isinstance(sampled[0], mi.BSDFSample3f):
        return sampled[0], sampled[1]
    name = type(bsdf).__name__  # a Python BSDF's own class (Mitsuba's class_name() says "BSDF")
    got = (f"a {type(sampled).__name__} of {len(sampled)} values" if isinstance(sampled, (tuple, list))
           else f"one {type(sampled).__name__}")
    raise ValueError(f"the specimen BSDF {name}: sample() must return the pair (mi.BSDFSample3f, weight), as Mitsuba's "
                     f"BSDF.sample does (got {got}); return bs, weight where weight = f * cos(theta_o) / pdf")
