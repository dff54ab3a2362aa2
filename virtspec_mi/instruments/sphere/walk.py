"""
The sphere walk: rays from the specimen through an integrating sphere to the detector
=====================================================================================

:class:`SphereLayout` is the integrating sphere as the kernel's exit hook
(:mod:`virtspec_mi.kernel.hooks`, ``needs_rays``): plain arrays only (the sphere's radius,
its port caps with their fates, the holders' port planes and disks, the baffle, the step
cap, the wall reflectance ρw per wavelength), so a layout is picklable and the kernel
imports nothing above it. Each ray first meets the specimen as in the hemispherical
instrument (:func:`virtspec_mi.kernel.tracer.tally_readings` traces it: the same beam,
random numbers and BSDF ``sample``, so the hemispherical fate of every ray is kept
alongside). Whatever the specimen returns into the sphere then walks it, one surface per
step of **one** symbolic Dr.Jit loop (:meth:`SphereLayout.step`: state in → one flight
and one surface event → state out; no host work per ray or bounce):

- **flight:** exact intersections — the sphere wall (far root of |p + t·d| = R), the
  port plane of each *holder* port (a port holding the specimen or the reference
  standard as a flat disk), the baffle disk; the nearest wins;
- **wall:** a hit point inside a port cap (x·c ≥ R cos α) takes that port's fate —
  detected, or lost through an open port; a plugged port has no cap here and is wall.
  On the wall (and the baffle, coated alike) the ray is absorbed with probability
  1 − ρw(λ), else re-emitted Lambertian (cosine-weighted about the inward normal; the
  baffle's normal facing the ray);
- **holder:** a crossing of the port plane outside the disk leaves through that port;
  inside, the disk's BSDF samples the ray (``TransportMode.Importance``, weight by
  Russian roulette as in the tracer): absorbed, back into the sphere, or out through
  the port (behind a reflectance specimen, out of a transmittance one);
- **cap:** a ray still walking after ``max_bounces`` steps is capped (counted apart).

Several readings (wavelengths) share a chunk as hemispherical readings do: each lane's
wavelength and ρw are its reading's, gathered by the reading's slot. The rays that
enter the sphere are walked by fewer lanes than rays (at least 2¹⁴, about 8 rays each):
a lane whose ray ends takes the next one at once, so a packet of lanes never idles
behind its longest walk (walk lengths are geometric, and the longest of 16 is about
three times the mean). Each ray's fate is written back at its own index.

A subclass scores the walk otherwise through a few hooks the plain walk leaves untraced
(:attr:`SphereLayout.carried` per-ray state with :meth:`SphereLayout.carried_starts` and
:meth:`SphereLayout.carried_sums`, :meth:`SphereLayout.entering`, ``_lives`` and the step's
``held``): :mod:`virtspec_mi.instruments.sphere.expected`, the expected-value detector.

Random numbers are counter-based, keyed on (seed, global ray index, dimension)
(:mod:`virtspec_mi.kernel.rng`): step b draws dimensions ``WALK_BASE + 4b + j``
(j = 0…3), far above the first interaction's, so counts are exact integers,
bit-reproducible and independent of chunking, of the lane layout and of which readings
share a chunk. Every ray is one Bernoulli trial for "detected".

A ray's bin code is ``hemisphere · codes + fate`` (:meth:`SphereLayout.exits`): the
hemisphere of its first interaction (0 none, 1 upper by a non-delta event, 2 lower,
3 upper by a delta event — specular reflection) and its sphere fate
(:class:`SphereFate`; codes = :attr:`SphereLayout.codes`); per reading it also sums wall
reflections, weight violations and rounded weights.

References
----------
Baranoski et al. (2001), Sect. 3 (fates, exact counts); Goebel (1967) (the sphere).

Dr.Jit and Mitsuba are imported where the walk runs, not with the module: a layout is
built (and pickled for a Dask worker) before Mitsuba is set up.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import IntEnum
from typing import Any, Sequence

import numpy as np

from virtspec_mi.kernel.counts import DIRECTION_TOLERANCE, WEIGHT_ROUNDING, Fate
from virtspec_mi.kernel.hooks import ChunkRays, ExitHook
from virtspec_mi.kernel.rng import GOLDEN, hash32, to_unit
from virtspec_mi.kernel.walk import CAPPED_COMPONENT

__all__ = ["FATES", "HEMISPHERES", "LAUNCH_STEPS", "SPECIMEN", "WALK_BASE", "Holder", "SphereFate", "SphereLayout", "holder_frame"]


class SphereFate(IntEnum):
    """
    How a ray's walk through the sphere ends (its sphere fate code); code
    ``LOST + j`` (:meth:`lost`) is "lost through port j" (index in the sphere's ports).
    """

    DETECTED = 0
    WALL = 1
    """Absorbed by the wall or the baffle."""
    HOLDER0 = 2
    """Absorbed by holder 0 (the disk in the beam: the specimen, or the standard)."""
    HOLDER1 = 3
    """Absorbed by holder 1 (the other disk)."""
    CAPPED = 4
    """Still walking after ``max_bounces`` steps, or a capped walk in a disk's BSDF."""
    INVALID = 5
    """An invalid outgoing direction from a disk's BSDF."""
    LOST = 6
    """Lost through port 0 (port j: ``LOST + j``)."""

    @staticmethod
    def lost(port: int) -> int:
        """The code of a ray lost through port ``port``."""

        return int(SphereFate.LOST) + int(port)


FATES: tuple[str, ...] = ("detected", "absorbed_wall", "absorbed_specimen", "absorbed_other", "capped",
                          "invalid_directions")
"""Names of the fate codes 0 … 5 (:class:`SphereFate` DETECTED … INVALID) in a result's counts."""

HEMISPHERES: tuple[str, ...] = ("none", "upper", "lower", "specular")
"""The first interaction's hemisphere, index h of a bin code h · codes + fate."""

SPECIMEN: str = "specimen"
"""A holder's BSDF that is the bench's specimen (any other holder BSDF is a Mitsuba plugin dict)."""

WALK_BASE: int = 1 << 20
"""First random-number dimension of the walk (the first interaction uses dimensions < 2¹⁶ in practice)."""

_ACTIVE = 0xFF
_VIOLATION, _ROUNDED = 1, 4
_LENGTH2 = ((1.0 - DIRECTION_TOLERANCE) ** 2, (1.0 + DIRECTION_TOLERANCE) ** 2)
_MIN_LANES = 1 << 14  # at least this many lanes (or one per ray): enough packets for every core
_RAYS_PER_LANE = 8  # otherwise each lane walks about this many rays in turn
LAUNCH_STEPS: int = 512
"""Steps each lane walks per kernel launch: between two launches the walk reaches a safe point (an interrupt
is honoured there: :attr:`~virtspec_mi.kernel.hooks.ChunkRays.safe_point`, the engine's), so a white sphere with small ports and a
large ``max_bounces`` answers Ctrl-C within about a second. The counts do not depend on it."""
_LOADED: dict[tuple[str, str], Any] = {}  # BSDFs loaded from their plugin dicts, per Mitsuba variant


@dataclass(frozen=True, eq=False)
class Holder:
    """
    A flat disk in a port plane: port index, BSDF (:data:`SPECIMEN` or a Mitsuba plugin
    dict, e.g. ``{"type": "diffuse", "reflectance": 0.99}``), disk radius (mm), frame
    (3×3, columns x, y, n).
    """

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


def _vec(values: Sequence[float]) -> Any:
    import mitsuba as mi

    return mi.Vector3f(*(float(v) for v in values))


def _loaded(spec: Any, specimen: Any) -> Any:
    """A holder's BSDF: the specimen, or its plugin dict loaded once per Mitsuba variant."""

    if isinstance(spec, str) and spec == SPECIMEN:
        return specimen
    if not isinstance(spec, dict):
        return spec  # already a BSDF (diagnostics; not picklable)
    import mitsuba as mi

    key = (mi.variant(), repr(sorted(spec.items())))
    if key not in _LOADED:
        _LOADED[key] = mi.load_dict(spec)
    return _LOADED[key]


@dataclass(frozen=True, eq=False)
class SphereLayout(ExitHook):
    """
    One sphere configuration as plain values (see the module docstring).

    Parameters
    ----------
    radius : float
        The sphere's radius R, mm.
    ports : int
        The number of ports (fate ``LOST + j`` for port j).
    caps : tuple
        (axis (3 floats), R cos α, fate code) of every port whose cap ends a walk
        (detected or lost); a plugged port has none (it is wall).
    planes : tuple
        (axis, R cos α, plane centre (3 floats)) of each holder's port.
    holders : tuple of Holder
        The disks in port planes; holder 0 is lit by the beam.
    baffle : tuple or None
        (centre (3 floats), unit normal (3 floats), radius) of the baffle disk.
    max_bounces : int
        The step cap of a walk.
    wall : tuple
        (wavelengths in nm, ρw at each): the wall reflectance at every wavelength the
        readings take.
    """

    radius: float
    ports: int
    caps: tuple
    planes: tuple
    holders: tuple
    baffle: tuple | None
    max_bounces: int
    wall: tuple

    needs_rays = True
    spectral = True
    sums = ("wall_reflections", "weight_violations", "rounded_weights")
    start_last = 1
    """The ``last`` surface of a walk's start (1: holder 0's plane)."""
    carried = ()
    """Names of further per-ray ``Float`` state a subclass's :meth:`step` carries (none here): each ray starts
    its walk at its value of :meth:`carried_starts`, and its value at the walk's end goes to :meth:`carried_sums`."""

    def entering(self, lanes: dict) -> Any:
        """Which first interactions send their ray on (into the sphere, or out through the port): the reflected
        and transmitted rays (the specimen's roulette kept the others)."""

        first_fate = lanes["fate"]
        return (first_fate == int(Fate.REFLECTED)) | (first_fate == int(Fate.TRANSMITTED))

    def carried_starts(self, lanes: dict) -> dict[str, Any]:
        """Every ray's start value of each :attr:`carried` state (none here)."""

        return {}

    def carried_sums(self, carried: dict[str, Any], rays: ChunkRays) -> dict[str, Any]:
        """Per-ray whole numbers to sum from the :attr:`carried` state of every ray at its walk's end (none here)."""

        return {}

    def extra_columns(self, wavelengths: np.ndarray) -> tuple:
        """Further per-reading values :meth:`step` takes as columns (none here; a subclass's)."""

        return ()

    @property
    def codes(self) -> int:
        """Sphere fate codes: :class:`SphereFate` DETECTED … INVALID and one per port."""

        return int(SphereFate.LOST) + self.ports

    @property
    def size(self) -> int:
        return len(HEMISPHERES) * self.codes

    def codes_of(self, fate: int) -> tuple[int, ...]:
        """The bin codes of the rays whose sphere fate is ``fate`` (one per first-interaction hemisphere)."""

        return tuple(h * self.codes + int(fate) for h in range(len(HEMISPHERES)))

    def beam_bsdf(self, specimen: Any) -> Any:
        return _loaded(self.holders[0].bsdf, specimen)

    def wall_reflectance(self, wavelengths: np.ndarray) -> np.ndarray:
        """ρw at ``wavelengths`` (each one of :attr:`wall`'s, in increasing order there)."""

        grid, values = (np.asarray(v, dtype=np.float64) for v in self.wall)
        index = np.minimum(np.searchsorted(grid, wavelengths), len(grid) - 1)
        if not np.array_equal(grid[index], wavelengths):  # the engine's contract: the layout covers its readings
            raise ValueError(f"the sphere layout holds no wall reflectance at {sorted(set(wavelengths) - set(grid))} nm")
        return values[index]

    # -- the chunk: first interactions in, bin codes and sums out -------------------------

    def exits(self, rays: ChunkRays) -> tuple[Any, dict[str, Any]]:
        """
        Continue the chunk's first interactions through the sphere: each ray's bin code
        (hemisphere · codes + sphere fate) and its wall reflections, weight violation and
        rounded weight (0 or 1 each), evaluated.
        """

        import drjit as dr
        import mitsuba as mi

        lanes = rays.lanes
        holder = self.holders[0]
        axis, _, centre = self.planes[0]
        start, wo_world = self._leaving_specimen(lanes, centre)
        left = self.entering(lanes)
        into = dr.dot(wo_world, _vec(axis)) < 0.0
        fate = self._first_fate(lanes, dr.select(
            left, dr.select(into, mi.UInt32(_ACTIVE), mi.UInt32(SphereFate.lost(holder.port))),
            mi.UInt32(int(SphereFate.HOLDER0))))
        rare, hemisphere = self._first_rare_and_hemisphere(lanes)
        slot = rays.slot
        dr.eval(start, wo_world, fate, rare, hemisphere, *(() if slot is None else (slot,)))  # one kernel
        walking = dr.compress(fate == _ACTIVE)  # the rays that entered the sphere
        walls = dr.zeros(mi.UInt32, dr.width(fate))
        carried = self.carried_starts(lanes)
        if dr.width(walking):
            fate, rare, walls = self._loop(walking, start, wo_world, fate, rare, rays, carried)
        return hemisphere * self.codes + fate, {**self._walk_sums(walls, rare), **self.carried_sums(carried, rays)}

    # -- what every walk starts and ends with (the single, real and double spheres) ---------------

    def _leaving_specimen(self, lanes: dict, centre: Sequence[float]) -> tuple[Any, Any]:
        """Where the rays leave the specimen (holder 0, its port plane's ``centre``) and their direction, in the world."""

        import mitsuba as mi

        frame = self.holders[0].frame
        wo, target = lanes["wo"], lanes["target"]
        wo_world = mi.Vector3f(*(wo.x * frame[i, 0] + wo.y * frame[i, 1] + wo.z * frame[i, 2] for i in range(3)))
        start = mi.Point3f(*(centre[i] + target.x * frame[i, 0] + target.y * frame[i, 1] for i in range(3)))
        return start, wo_world

    @staticmethod
    def _first_fate(lanes: dict, fate: Any) -> Any:
        """``fate``, unless the first interaction was capped or gave an invalid direction."""

        import drjit as dr
        import mitsuba as mi

        first_fate = lanes["fate"]
        fate = dr.select(first_fate == int(Fate.CAPPED), mi.UInt32(int(SphereFate.CAPPED)), fate)
        return dr.select(first_fate == int(Fate.INVALID), mi.UInt32(int(SphereFate.INVALID)), fate)

    @staticmethod
    def _first_rare_and_hemisphere(lanes: dict) -> tuple[Any, Any]:
        """The first interaction's rare bits (weight violation, rounded weight) and its hemisphere code."""

        import drjit as dr
        import mitsuba as mi

        first_fate, first_rare = lanes["fate"], lanes["rare"]
        rare = dr.select((first_rare & 1) != 0, mi.UInt32(_VIOLATION), 0) | dr.select(
            (first_rare & 4) != 0, mi.UInt32(_ROUNDED), 0)
        hemisphere = dr.select(first_fate == int(Fate.REFLECTED),
                               dr.select(lanes["specular"], mi.UInt32(3), mi.UInt32(1)),
                               dr.select(first_fate == int(Fate.TRANSMITTED), mi.UInt32(2), mi.UInt32(0)))
        return rare, hemisphere

    @staticmethod
    def _walk_sums(walls: Any, rare: Any) -> dict[str, Any]:
        """Each ray's wall reflections, weight violation and rounded weight (0 or 1 each)."""

        import drjit as dr
        import mitsuba as mi

        return {"wall_reflections": walls,
                "weight_violations": dr.select((rare & _VIOLATION) != 0, mi.UInt32(1), mi.UInt32(0)),
                "rounded_weights": dr.select((rare & _ROUNDED) != 0, mi.UInt32(1), mi.UInt32(0))}

    def _holder_sampled(self, holder: Holder, bsdf: Any, q: Any, d: Any, lit: Any, u: list, wavelength: Any,
                        label: str = "sphere_holder") -> tuple[Any, Any, Any, Any]:
        """
        A holder disk's BSDF sampled at the rays that hit it (``lit``; packets without one
        skip it): their direction out (world), weight, and whether it is invalid or capped.
        """

        import drjit as dr
        import mitsuba as mi

        frame = mi.Frame3f(_vec(holder.frame[:, 0]), _vec(holder.frame[:, 1]), _vec(holder.frame[:, 2]))
        wo, w, component = dr.if_stmt(
            (q, d, lit, *u, wavelength), lit,
            lambda q_, d_, lit_, u0, u1, u2, u3, lam, bsdf=bsdf, frame=frame: self._sample(
                bsdf, frame, q_, -d_, lam, [u0, u1, u2, u3], lit_),
            lambda *_: (mi.Vector3f(0.0, 0.0, 1.0), mi.Float(0.0), mi.UInt32(0)),
            label=label)
        length2 = dr.squared_norm(wo)
        invalid = ~((length2 >= _LENGTH2[0]) & (length2 <= _LENGTH2[1])) & (w > 0.0)
        return frame.to_world(wo), w, invalid, component == CAPPED_COMPONENT

    @staticmethod
    def _holder_settled(lit: Any, code: Any, w: Any, invalid: Any, capped: Any, wo_world: Any, fate: Any,
                        rare: Any, new_d: Any) -> tuple[Any, Any, Any]:
        """
        The rays that hit a holder: their fate (``code``, unless invalid or capped), the
        rare bits of their weight (violation, rounding) and their new direction.
        """

        import drjit as dr
        import mitsuba as mi

        code = dr.select(invalid, mi.UInt32(int(SphereFate.INVALID)), code)
        code = dr.select(capped, mi.UInt32(int(SphereFate.CAPPED)), code)
        exact = (w >= 0.0) & (w <= 1.0)
        rounded = ~exact & (w >= -WEIGHT_ROUNDING) & (w <= 1.0 + WEIGHT_ROUNDING)
        rare = rare | dr.select(lit & ~exact & ~rounded & ~capped, mi.UInt32(_VIOLATION), 0) \
            | dr.select(lit & rounded, mi.UInt32(_ROUNDED), 0)
        return dr.select(lit, code, fate), rare, dr.select(lit, wo_world, new_d)

    def _loop(self, walking: Any, start: Any, direction: Any, fate: Any, rare: Any,
              rays: ChunkRays, carried: dict[str, Any] | None = None) -> tuple[Any, Any, Any]:
        """
        The one symbolic loop over the rays that entered the sphere (indices ``walking``):
        each of L lanes walks its rays one after the other (rays j, j + L, j + 2L … of
        ``walking``), :meth:`step` by step, and takes the next ray as soon as one ends — so
        a lane never idles behind a long walk of its packet. Per-ray fates, rare bits and
        wall reflections are written back at the rays' indices (the random numbers depend
        on the ray, not on the lane, so the counts do not depend on L). ``carried``: per-ray start values of
        the :attr:`carried` state, replaced by the values at the walks' ends (none in the plain walk).
        """

        import drjit as dr
        import mitsuba as mi

        count = dr.width(walking)
        width = count if count <= _MIN_LANES else max(_MIN_LANES, -(-count // _RAYS_PER_LANE))
        n = dr.opaque(mi.UInt32, count)
        stride = dr.opaque(mi.UInt32, width)
        fate_out, rare_out = dr.copy(fate), dr.copy(rare)  # written per ray below; fate, rare only read
        walls_out = dr.zeros(mi.UInt32, dr.width(fate))
        root = dr.opaque(mi.UInt32, rays.root)
        single = rays.slot is None
        rho_w = self.wall_reflectance(rays.wavelengths).astype(np.float32)
        wavelengths = rays.wavelengths.astype(np.float32)
        bsdfs = [_loaded(holder.bsdf, rays.specimen) for holder in self.holders]
        extras = [values.astype(np.float32) for values in self.extra_columns(rays.wavelengths)]
        carried = {} if carried is None else carried
        starts = [(name, carried[name]) for name in self.carried if name in carried]
        ends = {name: dr.copy(values) for name, values in starts}  # written per ray below; the starts only read

        def reading_of(ray: Any) -> Any:
            return dr.zeros(mi.UInt32, width) if single else dr.gather(mi.UInt32, rays.slot, ray)

        slot = dr.arange(mi.UInt32, width)
        ray = dr.gather(mi.UInt32, walking, slot)
        state = (slot, ray, reading_of(ray), dr.gather(mi.Point3f, start, ray), dr.gather(mi.Vector3f, direction, ray),
                 dr.full(mi.UInt32, self.start_last, width), dr.full(mi.UInt32, _ACTIVE, width),
                 dr.zeros(mi.UInt32, width),
                 dr.zeros(mi.UInt32, width), dr.gather(mi.UInt32, rare, ray),
                 *(dr.gather(mi.Float, values, ray) for _, values in starts))

        def body(slot, ray, reading, p, d, last, state_fate, bounces, walls, state_rare, *more_state):
            at = None if single else reading
            out = self.step({"p": p, "d": d, "last": last, "fate": state_fate, "bounces": bounces, "walls": walls,
                             "rare": state_rare, **{name: value for (name, _), value in zip(starts, more_state)}},
                            rays.ray_index(ray, at), root, rays.column(rho_w, mi.Float, at),
                            rays.column(wavelengths, mi.Float, at), bsdfs,
                            *[rays.column(values, mi.Float, at) for values in extras])
            done = out["fate"] != _ACTIVE
            dr.scatter(fate_out, out["fate"], ray, done)
            dr.scatter(rare_out, out["rare"], ray, done)
            dr.scatter(walls_out, out["walls"], ray, done)
            for name, _ in starts:
                dr.scatter(ends[name], out[name], ray, done)
            slot = dr.select(done, slot + stride, slot)
            more = done & (slot < n)
            ray = dr.select(more, dr.gather(mi.UInt32, walking, slot, more), ray)
            if not single:
                reading = dr.select(more, dr.gather(mi.UInt32, rays.slot, ray, more), reading)
            return (slot, ray, reading,
                    dr.select(more, dr.gather(mi.Point3f, start, ray, more), out["p"]),
                    dr.select(more, dr.gather(mi.Vector3f, direction, ray, more), out["d"]),
                    dr.select(more, mi.UInt32(self.start_last), out["last"]),
                    dr.select(more, mi.UInt32(_ACTIVE), out["fate"]),
                    dr.select(more, mi.UInt32(0), out["bounces"]),
                    dr.select(more, mi.UInt32(0), out["walls"]),
                    dr.select(more, dr.gather(mi.UInt32, rare, ray, more), out["rare"]),
                    *(dr.select(more, dr.gather(mi.Float, values, ray, more), out[name]) for name, values in starts))

        def steps(*variables):  # body, and one step more of this launch
            return (*body(*variables[:-1]), variables[-1] + 1)

        budget = dr.opaque(mi.UInt32, LAUNCH_STEPS)
        while True:  # launches of at most LAUNCH_STEPS steps per lane, a safe point between two
            *state, _ = dr.while_loop((*state, dr.zeros(mi.UInt32, width)),
                                      lambda slot, *rest: (slot < n) & (rest[-1] < budget), steps,
                                      label="sphere_walk")
            dr.eval(*state, fate_out, rare_out, walls_out, *ends.values())
            if not bool(dr.any(state[0] < n, axis=None)):
                break
            if rays.safe_point is not None:  # the engine's: an interrupt during a long walk stops the run here
                rays.safe_point()
        carried.update(ends)
        return fate_out, rare_out, walls_out

    # -- one step: state in → one flight and one surface event → state out --------------

    def step(self, state: dict, ray_index: Any, root: Any, rho_w: Any, wavelength: Any, bsdfs: list,
             *columns: Any) -> dict:
        """One bounce of every lane still walking (``state['fate'] == ACTIVE``); ``bsdfs``: the holders'
        (``columns``: :meth:`extra_columns` of the lanes' readings, none here)."""

        import drjit as dr
        import mitsuba as mi

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
        baffle = self.baffle
        if baffle is not None:
            centre, normal, radius = _vec(baffle[0]), _vec(baffle[1]), baffle[2]
            t_b = dr.dot(centre - p, normal) / dr.dot(d, normal)
            on_disk = dr.squared_norm(p + t_b * d - centre) <= radius * radius
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
            facing = dr.select(dr.dot(d, _vec(baffle[1])) > 0.0, -_vec(baffle[1]), _vec(baffle[1]))
            inward = dr.select(surface == 3, facing, inward)
        survives = u[0] < rho_w
        fate = dr.select(diffuse & ~survives, mi.UInt32(int(SphereFate.WALL)), fate)
        local = mi.warp.square_to_cosine_hemisphere(mi.Point2f(u[1], u[2]))
        new_d = dr.normalize(mi.Frame3f(inward).to_world(local))
        on_sphere = x * (self.radius / dr.norm(x))
        new_p = dr.select(surface == 0, on_sphere, x)
        walls = state["walls"] + dr.select(diffuse & survives, mi.UInt32(1), mi.UInt32(0))
        rare = state["rare"]

        # the holders: a flat disk in its port plane, sampled by its BSDF
        held = mi.Float(1.0)  # the BSDF weight of the disk hit (1: none), for a subclass (unused here: not traced)
        for k, holder in enumerate(self.holders):
            _, _, centre = self.planes[k]
            on_holder = active & (surface == k + 1)
            q = x - _vec(centre)
            in_disk = dr.squared_norm(q) <= holder.radius * holder.radius
            lost = mi.UInt32(SphereFate.lost(holder.port))
            fate = dr.select(on_holder & ~in_disk, lost, fate)
            lit = on_holder & in_disk
            wo_world, w, invalid, capped = self._holder_sampled(holder, bsdfs[k], q, d, lit, u, wavelength)
            lives = self._lives(u[3], w)
            held = dr.select(lit, w, held)
            into = dr.dot(wo_world, _vec(self.planes[k][0])) < 0.0
            code = dr.select(lives, dr.select(into, mi.UInt32(_ACTIVE), lost), mi.UInt32(int(SphereFate.HOLDER0) + k))
            fate, rare, new_d = self._holder_settled(lit, code, w, invalid, capped, wo_world, fate, rare, new_d)

        bounces = state["bounces"] + dr.select(active, mi.UInt32(1), mi.UInt32(0))
        fate = dr.select((fate == _ACTIVE) & (bounces >= self.max_bounces), mi.UInt32(int(SphereFate.CAPPED)), fate)
        return {"p": dr.select(active, new_p, p), "d": dr.select(active, new_d, d),
                "last": dr.select(active, surface, last), "fate": fate, "bounces": bounces, "walls": walls,
                "rare": rare, "held": held}

    @staticmethod
    def _lives(u: Any, weight: Any) -> Any:
        """Whether a ray the disk's BSDF sampled with ``weight`` lives on: Russian roulette (``u < weight``)."""

        return u < weight

    @staticmethod
    def _sample(bsdf: Any, frame: Any, q: Any, wi_world: Any, wavelength: Any, u: list,
                active: Any) -> tuple[Any, Any, Any]:
        """The disk BSDF's ``sample`` at the hit (local wi, point, uv, wavelength)."""

        import drjit as dr
        import mitsuba as mi

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
