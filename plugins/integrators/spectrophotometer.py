"""
``spectrophotometer``: the virtual integrating-sphere instrument
================================================================

Shoots rays from the emitter disk at the specimen disk and counts, per reading,
the rays the specimen's BSDF sends to the upper hemisphere (reflected), to the
lower hemisphere (transmitted) or absorbs. One reading = one (wavelength, θi, φi)
with its own N independent rays; all readings of a call run in chunks of one fused
Dr.Jit kernel each (rays → BSDF ``sample`` → fate → exact integer tallies).

Parameters
----------
theta_i : float, default 0
    Polar incidence angle in degrees, 0 ≤ θi ≤ 90.
phi_i : float, default 0
    Azimuthal incidence angle in degrees (from the specimen's local x axis).
wavelengths : string or float, default "551"
    Wavelengths in nm: numbers and ``start:stop:step`` ranges, comma/space separated.
mu : float, default 0.005
    Certified tolerance μ of each reading, 0 < μ < 0.5.
delta : float, default 0.01
    Allowed failure probability δ, 0 < δ < 1.
rays : integer, default: from the bound
    Rays per reading (overrides the bound), 1 ≤ rays ≤ 2³² − 1.
bound : string, default "hoeffding"
    Ray budget: ``hoeffding`` (eq. 23), ``chebyshev`` (eq. 15), ``exact`` (smallest N
    certified by the exact binomial law) or ``two-stage`` (pilot batch, then a fresh
    batch sized per reading; see :mod:`virtspec_mi.twostage`).
joint : boolean, default false
    Certify reflectance and transmittance together (each at δ/2).
pilot_rays : integer, default ⌈10/μ⌉
    Two-stage pilot rays per reading, 1 ≤ pilot_rays ≤ 2³² − 1.
pilot_delta : float, default δ/10
    Two-stage pilot failure probability, 0 < pilot_delta < δ.
beam : string, default "conical"
    ``conical`` (conical-hemispherical), ``collimated`` (directional-hemispherical) or
    ``diffuse`` (hemispherical-hemispherical: incidence directions cosine-distributed
    over the upper hemisphere, aimed at uniform points of the specimen disk; θi and
    φi are not used).
sampling : string, default "jittered"
    Disk sampling: ``jittered`` (eq. 4), ``random`` (eq. 3) or ``concentric``.
seed : integer, default 0
    Seed of the counter-based random numbers, 0 ≤ seed < 2³².
chunk_size : integer, default 4194304
    Rays per kernel launch (bounds memory; results do not depend on it).

``mi.render(scene, seed=s, spp=n)`` returns a ``TensorXf`` of shape
``(len(wavelengths), 3)``: per wavelength (rows, in the order given) the
reflectance, transmittance and absorptance. ``spp`` > 0 sets the rays per reading;
``seed`` is added to the ``seed`` parameter. The full reading (counts, rays,
settings) is kept in ``integrator.last_reading``. The scene needs a sensor for
``mi.render`` (any; it is not used).

Conventions
-----------
- Fates are judged in the specimen frame: a ray leaving with wo·n > 0 is reflected
  (upper hemisphere), wo·n < 0 transmitted; one leaving exactly in the plane
  (wo·n = 0, grazing) counts on the far side of the specimen if the BSDF sampled a
  transmission, else on the side it came from. A zero BSDF weight is absorption.
- A reflected (transmitted) ray whose sampled event is a delta event
  (``DeltaReflection`` or ``DeltaTransmission``) also counts as specular reflection
  (regular transmission): ``Reading.specular_reflectance``,
  ``Reading.regular_transmittance``. They are counted per ray for a BSDF whose flags
  hold both delta and non-delta lobes; for one with only delta lobes they equal R and
  T, for one without delta lobes they are 0 (Mitsuba's flag contract).
- A walk that reached its step cap (``bs.sampled_component`` ==
  :data:`virtspec_mi.walk.CAPPED_COMPONENT`) is counted as ``capped``, apart from the
  three fates.
- A BSDF weight w ∈ [0, 1] survives with probability w (Russian roulette) so each
  ray stays a Bernoulli trial; weights outside [0, 1] or NaN are counted as
  ``weight_violations`` (the reading's guarantee then does not hold).
- Rays are traced in ``TransportMode.Importance`` (light travels from the emitter).
- The emitter disk neither occludes nor self-intersects its rays, and no general
  intersection is needed: each conical ray is aimed at a sampled specimen point and
  hits it by construction; a collimated ray hits the specimen centre.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import drjit as dr
import mitsuba as mi
import numpy as np

from virtspec_mi.geometry import incidence_frame, jittered_cell, sample_disk
from virtspec_mi.rng import chunk_root, dimension_key, dimension_keys, hash32, to_unit
from virtspec_mi.settings import Settings
from virtspec_mi.walk import CAPPED_COMPONENT

__all__ = ["ReadingPlan", "Spectrophotometer", "tally_readings", "trace_rays"]

_WORD = 1 << 32
# Dimensions of the random numbers: 0–1 emitter, 2–3 specimen, 4–6 BSDF, 7 survival;
# eq. (3) rejection draws from dimension 8 on (attempt k: 8 + 4k + 2·disk, +1).
_REJECTION_BASE = 8
# Columns of the per-reading table: wavelength, emitter centre D·ω, emitter axes e_u and
# e_v, incidence direction ω (towards the emitter), strata per side of the jittered grid.
_WAVELENGTH, _CENTRE, _E_U, _E_V, _OMEGA, _STRATA = 0, 1, 4, 7, 10, 13


@dataclass(frozen=True)
class ReadingPlan:
    """One reading for the kernel: wavelength (nm), incidence (degrees) and its rays."""

    wavelength: float
    theta_i: float
    phi_i: float
    rays: int


class Spectrophotometer(mi.SamplingIntegrator):
    """The instrument as a Mitsuba integrator (see the module docstring)."""

    def __init__(self, props: mi.Properties) -> None:
        super().__init__(props)
        names = ("theta_i", "phi_i", "wavelengths", "mu", "delta", "rays", "bound", "beam",
                 "sampling", "seed", "chunk_size", "joint", "pilot_rays", "pilot_delta")
        values = {name: props.get(name) for name in names if name in props}
        if "wavelengths" in values and not isinstance(values["wavelengths"], str):
            values["wavelengths"] = [values["wavelengths"]]
        try:
            self.settings = Settings(**values)
        except ValueError as error:
            raise ValueError(f"spectrophotometer: {error}") from None
        self.last_reading = None

    def render(self, scene, sensor=None, seed=0, spp=0, develop=True, evaluate=True):
        from virtspec_mi.reading import measure

        reading = measure(
            scene,
            seed=(self.settings.seed + int(seed)) % _WORD,
            rays=int(spp) if spp else None,
        )
        self.last_reading = reading
        table = np.stack([reading.reflectance, reading.transmittance, reading.absorptance], axis=1)
        return mi.TensorXf(table.astype(np.float32))

    def sample(self, scene, sampler, ray, medium=None, active=True):
        return mi.Spectrum(0.0), mi.Bool(False), []

    def to_string(self) -> str:
        return f"Spectrophotometer[{self.settings}]"


def tally_readings(
    instrument: Any, plans: list[ReadingPlan], settings: Settings, offsets: Any = None
) -> np.ndarray:
    """
    Trace every reading of ``plans`` and return exact counts, shape ``(len(plans), 6)``:
    reflected, transmitted, weight-violating, capped, specularly reflected and
    regularly transmitted rays per reading (``int64``).

    Reading k's rays are the global ray indices [offsets[k], offsets[k] + rays_k);
    ``offsets`` defaults to consecutive ranges (0, rays_0, rays_0 + rays_1, …) and may
    leave gaps (a sweep keys each reading on its index in the whole sweep, so a reading
    gets the same rays whichever other readings share the call). Ranges must not
    overlap. The readings' rays are packed into lanes in list order and cut into chunks
    of at most ``settings.chunk_size`` rays (never straddling a 2³² boundary of the
    global index); each chunk runs as one kernel, so memory stays bounded and counts do
    not depend on chunking.
    """

    rays = np.array([plan.rays for plan in plans], dtype=np.int64)
    starts = np.concatenate([[0], np.cumsum(rays)])  # packed (lane) position of each reading
    offsets = starts[:-1].copy() if offsets is None else _check_offsets(offsets, rays)
    # Packed positions where the high word of the global index changes: chunks are cut there.
    cuts = [starts[-1]]
    for k in range(len(plans)):
        first_block, last_block = offsets[k] // _WORD, (offsets[k] + rays[k] - 1) // _WORD
        cuts.extend(starts[k] + (b * _WORD - offsets[k]) for b in range(first_block + 1, last_block + 1))
        if k and first_block != (offsets[k - 1] + rays[k - 1] - 1) // _WORD:
            cuts.append(starts[k])
    cuts = np.unique(np.array(cuts, dtype=np.int64))
    counts = np.zeros((len(plans), 6), dtype=np.int64)
    kernel = _Kernel(instrument, plans, settings)
    first = 0
    while first < starts[-1]:
        size = int(min(settings.chunk_size, cuts[np.searchsorted(cuts, first, side="right")] - first))
        slots = np.arange(
            np.searchsorted(starts, first, side="right") - 1,
            np.searchsorted(starts, first + size, side="left"),
        )
        counts[slots] += kernel.run(first, size, slots, starts, offsets)
        first += size
    return counts


def _check_offsets(offsets: Any, rays: np.ndarray) -> np.ndarray:
    """Per-reading starts of the global ray index: whole numbers ≥ 0, ranges disjoint, < 2⁶³."""

    offsets = np.asarray(offsets)
    if offsets.shape != rays.shape or (offsets.size and not np.issubdtype(offsets.dtype, np.integer)):
        raise ValueError(f"offsets must be {len(rays)} whole numbers, one per reading")
    offsets = offsets.astype(np.int64)
    order = np.argsort(offsets, kind="stable")
    ends = offsets[order] + rays[order]
    if offsets.size and (offsets.min() < 0 or np.any(offsets[order][1:] < ends[:-1])):
        raise ValueError("offsets must be >= 0 and the readings' ray ranges [offset, offset + rays) disjoint")
    return offsets


def trace_rays(instrument: Any, plan: ReadingPlan, settings: Settings, count: int) -> dict:
    """
    The first ``count`` rays of one reading, ray by ray, through the same kernel code
    as :func:`tally_readings` (for tests and diagnostics): NumPy arrays of emitter
    points ``origin`` (specimen frame), specimen points ``target``, incident
    directions ``wi`` (towards the emitter), outgoing ``wo`` and ``fate``
    (0 absorbed, 1 reflected, 2 transmitted, 3 capped walk).
    """

    kernel = _Kernel(instrument, [plan], settings)
    lanes = kernel.trace(0, count, np.array([0]), np.array([0, plan.rays]), np.array([0]))
    dr.eval(lanes)
    return {name: np.array(value).T if np.ndim(value) > 1 else np.array(value)
            for name, value in lanes.items()}


class _Kernel:
    """The per-chunk ray kernel of one :func:`tally_readings` call."""

    def __init__(self, instrument: Any, plans: list[ReadingPlan], settings: Settings) -> None:
        self.bsdf = instrument.bsdf
        self.settings = settings
        # Specular/regular counts: per ray only for a BSDF with both delta and other lobes.
        flags = self.bsdf.flags()
        delta = mi.has_flag(flags, mi.BSDFFlags.Delta)
        smooth = mi.has_flag(flags, mi.BSDFFlags.Smooth) or mi.has_flag(flags, mi.BSDFFlags.Null)
        self.delta_lobes = "mixed" if delta and smooth else "all" if delta else "none"
        geometry = instrument.geometry
        self.emitter_radius = dr.opaque(mi.Float, geometry.emitter_radius)
        self.specimen_radius = dr.opaque(mi.Float, geometry.specimen_radius)
        self.distance = dr.opaque(mi.Float, geometry.distance)
        frame = instrument.to_world
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

    def run(self, first: int, size: int, slots: np.ndarray, starts: np.ndarray,
            offsets: np.ndarray) -> np.ndarray:
        """Counts (reflected, transmitted, violations, capped, specular, regular) of ``slots`` in a chunk."""

        lanes = self.trace(first, size, slots, starts, offsets)
        code = dr.select(lanes["fate"] == 1, mi.UInt64(1), mi.UInt64(0)) | dr.select(
            lanes["fate"] == 2, mi.UInt64(_WORD), mi.UInt64(0)
        )
        rare = (lanes["violation"], lanes["fate"] == 3)
        if self.delta_lobes == "mixed":
            delta = dr.select(lanes["specular"], mi.UInt64(1), mi.UInt64(0)) | dr.select(
                lanes["regular"], mi.UInt64(_WORD), mi.UInt64(0)
            )
            dr.eval(code, delta, *rare)  # the one fused ray kernel
        else:
            dr.eval(code, *rare)
        counts = np.zeros((len(slots), 6), dtype=np.int64)
        bounds, _ = _lane_ranges(first, size, slots, starts)
        ends = np.append(bounds[1:], size)
        packed_codes = ((0, code), (4, delta)) if self.delta_lobes == "mixed" else ((0, code),)
        for column, packed_code in packed_codes:  # two 32-bit counts per UInt64
            if len(slots) == 1:
                packed = np.array([int(dr.sum(packed_code).numpy()[0])], dtype=np.uint64)
            else:
                packed = _segment_sums(dr.cumsum(packed_code), bounds, ends)
            counts[:, column] = packed & np.uint64(_WORD - 1)
            counts[:, column + 1] = packed >> np.uint64(32)
        if self.delta_lobes == "all":  # every event is a delta event: nothing to count
            counts[:, 4:6] = counts[:, 0:2]
        for column, flags in enumerate(rare, start=2):  # almost always none: skip the scan
            if int(dr.count(flags).numpy()[0]) > 0:
                counts[:, column] = _segment_sums(dr.cumsum(mi.UInt64(dr.select(flags, 1, 0))), bounds, ends)
        return counts

    def trace(self, first: int, size: int, slots: np.ndarray, starts: np.ndarray,
              offsets: np.ndarray) -> dict:
        """Symbolic per-lane quantities of the packed lanes [first, first + size) (nothing evaluated)."""

        settings = self.settings
        lane = dr.arange(mi.UInt32, size)
        # Lane l of reading k has global ray index g = offsets[k] + (first + l − starts[k]); the
        # chunk never crosses a 2³² boundary of g, so one root and a per-reading low-word shift.
        shift = (offsets[slots] - starts[slots] + first) % _WORD
        root = chunk_root(settings.seed, int(offsets[slots[0]] + first - starts[slots[0]]) // _WORD)

        # Per-reading parameters: width-1 opaque values for a single reading, else gathered.
        bounds, j0 = _lane_ranges(first, size, slots, starts)
        rows = self.readings[slots]
        if len(slots) == 1:
            def column(values: np.ndarray, kind: Any) -> Any:
                return dr.opaque(kind, values[0].item())
            ray = lane + column(j0, mi.UInt32)
        else:
            slot = _find_slot(bounds, lane)

            def column(values: np.ndarray, kind: Any) -> Any:
                return dr.gather(kind, kind(values), slot)
            ray = lane - column(bounds, mi.UInt32) + column(j0, mi.UInt32)
        if np.all(shift == shift[0]):  # consecutive readings (the default layout): one scalar
            ray_index = lane + dr.opaque(mi.UInt32, int(shift[0]))
        else:
            ray_index = lane + column(shift.astype(np.uint32), mi.UInt32)
        keys = [dr.opaque(mi.UInt32, k) for k in dimension_keys(root)]

        def uniform(dimension: int) -> mi.Float:
            return to_unit(hash32(ray_index ^ keys[dimension]), mi.Float)

        def vector(index: int) -> mi.Vector3f:
            return mi.Vector3f(*(column(rows[:, index + k], mi.Float) for k in range(3)))

        wavelength = column(rows[:, _WAVELENGTH], mi.Float)

        if settings.beam == "diffuse":
            u0, u1 = uniform(0), uniform(1)
            if settings.sampling == "jittered":
                u0, u1 = jittered_cell(mi, u0, u1, ray, column(rows[:, _STRATA].astype(np.uint32), mi.UInt32))
            wi = mi.warp.square_to_cosine_hemisphere(mi.Point2f(u0, u1))
            target = sample_disk(mi, settings.sampling, uniform(2), uniform(3), self.specimen_radius,
                                 lambda r: _rejection(ray_index, root, r, 1))
            origin = mi.Point3f(target.x, target.y, 0.0) + wi * self.distance
        elif settings.beam == "collimated":
            wi = vector(_OMEGA)
            target = mi.Point2f(0.0, 0.0)
            origin = mi.Point3f(wi)
        else:
            u0, u1 = uniform(0), uniform(1)
            if settings.sampling == "jittered":
                u0, u1 = jittered_cell(mi, u0, u1, ray, column(rows[:, _STRATA].astype(np.uint32), mi.UInt32))
            emitter = sample_disk(mi, settings.sampling, u0, u1, self.emitter_radius,
                                  lambda r: _rejection(ray_index, root, r, 0))
            target = sample_disk(mi, settings.sampling, uniform(2), uniform(3), self.specimen_radius,
                                 lambda r: _rejection(ray_index, root, r, 1))
            origin = mi.Point3f(vector(_CENTRE) + emitter.x * vector(_E_U) + emitter.y * vector(_E_V))
            wi = dr.normalize(origin - mi.Point3f(target.x, target.y, 0.0))

        si = dr.zeros(mi.SurfaceInteraction3f)
        si.wi = wi
        si.wavelengths = mi.Spectrum(wavelength)
        si.sh_frame = self.frame
        si.n = self.frame.n
        si.p = self.centre + self.frame.s * target.x + self.frame.t * target.y
        radius = dr.norm(target)
        azimuth = dr.atan2(target.y, target.x) * dr.inv_two_pi
        si.uv = mi.Point2f(radius / self.specimen_radius, dr.select(azimuth < 0, azimuth + 1.0, azimuth))
        context = mi.BSDFContext(mi.TransportMode.Importance)
        bs, weight = self.bsdf.sample(context, si, uniform(4), mi.Point2f(uniform(5), uniform(6)), True)
        w = mi.Spectrum(weight)[0]
        survives = uniform(7) < w
        # wo·n = 0 exactly (grazing exit): the sampled event decides — transmission crosses.
        crossed = mi.has_flag(bs.sampled_type, mi.BSDFFlags.Transmission)
        upper = dr.select(bs.wo.z != 0.0, bs.wo.z > 0.0, crossed ^ (wi.z >= 0.0))
        fate = dr.select(survives, dr.select(upper, mi.UInt32(1), mi.UInt32(2)), mi.UInt32(0))
        fate = dr.select(bs.sampled_component == CAPPED_COMPONENT, mi.UInt32(3), fate)
        violation = ~((w >= 0.0) & (w <= 1.0))
        delta = mi.has_flag(bs.sampled_type, mi.BSDFFlags.Delta)
        specular, regular = (fate == 1) & delta, (fate == 2) & delta
        return {"origin": origin, "target": target, "wi": wi, "wo": bs.wo, "fate": fate,
                "violation": violation, "specular": specular, "regular": regular}


@dr.syntax
def _rejection(ray_index: mi.UInt32, root: int, radius: mi.Float, disk: int) -> mi.Point2f:
    """Eq. (3): uniform points of the square [−r, r]² until one falls in the disk."""

    key = dr.opaque(mi.UInt32, root)
    dimension = mi.UInt32(_REJECTION_BASE + 2 * disk)
    x = mi.Float(1.0)
    y = mi.Float(1.0)
    while dr.hint(x * x + y * y > 1.0, label="rejection"):
        kx = dimension_key(key, dimension)
        ky = dimension_key(key, dimension + 1)
        x = dr.fma(2.0, to_unit(hash32(ray_index ^ kx), mi.Float), -1.0)
        y = dr.fma(2.0, to_unit(hash32(ray_index ^ ky), mi.Float), -1.0)
        dimension += 4
    return mi.Point2f(x * radius, y * radius)


def _lane_ranges(first: int, size: int, slots: np.ndarray, starts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per reading of a chunk: its first lane in the chunk, and the index of that lane's ray."""

    bounds = np.clip(starts[slots] - first, 0, size).astype(np.uint32)
    first_ray = np.maximum(first - starts[slots], 0).astype(np.uint32)
    return bounds, first_ray


def _find_slot(bounds: np.ndarray, lane: mi.UInt32) -> mi.UInt32:
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


def _segment_sums(cumulative: Any, bounds: np.ndarray, ends: np.ndarray) -> np.ndarray:
    """Sums over lane ranges [bounds, ends) from an inclusive cumulative sum."""

    bounds, ends = bounds.astype(np.int64), ends.astype(np.int64)

    last = dr.gather(type(cumulative), cumulative, mi.UInt32(np.maximum(ends - 1, 0).astype(np.uint32)))
    before = dr.gather(type(cumulative), cumulative, mi.UInt32(np.maximum(bounds - 1, 0).astype(np.uint32)))
    last, before = np.array(last, dtype=np.uint64), np.array(before, dtype=np.uint64)
    before[bounds == 0] = 0
    return last - before
