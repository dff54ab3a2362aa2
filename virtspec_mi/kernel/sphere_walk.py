"""
The sphere walk: rays from the specimen through an integrating sphere to the detector
=====================================================================================

One reading = one wavelength with its own N rays. Each ray first meets the specimen as
in the hemispherical instrument (:func:`virtspec_mi.kernel.tracer.first_interactions`:
the same beam, random numbers and BSDF ``sample``, so the hemispherical fate of every
ray is kept alongside). Whatever the specimen returns into the sphere then walks it,
one surface per step of **one** symbolic Dr.Jit loop (:meth:`SphereWalk.step`: state
in → one flight and one surface event → state out; no host work per ray or bounce):

- **flight:** exact intersections — the sphere wall (far root of |p + t·d| = R), the
  port plane of each *holder* port (a port holding the specimen or the reference
  standard as a flat disk), the baffle disk; the nearest wins;
- **wall:** a hit point inside a port cap (x·c ≥ R cos α) takes that port's role —
  ``detector``: detected; an open port (entrance, SCE specular trap, ``open``): lost
  through it; a plugged port (SCI specular plug, the reference port of a single-beam
  substitution) is wall. On the wall (and the baffle, coated alike) the ray is
  absorbed with probability 1 − ρw(λ), else re-emitted Lambertian (cosine-weighted
  about the inward normal; the baffle's normal facing the ray);
- **holder:** a crossing of the port plane outside the disk leaves through that port;
  inside, the disk's BSDF samples the ray (``TransportMode.Importance``, weight by
  Russian roulette as in the tracer): absorbed, back into the sphere, or out through
  the port (behind a reflectance specimen, out of a transmittance one);
- **cap:** a ray still walking after ``max_bounces`` steps is capped (counted apart).

The rays that enter the sphere are walked by fewer lanes than rays (at least 2¹⁴, about
8 rays each): a lane whose ray ends takes the next one at once, so a packet of lanes
never idles behind its longest walk (walk lengths are geometric, and the longest of 16
is about three times the mean). Each ray's fate is written back at its own index.

Random numbers are counter-based, keyed on (seed, global ray index, dimension)
(:mod:`virtspec_mi.kernel.rng`): step b draws dimensions ``WALK_BASE + 4b + j``
(j = 0…3), far above the first interaction's, so counts are exact integers,
bit-reproducible and independent of chunking and of the lane layout. Every ray is one Bernoulli trial for
"detected".

Fate codes (:data:`FATES`): 0 detected, 1 absorbed by the wall or baffle, 2 absorbed
by holder 0 (the specimen in the beam), 3 absorbed by holder 1 (the other disk), 4
capped, 5 invalid direction, 6 + j lost through port j (index in ``sphere.ports``).

References
----------
Baranoski et al. (2001), Sect. 3 (fates, exact counts); Goebel (1967) (the sphere).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Sequence

import drjit as dr
import mitsuba as mi
import numpy as np

from virtspec_mi.kernel.counts import DIRECTION_TOLERANCE, WEIGHT_ROUNDING, Fate
from virtspec_mi.kernel.rng import GOLDEN, chunk_root, hash32, to_unit
from virtspec_mi.kernel.tracer import ReadingPlan, first_interactions
from virtspec_mi.kernel.walk import CAPPED_COMPONENT
from virtspec_mi.settings import Settings
from virtspec_mi.geometry.sphere import Sphere

__all__ = ["FATES", "WALK_BASE", "Holder", "SphereWalk", "holder_frame", "tally_sphere"]

FATES: tuple[str, ...] = ("detected", "absorbed_wall", "absorbed_specimen", "absorbed_other", "capped",
                          "invalid_directions")
"""Names of the fate codes 0 … 5; code 6 + j is "lost through port j"."""

WALK_BASE: int = 1 << 20
"""First random-number dimension of the walk (the first interaction uses dimensions < 2¹⁶ in practice)."""

_ACTIVE = 0xFF
_DETECTED, _WALL, _HOLDER0, _HOLDER1, _CAPPED, _INVALID, _LOST = 0, 1, 2, 3, 4, 5, 6
_VIOLATION, _ROUNDED = 1, 4
_LENGTH2 = ((1.0 - DIRECTION_TOLERANCE) ** 2, (1.0 + DIRECTION_TOLERANCE) ** 2)
_WORD = 1 << 32
_MIN_LANES = 1 << 14  # at least this many lanes (or one per ray): enough packets for every core
_RAYS_PER_LANE = 8  # otherwise each lane walks about this many rays in turn


@dataclass(frozen=True)
class Holder:
    """A flat disk in a port plane: port index, BSDF, disk radius (mm), frame (3×3, columns x, y, n)."""

    port: int
    bsdf: Any
    radius: float
    frame: np.ndarray


def holder_frame(axis: np.ndarray, outward: bool) -> np.ndarray:
    """
    The frame of a disk in a port plane (columns x, y, n): n = −axis (facing into the
    sphere) or +axis (``outward``, a transmittance specimen lit from outside); x is the
    sphere's +x projected onto the disk plane (+y when +x is within 25° of n).
    """

    n = np.asarray(axis, float) * (1.0 if outward else -1.0)
    e = np.array([1.0, 0.0, 0.0]) if abs(n[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = e - (e @ n) * n
    x /= np.linalg.norm(x)
    return np.stack([x, np.cross(n, x), n], axis=1)


def _vec(values: Sequence[float]) -> mi.Vector3f:
    return mi.Vector3f(*(float(v) for v in values))


class SphereWalk:
    """
    The walk of one sphere configuration: ``sphere``, the holders (holder 0 is lit by the
    beam), the fate of each port's cap (``actions``: fate code, or ``None`` for a plugged
    port that acts as wall) and the step cap.
    """

    def __init__(self, sphere: Sphere, holders: Sequence[Holder], actions: Sequence[int | None],
                 max_bounces: int) -> None:
        self.sphere = sphere
        self.holders = list(holders)
        self.actions = list(actions)
        self.max_bounces = int(max_bounces)
        radius = sphere.radius
        self.radius = radius
        self.caps = [(p.axis, radius * p.cos_half_angle(radius), action)
                     for p, action in zip(sphere.ports, self.actions) if action is not None]
        self.planes = [(sphere.ports[h.port].axis, radius * sphere.ports[h.port].cos_half_angle(radius),
                        sphere.port_plane_centre(sphere.ports[h.port])) for h in self.holders]

    # -- one step: state in → one flight and one surface event → state out --------------

    def step(self, state: dict, ray_index: Any, root: Any, rho_w: Any, wavelength: Any) -> dict:
        """One bounce of every lane still walking (``state['fate'] == ACTIVE``)."""

        p, d, last = state["p"], state["d"], state["last"]
        active = state["fate"] == _ACTIVE
        b = dr.dot(p, d)
        c = dr.squared_norm(p) - self.radius * self.radius
        t = -b + dr.safe_sqrt(b * b - c)
        surface = mi.UInt32(0)
        for k, (axis, offset, _) in enumerate(self.planes):
            cos_d = dr.dot(d, _vec(axis))
            t_k = (offset - dr.dot(p, _vec(axis))) / cos_d
            hit = (cos_d > 0.0) & (t_k > 0.0) & (t_k < t) & (last != k + 1)
            t = dr.select(hit, t_k, t)
            surface = dr.select(hit, mi.UInt32(k + 1), surface)
        baffle = self.sphere.baffle
        if baffle is not None:
            centre, normal = _vec(baffle.centre), _vec(baffle.normal)
            t_b = dr.dot(centre - p, normal) / dr.dot(d, normal)
            on_disk = dr.squared_norm(p + t_b * d - centre) <= baffle.radius * baffle.radius
            hit = (last != 3) & (t_b > 0.0) & (t_b < t) & on_disk
            t = dr.select(hit, t_b, t)
            surface = dr.select(hit, mi.UInt32(3), surface)
        x = p + t * d

        keys = [hash32(root + (mi.UInt32(WALK_BASE + j) + 4 * state["bounces"]) * GOLDEN) for j in range(4)]
        u = [to_unit(hash32(ray_index ^ key), mi.Float) for key in keys]

        fate = state["fate"]
        # the wall: port caps first, then absorption or Lambertian re-emission
        on_wall = active & (surface == 0)
        for axis, threshold, action in self.caps:
            inside = dr.dot(x, _vec(axis)) >= threshold
            fate = dr.select(on_wall & inside & (fate == _ACTIVE), mi.UInt32(action), fate)
        diffuse = (on_wall & (fate == _ACTIVE)) | (active & (surface == 3))
        inward = -dr.normalize(x)
        if baffle is not None:
            facing = dr.select(dr.dot(d, _vec(baffle.normal)) > 0.0, -_vec(baffle.normal), _vec(baffle.normal))
            inward = dr.select(surface == 3, facing, inward)
        survives = u[0] < rho_w
        fate = dr.select(diffuse & ~survives, mi.UInt32(_WALL), fate)
        local = mi.warp.square_to_cosine_hemisphere(mi.Point2f(u[1], u[2]))
        new_d = dr.normalize(mi.Frame3f(inward).to_world(local))
        on_sphere = x * (self.radius / dr.norm(x))
        new_p = dr.select(surface == 0, on_sphere, x)
        walls = state["walls"] + dr.select(diffuse & survives, mi.UInt32(1), mi.UInt32(0))
        rare = state["rare"]

        # the holders: a flat disk in its port plane, sampled by its BSDF
        for k, holder in enumerate(self.holders):
            _, _, centre = self.planes[k]
            on_holder = active & (surface == k + 1)
            q = x - _vec(centre)
            in_disk = dr.squared_norm(q) <= holder.radius * holder.radius
            lost = mi.UInt32(_LOST + holder.port)
            fate = dr.select(on_holder & ~in_disk, lost, fate)
            lit = on_holder & in_disk
            frame = mi.Frame3f(_vec(holder.frame[:, 0]), _vec(holder.frame[:, 1]), _vec(holder.frame[:, 2]))
            wo, w, component = dr.if_stmt(  # packets without a hit on this disk skip its BSDF
                (q, d, lit, *u, wavelength), lit,
                lambda q_, d_, lit_, u0, u1, u2, u3, lam, bsdf=holder.bsdf, frame=frame: self._sample(
                    bsdf, frame, q_, -d_, lam, [u0, u1, u2, u3], lit_),
                lambda *_: (mi.Vector3f(0.0, 0.0, 1.0), mi.Float(0.0), mi.UInt32(0)),
                label="sphere_holder")
            wo_world = frame.to_world(wo)
            length2 = dr.squared_norm(wo)
            invalid = ~((length2 >= _LENGTH2[0]) & (length2 <= _LENGTH2[1])) & (w > 0.0)
            lives = u[3] < w
            into = dr.dot(wo_world, _vec(self.planes[k][0])) < 0.0
            capped = component == CAPPED_COMPONENT
            code = dr.select(lives, dr.select(into, mi.UInt32(_ACTIVE), lost), mi.UInt32(_HOLDER0 + k))
            code = dr.select(invalid, mi.UInt32(_INVALID), code)
            code = dr.select(capped, mi.UInt32(_CAPPED), code)
            fate = dr.select(lit, code, fate)
            exact = (w >= 0.0) & (w <= 1.0)
            rounded = ~exact & (w >= -WEIGHT_ROUNDING) & (w <= 1.0 + WEIGHT_ROUNDING)
            rare = rare | dr.select(lit & ~exact & ~rounded & ~capped, mi.UInt32(_VIOLATION), 0) \
                | dr.select(lit & rounded, mi.UInt32(_ROUNDED), 0)
            new_d = dr.select(lit, wo_world, new_d)

        bounces = state["bounces"] + dr.select(active, mi.UInt32(1), mi.UInt32(0))
        fate = dr.select((fate == _ACTIVE) & (bounces >= self.max_bounces), mi.UInt32(_CAPPED), fate)
        return {"p": dr.select(active, new_p, p), "d": dr.select(active, new_d, d),
                "last": dr.select(active, surface, last), "fate": fate, "bounces": bounces, "walls": walls,
                "rare": rare}

    @staticmethod
    def _sample(bsdf: Any, frame: Any, q: Any, wi_world: Any, wavelength: Any, u: list,
                active: Any) -> tuple[Any, Any, Any]:
        """The disk BSDF's ``sample`` at the hit (local wi, point, uv, wavelength)."""

        si = dr.zeros(mi.SurfaceInteraction3f)
        si.wi = frame.to_local(wi_world)
        si.wavelengths = mi.Spectrum(wavelength)
        si.sh_frame = mi.Frame3f(mi.Vector3f(0.0, 0.0, 1.0))
        si.n = mi.Vector3f(0.0, 0.0, 1.0)
        local = frame.to_local(q)
        si.p = mi.Point3f(local.x, local.y, 0.0)
        azimuth = dr.atan2(local.y, local.x) * dr.inv_two_pi
        si.uv = mi.Point2f(dr.norm(mi.Vector2f(local.x, local.y)), dr.select(azimuth < 0, azimuth + 1.0, azimuth))
        context = mi.BSDFContext(mi.TransportMode.Importance)
        bs, weight = bsdf.sample(context, si, u[0], mi.Point2f(u[1], u[2]), active)
        return bs.wo, mi.Spectrum(weight)[0], bs.sampled_component

    # -- one chunk ------------------------------------------------------------------------

    def run(self, instrument: Any, plan: ReadingPlan, settings: Settings, first: int, size: int,
            offset: int, rho_w: float) -> dict[str, np.ndarray]:
        """
        Walk rays [first, first + size) of one reading (global index from ``offset``);
        return its histogram ``cross[h, code]`` (h: the first interaction's hemisphere, 0
        none, 1 upper by a non-delta event, 2 lower, 3 upper by a delta event — specular
        reflection; code: the sphere fate), wall reflections and rare counts.
        """

        global_first = offset + first
        block = global_first // _WORD
        if (global_first + size - 1) // _WORD != block:
            raise ValueError("a sphere chunk must not cross a 2**32 boundary of the global ray index")
        lanes = first_interactions(instrument, plan, settings, first, size, offset)
        base = dr.opaque(mi.UInt32, global_first % _WORD)  # global ray index (low word) of lane 0
        root = dr.opaque(mi.UInt32, chunk_root(settings.seed, block))
        holder = self.holders[0]
        axis, _, centre = self.planes[0]
        frame = holder.frame
        first_fate = lanes["fate"]
        wo = lanes["wo"]
        wo_world = mi.Vector3f(*(wo.x * frame[i, 0] + wo.y * frame[i, 1] + wo.z * frame[i, 2] for i in range(3)))
        target = lanes["target"]
        start = mi.Point3f(*(centre[i] + target.x * frame[i, 0] + target.y * frame[i, 1] for i in range(3)))
        left = (first_fate == int(Fate.REFLECTED)) | (first_fate == int(Fate.TRANSMITTED))
        into = dr.dot(wo_world, _vec(axis)) < 0.0
        fate = dr.select(left, dr.select(into, mi.UInt32(_ACTIVE), mi.UInt32(_LOST + holder.port)),
                         mi.UInt32(_HOLDER0))
        fate = dr.select(first_fate == int(Fate.CAPPED), mi.UInt32(_CAPPED), fate)
        fate = dr.select(first_fate == int(Fate.INVALID), mi.UInt32(_INVALID), fate)
        first_rare = lanes["rare"]
        rare = dr.select((first_rare & 1) != 0, mi.UInt32(_VIOLATION), 0) | dr.select(
            (first_rare & 4) != 0, mi.UInt32(_ROUNDED), 0)
        rho = dr.opaque(mi.Float, rho_w)
        wavelength = dr.opaque(mi.Float, plan.wavelength)
        hemisphere = dr.select(first_fate == int(Fate.REFLECTED),
                               dr.select(lanes["specular"], mi.UInt32(3), mi.UInt32(1)),
                               dr.select(first_fate == int(Fate.TRANSMITTED), mi.UInt32(2), mi.UInt32(0)))
        dr.eval(start, wo_world, fate, rare, hemisphere)  # the first interactions: one kernel
        walking = dr.compress(fate == _ACTIVE)  # the rays that entered the sphere
        walls = mi.UInt64(0)
        if dr.width(walking):
            fate, rare, walls = self._loop(walking, start, wo_world, fate, rare, base, root, rho, wavelength)

        codes = _LOST + len(self.sphere.ports)
        histogram = dr.zeros(mi.UInt32, 4 * codes)
        dr.scatter_reduce(dr.ReduceOp.Add, histogram, mi.UInt32(1), hemisphere * codes + fate)
        violations = dr.count((rare & _VIOLATION) != 0)
        rounded = dr.count((rare & _ROUNDED) != 0)
        dr.eval(histogram, walls, violations, rounded)
        return {"cross": np.array(histogram, dtype=np.int64).reshape(4, codes),
                "wall_reflections": int(np.array(walls)[0]), "weight_violations": int(np.array(violations)[0]),
                "rounded_weights": int(np.array(rounded)[0])}

    @dr.syntax
    def _loop(self, walking: Any, start: Any, direction: Any, fate: Any, rare: Any, base: Any, root: Any,
              rho: Any, wavelength: Any) -> tuple[Any, Any, Any]:
        """
        The one symbolic loop over the rays that entered the sphere (indices ``walking``):
        each of L lanes walks its rays one after the other (rays j, j + L, j + 2L … of
        ``walking``), :meth:`step` by step, and takes the next ray as soon as one ends — so
        a lane never idles behind a long walk of its packet. Per-ray fates and rare bits
        are written back at the rays' indices (the random numbers depend on the ray, not
        on the lane, so the counts do not depend on L). Returns the final per-ray fate and
        rare arrays and the wall reflections summed.
        """

        count = dr.width(walking)
        lanes = count if count <= _MIN_LANES else max(_MIN_LANES, -(-count // _RAYS_PER_LANE))
        n = dr.opaque(mi.UInt32, count)
        stride = dr.opaque(mi.UInt32, lanes)
        fate_out, rare_out = dr.copy(fate), dr.copy(rare)  # written per ray below; fate, rare only read
        slot = dr.arange(mi.UInt32, lanes)
        ray = dr.gather(mi.UInt32, walking, slot)
        p = dr.gather(mi.Point3f, start, ray)
        d = dr.gather(mi.Vector3f, direction, ray)
        state_rare = dr.gather(mi.UInt32, rare, ray)
        state_fate = dr.full(mi.UInt32, _ACTIVE, lanes)
        last = dr.full(mi.UInt32, 1, lanes)
        bounces = dr.zeros(mi.UInt32, lanes)
        walls = dr.zeros(mi.UInt32, lanes)
        while dr.hint(slot < n, label="sphere_walk"):
            out = self.step({"p": p, "d": d, "last": last, "fate": state_fate, "bounces": bounces, "walls": walls,
                             "rare": state_rare}, base + ray, root, rho, wavelength)
            done = out["fate"] != _ACTIVE
            dr.scatter(fate_out, out["fate"], ray, done)
            dr.scatter(rare_out, out["rare"], ray, done)
            slot = dr.select(done, slot + stride, slot)
            more = done & (slot < n)
            ray = dr.select(more, dr.gather(mi.UInt32, walking, slot, more), ray)
            p = dr.select(more, dr.gather(mi.Point3f, start, ray, more), out["p"])
            d = dr.select(more, dr.gather(mi.Vector3f, direction, ray, more), out["d"])
            state_rare = dr.select(more, dr.gather(mi.UInt32, rare, ray, more), out["rare"])
            state_fate = dr.select(more, mi.UInt32(_ACTIVE), out["fate"])
            last = dr.select(more, mi.UInt32(1), out["last"])
            bounces = dr.select(more, mi.UInt32(0), out["bounces"])
            walls = out["walls"]
        return fate_out, rare_out, dr.sum(mi.UInt64(walls))


def tally_sphere(walk: SphereWalk, instrument: Any, wavelengths: Sequence[float], rho_w: Sequence[float],
                 rays: int, settings: Settings) -> list[dict[str, Any]]:
    """
    Every reading (one per wavelength, ``rays`` rays each, consecutive global ray ranges
    as :func:`virtspec_mi.engine.readings.measure_reading` numbers them) in chunks of at most
    ``settings.chunk_size`` rays cut at 2³² boundaries; the chunks' tallies summed.
    """

    out = []
    for k, (wavelength, rho) in enumerate(zip(wavelengths, rho_w)):
        plan = ReadingPlan(float(wavelength), settings.theta_i, settings.phi_i, int(rays))
        offset = k * int(rays)
        total: dict[str, Any] | None = None
        first = 0
        while first < rays:
            size = min(settings.chunk_size, rays - first, _WORD - (offset + first) % _WORD)
            part = walk.run(instrument, plan, settings, first, size, offset, float(rho))
            total = part if total is None else {key: total[key] + part[key] for key in part}
            first += size
        out.append(total)
    return out
