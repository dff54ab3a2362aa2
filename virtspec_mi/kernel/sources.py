"""
The incident rays of one kernel chunk: :class:`RaySource`
=========================================================

A chunk of the kernel (:mod:`virtspec_mi.kernel.tracer`) traces the packed lanes of its
readings; :class:`RaySource` gives any lane's incident ray — its emitter and specimen
points (eqs. 3, 4), direction and random-number keys — from its position in the chunk,
the same whether every position runs at once or a lane works through a queue of them,
and the helpers that map positions to readings (lane ranges, segment sums).

References
----------
Baranoski et al. (2001), eqs. (3), (4).
"""

from __future__ import annotations

from typing import Any

import drjit as dr
import mitsuba as mi
import numpy as np

from virtspec_mi.kernel.disk import jittered_cell, sample_disk
from virtspec_mi.kernel.rng import chunk_root, dimension_key, dimension_keys, hash32, to_unit

__all__ = ["RaySource", "WORD", "REJECTION_BASE", "WAVELENGTH", "CENTRE", "E_U", "E_V", "OMEGA", "STRATA",
           "gather_tree", "full", "lane_ranges", "find_slot", "segment_sums"]

WORD = 1 << 32
# Dimensions of the random numbers: 0–1 emitter, 2–3 specimen, 4–6 BSDF, 7 survival;
# eq. (3) rejection draws from dimension 8 on (attempt k: 8 + 4k + 2·disk, +1).
REJECTION_BASE = 8
# Columns of the per-reading table: wavelength, emitter centre D·ω, emitter axes e_u and
# e_v, incidence direction ω (towards the emitter), strata per side of the jittered grid.
WAVELENGTH, CENTRE, E_U, E_V, OMEGA, STRATA = 0, 1, 4, 7, 10, 13


class RaySource:
    """
    The incident rays of one chunk, the packed lanes [first, first + size): host-side
    keys and per-reading rows once per chunk, then any ray's quantities from its
    position p in the chunk (:meth:`incident`, :meth:`uniform`) — the same whether all
    positions run at once (:meth:`_Kernel.trace`) or a lane works through a queue of them
    (:meth:`_Kernel.walk`).
    """

    def __init__(self, kernel: Any, first: int, size: int, slots: np.ndarray, starts: np.ndarray,
                 offsets: np.ndarray) -> None:
        self.kernel, self.size = kernel, size
        # Position p of reading k has global ray index g = offsets[k] + (first + p − starts[k]); the
        # chunk never crosses a 2³² boundary of g, so one root and a per-reading low-word shift.
        self.shift = (offsets[slots] - starts[slots] + first) % WORD
        self.root = chunk_root(kernel.seed, int(offsets[slots[0]] + first - starts[slots[0]]) // WORD)
        # Per-reading parameters: width-1 opaque values for a single reading, else gathered.
        self.bounds, self.j0 = lane_ranges(first, size, slots, starts)
        self.slots, self.rows = slots, kernel.readings[slots]
        self.single = len(slots) == 1
        self.keys = [dr.opaque(mi.UInt32, k) for k in dimension_keys(self.root)]
        # Queued walks: a column equal for every reading of the chunk is one opaque value.
        self.fold_constant = kernel.queued
        # End (chunk position) of each reading's lanes, for a lane that moves along its queue.
        self.ends = mi.UInt32(np.append(self.bounds[1:], size).astype(np.uint32))

    def slot(self, lane: Any) -> Any:
        """Index of each position's reading in the chunk (``None`` for a single reading)."""

        return None if self.single else find_slot(self.bounds, lane)

    def column(self, values: np.ndarray, kind: Any, slot: Any) -> Any:
        """Per-reading ``values`` (one per slot of the chunk) at positions of readings ``slot``."""

        if slot is None or (self.fold_constant and np.all(values == values[0])):
            return dr.opaque(kind, values[0].item())
        return dr.gather(kind, kind(values), slot)

    def ray_index(self, lane: Any, slot: Any) -> Any:
        """Low word of the global ray index of each position."""

        if np.all(self.shift == self.shift[0]):  # consecutive readings (the default layout): one scalar
            return lane + dr.opaque(mi.UInt32, int(self.shift[0]))
        return lane + self.column(self.shift.astype(np.uint32), mi.UInt32, slot)

    def incident(self, lane: Any, slot: Any = False) -> dict:
        """Emitter point ``origin``, specimen point ``target``, the surface interaction ``si``,
        the BSDF's ``sample1``/``sample2`` and the roulette's ``survival`` uniform of the rays at
        positions ``lane`` (their readings ``slot``: found by a binary search when not given)."""

        kernel, rows, root = self.kernel, self.rows, self.root
        slot = self.slot(lane) if slot is False else slot

        def column(values: np.ndarray, kind: Any) -> Any:
            return self.column(values, kind, slot)

        ray = lane + column(self.j0, mi.UInt32) if slot is None else (
            lane - column(self.bounds, mi.UInt32) + column(self.j0, mi.UInt32))
        ray_index = self.ray_index(lane, slot)

        def uniform(dimension: int) -> mi.Float:
            return to_unit(hash32(ray_index ^ self.keys[dimension]), mi.Float)

        def vector(index: int) -> mi.Vector3f:
            return mi.Vector3f(*(column(rows[:, index + k], mi.Float) for k in range(3)))

        wavelength = column(rows[:, WAVELENGTH], mi.Float)

        if kernel.beam == "diffuse":
            u0, u1 = uniform(0), uniform(1)
            if kernel.sampling == "jittered":
                u0, u1 = jittered_cell(mi, u0, u1, ray, column(rows[:, STRATA].astype(np.uint32), mi.UInt32))
            wi = mi.warp.square_to_cosine_hemisphere(mi.Point2f(u0, u1))
            target = sample_disk(mi, kernel.sampling, uniform(2), uniform(3), kernel.specimen_radius,
                                 lambda r: rejection(ray_index, root, r, 1))
            origin = mi.Point3f(target.x, target.y, 0.0) + wi * kernel.distance
        elif kernel.beam == "collimated":
            wi = vector(OMEGA)
            target = mi.Point2f(0.0, 0.0)
            origin = mi.Point3f(wi)
        else:
            u0, u1 = uniform(0), uniform(1)
            if kernel.sampling == "jittered":
                u0, u1 = jittered_cell(mi, u0, u1, ray, column(rows[:, STRATA].astype(np.uint32), mi.UInt32))
            emitter = sample_disk(mi, kernel.sampling, u0, u1, kernel.emitter_radius,
                                  lambda r: rejection(ray_index, root, r, 0))
            target = sample_disk(mi, kernel.sampling, uniform(2), uniform(3), kernel.specimen_radius,
                                 lambda r: rejection(ray_index, root, r, 1))
            origin = mi.Point3f(vector(CENTRE) + emitter.x * vector(E_U) + emitter.y * vector(E_V))
            wi = dr.normalize(origin - mi.Point3f(target.x, target.y, 0.0))

        si = dr.zeros(mi.SurfaceInteraction3f)
        si.wi = wi
        si.wavelengths = mi.Spectrum(wavelength)
        si.sh_frame = kernel.frame
        si.n = kernel.frame.n
        si.p = kernel.centre + kernel.frame.s * target.x + kernel.frame.t * target.y
        radius = dr.norm(target)
        azimuth = dr.atan2(target.y, target.x) * dr.inv_two_pi
        si.uv = mi.Point2f(radius / kernel.specimen_radius, dr.select(azimuth < 0, azimuth + 1.0, azimuth))
        return {"origin": origin, "target": target, "si": si, "sample1": uniform(4),
                "sample2": mi.Point2f(uniform(5), uniform(6)), "survival": uniform(7)}


@dr.syntax
def rejection(ray_index: mi.UInt32, root: int, radius: mi.Float, disk: int) -> mi.Point2f:
    """Eq. (3): uniform points of the square [−r, r]² until one falls in the disk."""

    key = dr.opaque(mi.UInt32, root)
    dimension = mi.UInt32(REJECTION_BASE + 2 * disk)
    x = mi.Float(1.0)
    y = mi.Float(1.0)
    while dr.hint(x * x + y * y > 1.0, label="rejection"):
        kx = dimension_key(key, dimension)
        ky = dimension_key(key, dimension + 1)
        x = dr.fma(2.0, to_unit(hash32(ray_index ^ kx), mi.Float), -1.0)
        y = dr.fma(2.0, to_unit(hash32(ray_index ^ ky), mi.Float), -1.0)
        dimension += 4
    return mi.Point2f(x * radius, y * radius)


def gather_tree(tree: Any, index: Any) -> Any:
    """Entries ``index`` of every array of a PyTree (tuples, lists, dicts, Dr.Jit arrays and
    structs); a width-1 value (a literal, a scalar) is the same for every entry and kept."""

    if isinstance(tree, (tuple, list)):
        return type(tree)(gather_tree(item, index) for item in tree)
    if isinstance(tree, dict):
        return {key: gather_tree(item, index) for key, item in tree.items()}
    if not dr.is_array_v(tree) and not hasattr(type(tree), "DRJIT_STRUCT"):
        return tree
    if dr.width(tree) <= 1:
        return tree
    return dr.gather(type(tree), tree, index)


def full(value: Any, size: int) -> Any:
    """``value`` at width ``size``: a width-1 array broadcast (e.g. a constant BSDF weight), else as is."""

    return value if dr.width(value) == size else value + dr.zeros(type(value), size)


def lane_ranges(first: int, size: int, slots: np.ndarray, starts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per reading of a chunk: its first lane in the chunk, and the index of that lane's ray."""

    bounds = np.clip(starts[slots] - first, 0, size).astype(np.uint32)
    first_ray = np.maximum(first - starts[slots], 0).astype(np.uint32)
    return bounds, first_ray


def find_slot(bounds: np.ndarray, lane: mi.UInt32) -> mi.UInt32:
    """Index of the last reading whose first lane is ≤ ``lane`` (binary lifting, padded to 2^k)."""

    steps = max(1, int(np.ceil(np.log2(len(bounds)))))
    padded = np.full(1 << steps, 0xFFFFFFFF, dtype=np.uint32)
    padded[: len(bounds)] = bounds
    table = mi.UInt32(padded)
    slot = mi.UInt32(0)
    for step in reversed(range(steps)):
        probe = slot + (1 << step)
        slot = dr.select(dr.gather(mi.UInt32, table, probe) <= lane, probe, slot)
    return slot


def segment_sums(cumulative: Any, bounds: np.ndarray, ends: np.ndarray) -> np.ndarray:
    """Sums over lane ranges [bounds, ends) from an inclusive cumulative sum."""

    bounds, ends = bounds.astype(np.int64), ends.astype(np.int64)

    last = dr.gather(type(cumulative), cumulative, mi.UInt32(np.maximum(ends - 1, 0).astype(np.uint32)))
    before = dr.gather(type(cumulative), cumulative, mi.UInt32(np.maximum(bounds - 1, 0).astype(np.uint32)))
    last, before = np.array(last, dtype=np.uint64), np.array(before, dtype=np.uint64)
    before[bounds == 0] = 0
    return last - before
