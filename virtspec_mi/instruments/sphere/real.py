"""
The walk of a real sphere: port walls, non-circular ports, a traced beam
========================================================================

:class:`RealSphereLayout` is :class:`~virtspec_mi.instruments.sphere.walk.SphereLayout`
with what :mod:`virtspec_mi.instruments.sphere.ports` and
:mod:`virtspec_mi.instruments.sphere.beam` add. A sphere with none of it is walked by
the plain layout (:meth:`~virtspec_mi.instruments.sphere.geometry.Sphere.layout` decides),
so its counts and its speed are today's; a real sphere pays for what it uses.

One step (:meth:`RealSphereLayout.step`) is still one flight and one surface event, the
flight now through up to three pieces of space:

1. a ray **inside a port's cylinder** (its last surface was that cylinder, or the disk
   at its outer end) flies to the cylinder's wall, to the outer end (moving outwards) or
   back through the rim plane into the sphere (moving inwards);
2. a ray **in the sphere** (or just back from a cylinder, from its rim-plane crossing)
   flies as in the plain walk: the wall, a knife-edge holder's plane, the baffle;
3. a wall hit inside the cap of a **deep port** is not a surface (the cap is the hole):
   the ray entered the cylinder where it crossed the rim plane and flies on in it, to
   the cylinder's wall or its outer end.

Events: the sphere wall, the baffle and a knife-edge holder as in the plain walk; a
**cylinder wall** absorbs with probability 1 − ρe(λ) and re-emits Lambertian about its
inward normal (counted with the wall reflections; absorbed: fate ``absorbed_wall``);
a deep port's **outer end** takes the port's fate (detected, lost) or is its holder's
disk (in the disk: its BSDF; outside: lost through the port). A wall hit in a
**non-circular** knife-edge port (its projection onto the port's tangent plane inside
the ellipse or rectangle) takes that port's fate.

A **traced beam**: every ray starts on its beam line inside the sphere
(:mod:`~virtspec_mi.instruments.sphere.beam`, random dimensions ``BEAM_BASE + j``, between
the first interaction's and the walk's), and the walk's first step finds what the beam
meets; a ray whose first event is not holder 0's disk is **beam spill** (rare bit
:data:`SPILL`, summed per reading as ``beam_spill``).

References
----------
Goebel (1967); Prokhorov, Mekhontsev & Hanssen (2003), Appl. Opt. 42(19), 3832 (Monte
Carlo of sphere geometry errors: port edges, beam size).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

from virtspec_mi.kernel.counts import WEIGHT_ROUNDING
from virtspec_mi.kernel.hooks import ChunkRays
from virtspec_mi.kernel.rng import GOLDEN, hash32, to_unit
from virtspec_mi.kernel.walk import CAPPED_COMPONENT
from virtspec_mi.instruments.sphere.walk import (_ACTIVE, _LENGTH2, _ROUNDED, _VIOLATION, WALK_BASE, SphereFate,
                                                 SphereLayout, _loaded, _vec)

__all__ = ["BEAM_BASE", "SPILL", "TUBE", "END", "POST", "RealSphereLayout", "real_layout", "check_traced_beam", "port_frame"]

BEAM_BASE: int = WALK_BASE - 16
"""First random-number dimension of a traced beam ray (4 of them), below the walk's."""

SPILL: int = 16
"""Rare bit of a traced beam ray whose first event is not the specimen's disk."""

TUBE: int = 16
"""``last`` code of a ray in port cylinder i (its wall, or its outer disk): ``TUBE + i``."""

END: int = 48
"""Surface code of the outer end of cylinder i of a port without a holder: ``END + i``."""

POST: int = 80
"""Surface code of the side of holder k's post (a disk standing proud of its port): ``POST + k``."""


def port_frame(axis: Any) -> tuple[np.ndarray, np.ndarray]:
    """
    (e₁, e₂) of a port's tangent plane: e₁ is the sphere's +x projected onto it (+y when
    the axis is within 25° of ±x), e₂ = c × e₁ (:mod:`virtspec_mi.instruments.sphere.ports`).
    """

    c = np.asarray(axis, dtype=np.float64)
    e = np.array([1.0, 0.0, 0.0]) if abs(c[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    e1 = e - (e @ c) * c
    e1 /= np.linalg.norm(e1)
    return e1, np.cross(c, e1)


def _cylinder_exit(p: Any, d: Any, axis: Any, radius: float) -> Any:
    """Distance along ``d`` from ``p`` (inside the infinite cylinder) to its wall (∞ along the axis)."""

    import drjit as dr
    import mitsuba as mi

    q = p - dr.dot(p, axis) * axis
    w = d - dr.dot(d, axis) * axis
    a = dr.squared_norm(w)
    b = dr.dot(q, w)
    c = dr.squared_norm(q) - radius * radius
    t = (-b + dr.safe_sqrt(b * b - a * c)) / a
    return dr.select(a > 1e-12, t, mi.Float(dr.inf))


@dataclass(frozen=True, eq=False)
class RealSphereLayout(SphereLayout):
    """
    A sphere layout with port cylinders, non-circular ports and a traced beam (see the
    module docstring). Parameters beyond :class:`SphereLayout`'s:

    Parameters
    ----------
    tubes : tuple
        Per deep port: (port index, axis, rim offset R cos α, depth, radius, fate code of
        its outer end or −1, holder index at its outer end or −1).
    edges : tuple
        Per tube: ρe at each of :attr:`wall`'s wavelengths.
    shaped : tuple
        Per non-circular knife-edge port with a fate: (axis, e₁, e₂, kind 0 ellipse / 1
        rectangle, a, b, fate code).
    beam : tuple or None
        A traced beam: (kind 0 point / 1 ellipse / 2 rectangle, a, b, cos β), mm.
    masks : tuple
        Per holder: ``None``, or its mask (aperture, port radius, ρm at each of
        :attr:`wall`'s wavelengths).
    fovs : tuple
        Per entry of :attr:`caps` (or empty): ``None``, or a detector's field of view
        (cos γ, the fate code of a ray outside it); a shaped port and a tube carry theirs
        as their last element.
    wall_specular : float
        The mirror share s of the wall's (and the baffle's) reflection (0: Lambertian).
    wall_bsdf : dict or None
        A Mitsuba BSDF plugin dict sampled at each wall and baffle event (instead of ρw and
        the Lambertian).
    posts : tuple
        Per holder: ``None``, or the post of a disk standing proud of its port (rim
        offset R cos α, proud s, the post's radius, its ρ at each of :attr:`wall`'s
        wavelengths): the holder's plane is then R cos α − s and only its disk stops a ray.
    """

    tubes: tuple = ()
    edges: tuple = ()
    shaped: tuple = ()
    beam: tuple | None = None
    masks: tuple = ()
    fovs: tuple = ()
    wall_specular: float = 0.0
    posts: tuple = ()
    wall_bsdf: Any = None

    @property
    def sums(self) -> tuple[str, ...]:  # type: ignore[override]
        base = ("wall_reflections", "weight_violations", "rounded_weights")
        return base + (("beam_spill",) if self.beam is not None else ())

    @property
    def start_last(self) -> int:  # type: ignore[override]
        """A traced beam starts in the sphere (0); a specimen in a deep port starts in its cylinder."""

        if self.beam is not None:
            return 0
        tube = self._holder_tube(0)
        return 1 if tube < 0 else TUBE + tube

    def _holder_tube(self, k: int) -> int:
        return next((i for i, tube in enumerate(self.tubes) if tube[6] == k), -1)

    @staticmethod
    def _seen(code: Any, d: Any, axis: Any, fov: tuple | None) -> Any:
        """A port's fate code, or its lost code for a ray outside the detector's field of view."""

        import drjit as dr
        import mitsuba as mi

        if fov is None:
            return code
        return dr.select(dr.dot(d, axis) >= fov[0], code, mi.UInt32(fov[1]))

    def extra_columns(self, wavelengths: np.ndarray) -> tuple:
        """ρe of every tube at the readings' wavelengths."""

        grid = np.asarray(self.wall[0], dtype=np.float64)
        index = np.minimum(np.searchsorted(grid, wavelengths), len(grid) - 1)
        masks = tuple(mask[2] for mask in self.masks if mask is not None)
        posts = tuple(post[3] for post in self.posts if post is not None)
        return tuple(np.asarray(values, dtype=np.float64)[index] for values in (*self.edges, *masks, *posts))

    # -- the chunk: a traced beam starts every ray on its beam line -----------------------

    def exits(self, rays: ChunkRays) -> tuple[Any, dict[str, Any]]:
        if self.wall_bsdf is not None:
            _loaded(self.wall_bsdf, rays.specimen)  # loaded once, outside the walk's loop
        if self.beam is None:
            return super().exits(rays)
        import drjit as dr
        import mitsuba as mi

        lanes = rays.lanes
        holder = self.holders[0]
        axis, _, centre = self.planes[0]
        frame = holder.frame
        first_fate = lanes["fate"]
        wi = lanes["wi"]
        travel = -mi.Vector3f(*(wi.x * frame[i, 0] + wi.y * frame[i, 1] + wi.z * frame[i, 2] for i in range(3)))
        fx = _vec(frame[:, 0])
        u_axis = dr.normalize(fx - dr.dot(fx, travel) * travel)
        v_axis = dr.cross(travel, u_axis)
        count = dr.width(first_fate)
        index = rays.ray_index(dr.arange(mi.UInt32, count), rays.slot)
        root = dr.opaque(mi.UInt32, rays.root)
        u = [to_unit(hash32(index ^ hash32(root + mi.UInt32(BEAM_BASE + j) * GOLDEN)), mi.Float) for j in range(4)]
        kind, a, b, cos_beta = self.beam
        if kind == 1:
            r, phi = dr.sqrt(u[0]), dr.two_pi * u[1]
            su, sv = a * r * dr.cos(phi), b * r * dr.sin(phi)
        elif kind == 2:
            su, sv = a * (2.0 * u[0] - 1.0), b * (2.0 * u[1] - 1.0)
        else:
            su, sv = mi.Float(0.0), mi.Float(0.0)
        cos_t = 1.0 - u[2] * (1.0 - cos_beta)
        sin_t = dr.safe_sqrt(1.0 - cos_t * cos_t)
        phi = dr.two_pi * u[3]
        direction = dr.normalize(cos_t * travel + sin_t * (dr.cos(phi) * u_axis + dr.sin(phi) * v_axis))
        point = _vec(centre) + su * u_axis + sv * v_axis
        start = mi.Point3f(point - (dr.dot(point, _vec(axis)) / dr.dot(direction, _vec(axis))) * direction)
        direction = mi.Vector3f(direction)
        fate = dr.full(mi.UInt32, _ACTIVE, count)
        rare, hemisphere = self._first_rare_and_hemisphere(lanes)
        slot = rays.slot
        dr.eval(start, direction, fate, rare, hemisphere, *(() if slot is None else (slot,)))
        fate, rare, walls = self._loop(dr.arange(mi.UInt32, count), start, direction, fate, rare, rays)
        return hemisphere * self.codes + fate, {
            **self._walk_sums(walls, rare), "beam_spill": dr.select((rare & SPILL) != 0, mi.UInt32(1), mi.UInt32(0))}

    # -- one step ---------------------------------------------------------------------------

    def step(self, state: dict, ray_index: Any, root: Any, rho_w: Any, wavelength: Any, bsdfs: list,
             *columns: Any) -> dict:
        """One bounce of every lane still walking, through cylinders, sphere and cylinders (module docstring)."""

        import drjit as dr
        import mitsuba as mi

        p, d, last = state["p"], state["d"], state["last"]
        active = state["fate"] == _ACTIVE
        inf = mi.Float(dr.inf)
        deep_holders = {tube[6] for tube in self.tubes if tube[6] >= 0}

        # 1. rays in a cylinder: its wall, its outer end, or back into the sphere
        surface = mi.UInt32(0)
        x = mi.Point3f(p)
        resolved = mi.Bool(False)
        body_p = mi.Point3f(p)
        body_last = mi.UInt32(last)
        for i, (_, axis, offset, depth, radius, _, holder, _) in enumerate(self.tubes):
            c = _vec(axis)
            inside = active & (last == TUBE + i)
            dc = dr.dot(d, c)
            pc = dr.dot(p, c)
            t_wall = _cylinder_exit(p, d, c, radius)
            t_end = (offset + depth - pc) / dc
            t_rim = (offset - pc) / dc
            to_end = inside & (dc > 0.0) & (t_end <= t_wall)
            to_rim = inside & (dc < 0.0) & (t_rim < t_wall)
            to_wall = inside & ~to_end & ~to_rim
            end_code = mi.UInt32(holder + 1 if holder >= 0 else END + i)
            surface = dr.select(to_end, end_code, dr.select(to_wall, mi.UInt32(TUBE + i), surface))
            x = dr.select(to_end, p + t_end * d, dr.select(to_wall, p + t_wall * d, x))
            resolved = resolved | to_end | to_wall
            body_p = dr.select(to_rim, p + t_rim * d, body_p)
            body_last = dr.select(to_rim, mi.UInt32(0), body_last)

        # 2. the sphere: the wall, knife-edge holders' planes, the baffle
        b = dr.dot(body_p, d)
        c2 = dr.squared_norm(body_p) - self.radius * self.radius
        t = -b + dr.safe_sqrt(b * b - c2)
        body_surface = mi.UInt32(0)
        for k, (axis, offset, centre) in enumerate(self.planes):
            if k in deep_holders:
                continue
            cos_d = dr.dot(d, _vec(axis))
            t_k = (offset - dr.dot(body_p, _vec(axis))) / cos_d
            hit = (cos_d > 0.0) & (t_k > 0.0) & (t_k < t) & (body_last != k + 1)
            post = self.posts[k] if self.posts else None
            if post is not None:  # a disk standing proud: only the disk stops a ray, and the post's side
                radius = self.holders[k].radius
                hit = hit & (dr.squared_norm(body_p + t_k * d - _vec(centre)) <= radius * radius)
                c = _vec(axis)
                q = body_p - dr.dot(body_p, c) * c
                w = d - dr.dot(d, c) * c
                a_, b_ = dr.squared_norm(w), dr.dot(q, w)
                disc = b_ * b_ - a_ * (dr.squared_norm(q) - radius * radius)
                t_s = (-b_ - dr.safe_sqrt(disc)) / a_
                along = dr.dot(body_p + t_s * d, c)
                side = (a_ > 1e-12) & (b_ < 0.0) & (disc >= 0.0) & (t_s > 0.0) & (t_s < t) & (
                    along >= post[0] - post[1]) & (along <= post[0]) & (body_last != POST + k)
                t = dr.select(side, t_s, t)
                body_surface = dr.select(side, mi.UInt32(POST + k), body_surface)
                hit = hit & (t_k < t)
            t = dr.select(hit, t_k, t)
            body_surface = dr.select(hit, mi.UInt32(k + 1), body_surface)
        baffle = self.baffle
        if baffle is not None:
            centre, normal, radius = _vec(baffle[0]), _vec(baffle[1]), baffle[2]
            t_b = dr.dot(centre - body_p, normal) / dr.dot(d, normal)
            on_disk = dr.squared_norm(body_p + t_b * d - centre) <= radius * radius
            hit = (body_last != 3) & (t_b > 0.0) & (t_b < t) & on_disk
            t = dr.select(hit, t_b, t)
            body_surface = dr.select(hit, mi.UInt32(3), body_surface)
        body_x = body_p + t * d

        # 3. a wall hit in a deep port's cap: into its cylinder at the rim plane, on to its wall or outer end
        for i, (_, axis, offset, depth, radius, _, holder, _) in enumerate(self.tubes):
            c = _vec(axis)
            enters = ~resolved & (body_surface == 0) & (dr.dot(body_x, c) >= offset)
            dc = dr.dot(d, c)
            rim = body_p + ((offset - dr.dot(body_p, c)) / dc) * d
            t_wall = _cylinder_exit(rim, d, c, radius)
            t_end = (offset + depth - dr.dot(rim, c)) / dc
            to_end = t_end <= t_wall
            end_code = mi.UInt32(holder + 1 if holder >= 0 else END + i)
            body_surface = dr.select(enters, dr.select(to_end, end_code, mi.UInt32(TUBE + i)), body_surface)
            body_x = dr.select(enters, rim + dr.select(to_end, t_end, t_wall) * d, body_x)
        surface = dr.select(resolved, surface, body_surface)
        x = dr.select(resolved, x, body_x)
        del inf

        keys = [hash32(root + (mi.UInt32(WALK_BASE + j) + 4 * state["bounces"]) * GOLDEN) for j in range(4)]
        u = [to_unit(hash32(ray_index ^ key), mi.Float) for key in keys]

        fate = state["fate"]
        on_wall = active & (surface == 0)
        for n, (axis, threshold, action) in enumerate(self.caps):
            inside = dr.dot(x, _vec(axis)) >= threshold
            code = self._seen(mi.UInt32(action), d, _vec(axis), self.fovs[n] if self.fovs else None)
            fate = dr.select(on_wall & inside & (fate == _ACTIVE), code, fate)
        for axis, e1, e2, kind, a, b_, action, fov in self.shaped:
            px, py = dr.dot(x, _vec(e1)) / a, dr.dot(x, _vec(e2)) / b_
            inside = (dr.dot(x, _vec(axis)) > 0.0) & (
                (px * px + py * py <= 1.0) if kind == 0 else ((dr.abs(px) <= 1.0) & (dr.abs(py) <= 1.0)))
            code = self._seen(mi.UInt32(action), d, _vec(axis), fov)
            fate = dr.select(on_wall & inside & (fate == _ACTIVE), code, fate)
        on_tube = active & (surface >= TUBE) & (surface < TUBE + len(self.tubes))
        on_post = active & (surface >= POST) & (surface < POST + len(self.holders))
        diffuse = (on_wall & (fate == _ACTIVE)) | (active & (surface == 3)) | on_tube | on_post
        inward = -dr.normalize(x)
        rho = mi.Float(rho_w)
        on_cylinder = mi.Point3f(x)
        for i, (_, axis, offset, depth, radius, action, holder, fov) in enumerate(self.tubes):
            c = _vec(axis)
            here = surface == TUBE + i
            q = x - dr.dot(x, c) * c
            inward = dr.select(here, -dr.normalize(q), inward)
            rho = dr.select(here, columns[i], rho)
            on_cylinder = dr.select(here, dr.dot(x, c) * c + q * (radius / dr.norm(q)), on_cylinder)
            if holder < 0:  # the outer end: the port's fate
                fate = dr.select(active & (surface == END + i), self._seen(mi.UInt32(action), d, c, fov), fate)
        column = len(self.tubes) + sum(mask is not None for mask in self.masks)
        for k, post in enumerate(self.posts):
            if post is None:
                continue
            c = _vec(self.planes[k][0])
            here = surface == POST + k
            q = x - dr.dot(x, c) * c
            inward = dr.select(here, dr.normalize(q), inward)  # the post's side faces away from its axis
            rho = dr.select(here, columns[column], rho)
            on_cylinder = dr.select(here, dr.dot(x, c) * c + q * (self.holders[k].radius / dr.norm(q)), on_cylinder)
            column += 1
        if baffle is not None:
            facing = dr.select(dr.dot(d, _vec(baffle[1])) > 0.0, -_vec(baffle[1]), _vec(baffle[1]))
            inward = dr.select(surface == 3, facing, inward)
        survives = u[0] < rho
        local = mi.warp.square_to_cosine_hemisphere(mi.Point2f(u[1], u[2]))
        new_d = dr.normalize(mi.Frame3f(inward).to_world(local))
        rare = state["rare"]
        if self.wall_bsdf is not None:  # the wall's (and baffle's) own BSDF, sampled about the inward normal
            coated = diffuse & ~on_tube & ~on_post
            wo, w, component = dr.if_stmt(
                (x, d, inward, coated, *u, wavelength), coated,
                lambda x_, d_, n_, c_, u0, u1, u2, u3, lam, bsdf=_loaded(self.wall_bsdf, None): self._sample(
                    bsdf, mi.Frame3f(n_), x_, -d_, lam, [u0, u1, u2, u3], c_),
                lambda *_: (mi.Vector3f(0.0, 0.0, 1.0), mi.Float(0.0), mi.UInt32(0)),
                label="sphere_wall")
            length2 = dr.squared_norm(wo)
            invalid = coated & ~((length2 >= _LENGTH2[0]) & (length2 <= _LENGTH2[1])) & (w > 0.0)
            survives = dr.select(coated, (u[3] < w) & (wo.z > 0.0), survives)
            new_d = dr.select(coated, dr.normalize(mi.Frame3f(inward).to_world(wo)), new_d)
            exact = (w >= 0.0) & (w <= 1.0)
            rounded = ~exact & (w >= -WEIGHT_ROUNDING) & (w <= 1.0 + WEIGHT_ROUNDING)
            rare = rare | dr.select(coated & ~exact & ~rounded, mi.UInt32(_VIOLATION), 0) \
                | dr.select(coated & rounded, mi.UInt32(_ROUNDED), 0)
            fate = dr.select(invalid, mi.UInt32(int(SphereFate.INVALID)), fate)
            fate = dr.select(coated & (component == CAPPED_COMPONENT), mi.UInt32(int(SphereFate.CAPPED)), fate)
            survives = survives & ~invalid
        fate = dr.select(diffuse & ~survives & (fate == _ACTIVE), mi.UInt32(int(SphereFate.WALL)), fate)
        if self.wall_specular > 0.0:  # the wall's (and baffle's) mirror share: u[3] is free at a wall event
            mirror = diffuse & ~on_tube & ~on_post & (u[3] < self.wall_specular)
            new_d = dr.select(mirror, dr.normalize(d - 2.0 * dr.dot(d, inward) * inward), new_d)
        on_sphere = x * (self.radius / dr.norm(x))
        new_p = dr.select(surface == 0, on_sphere, dr.select(on_tube | on_post, on_cylinder, x))
        walls = state["walls"] + dr.select(diffuse & survives, mi.UInt32(1), mi.UInt32(0))
        next_last = surface

        mask_column = len(self.tubes)
        for k, holder in enumerate(self.holders):
            _, _, centre = self.planes[k]
            on_holder = active & (surface == k + 1)
            q = x - _vec(centre)
            in_disk = dr.squared_norm(q) <= holder.radius * holder.radius
            lost = mi.UInt32(SphereFate.lost(holder.port))
            mask = self.masks[k] if self.masks else None
            on_mask = mi.Bool(False)
            if mask is not None:  # the clip's annulus: Lambertian, rho_m, facing the sphere
                aperture, port_radius, _ = mask
                on_mask = on_holder & (dr.squared_norm(q) >= aperture * aperture) & (
                    dr.squared_norm(q) <= port_radius * port_radius)
                in_disk = in_disk & ~on_mask
                kept = u[0] < columns[mask_column]
                mask_column += 1
                fate = dr.select(on_mask & ~kept, mi.UInt32(int(SphereFate.WALL)), fate)
                walls = walls + dr.select(on_mask & kept, mi.UInt32(1), mi.UInt32(0))
                new_d = dr.select(on_mask, dr.normalize(mi.Frame3f(-_vec(self.planes[k][0])).to_world(local)), new_d)
            fate = dr.select(on_holder & ~in_disk & ~on_mask, lost, fate)
            lit = on_holder & in_disk
            if k == 0 and self.beam is not None:
                rare = rare | dr.select(active & (state["bounces"] == 0) & ~lit, mi.UInt32(SPILL), 0)
            wo_world, w, invalid, capped = self._holder_sampled(holder, bsdfs[k], q, d, lit, u, wavelength)
            lives = u[3] < w
            into = dr.dot(wo_world, _vec(self.planes[k][0])) < 0.0
            code = dr.select(lives, dr.select(into, mi.UInt32(_ACTIVE), lost), mi.UInt32(int(SphereFate.HOLDER0) + k))
            fate, rare, new_d = self._holder_settled(lit, code, w, invalid, capped, wo_world, fate, rare, new_d)
            tube = self._holder_tube(k)
            if tube >= 0:  # back from a recessed disk: into its cylinder
                next_last = dr.select(on_holder, mi.UInt32(TUBE + tube), next_last)

        bounces = state["bounces"] + dr.select(active, mi.UInt32(1), mi.UInt32(0))
        fate = dr.select((fate == _ACTIVE) & (bounces >= self.max_bounces), mi.UInt32(int(SphereFate.CAPPED)), fate)
        return {"p": dr.select(active, new_p, p), "d": dr.select(active, new_d, d),
                "last": dr.select(active, next_last, last), "fate": fate, "bounces": bounces, "walls": walls,
                "rare": rare}


def real_layout(sphere: Any, holders: Sequence[Any], caps: Sequence[int | None], max_bounces: int,
                grid: np.ndarray) -> RealSphereLayout:
    """The :class:`RealSphereLayout` of a sphere with deep or non-circular ports or a beam profile (plain values)."""

    radius = sphere.radius
    rho_w = sphere.wall_reflectance_at(grid)
    holder_of = {h.port: k for k, h in enumerate(holders)}
    circles, shaped, tubes, edges, fovs = [], [], [], [], []
    for j, (port, action) in enumerate(zip(sphere.ports, caps)):
        axis = tuple(float(v) for v in port.axis)
        offset = radius * port.cos_half_angle(radius)
        fov = None if port.field_of_view is None or action is None else (
            math.cos(math.radians(port.field_of_view)), SphereFate.lost(j))
        if port.shape != "circle":
            if j in holder_of:
                raise ValueError(f"port {port.name!r}: shape {port.shape} cannot hold a specimen or a standard (its "
                                 "rim is not planar): give it shape circle, or measure so that it holds none")
            if action is not None:
                e1, e2 = port_frame(port.axis)
                shaped.append((axis, tuple(float(v) for v in e1), tuple(float(v) for v in e2),
                               0 if port.shape == "ellipse" else 1, port.width / 2.0, port.height / 2.0, int(action),
                               fov))
            continue
        if port.depth > 0.0 and (action is not None or j in holder_of):
            holder = holder_of.get(j, -1)
            tubes.append((j, axis, offset, port.depth, port.radius, -1 if holder >= 0 else int(action), holder, fov))
            edge = rho_w if port.edge_reflectance is None else np.full(grid.shape, port.edge_reflectance)
            edges.append(tuple(float(v) for v in edge))
        elif action is not None:
            circles.append((axis, offset, int(action)))
            fovs.append(fov)
    deep = {tube[6]: tube for tube in tubes if tube[6] >= 0}

    def plane(k: int, holder: Any) -> tuple:
        port = sphere.ports[holder.port]
        offset = radius * port.cos_half_angle(radius) + (port.depth if k in deep else 0.0) - port.proud
        return (tuple(float(v) for v in port.axis), offset, tuple(float(v) * offset for v in port.axis))

    profile = sphere.beam_profile
    beam = None
    if profile is not None:
        a, b = profile.half_sizes()
        beam = (BEAM_SHAPES_CODE[profile.shape], a, b, math.cos(math.radians(profile.divergence)))
    posts = []
    for holder in holders:
        port = sphere.ports[holder.port]
        values = rho_w if port.edge_reflectance is None else np.full(grid.shape, port.edge_reflectance)
        posts.append(None if not port.proud else (radius * port.cos_half_angle(radius), port.proud,
                                                  float(holder.radius), tuple(float(v) for v in values)))
    masks = []
    for holder in holders:
        port = sphere.ports[holder.port]
        if port.aperture is None:
            masks.append(None)
            continue
        values = rho_w if port.mask_reflectance is None else np.full(grid.shape, port.mask_reflectance)
        masks.append((port.aperture, port.radius, tuple(float(v) for v in values)))
    return RealSphereLayout(
        radius=radius, ports=len(sphere.ports), caps=tuple(circles),
        planes=tuple(plane(k, h) for k, h in enumerate(holders)), holders=tuple(holders),
        baffle=None if sphere.baffle is None else (sphere.baffle.centre, sphere.baffle.normal, sphere.baffle.radius),
        max_bounces=int(max_bounces), wall=(tuple(float(w) for w in grid), tuple(float(r) for r in rho_w)),
        tubes=tuple(tubes), edges=tuple(edges), shaped=tuple(shaped), beam=beam,
        masks=tuple(masks) if any(m is not None for m in masks) else (),
        fovs=tuple(fovs) if any(f is not None for f in fovs) else (), wall_specular=float(sphere.wall_specular),
        wall_bsdf=sphere.wall_bsdf,
        posts=tuple(posts) if any(p is not None for p in posts) else ())


BEAM_SHAPES_CODE: dict[str, int] = {"point": 0, "ellipse": 1, "rectangle": 2}


def check_traced_beam(sphere: Any, measurement: str, beam: str, local: np.ndarray, frame: np.ndarray) -> None:
    """
    A traced beam (a sphere with a beam profile) must be a collimated reflectance beam
    whose every line starts inside the sphere: checked on the cross-section's edge and
    the cone's rim (``local``: the incident direction in the specimen frame, towards the
    source; ``frame``: the specimen disk's frame in the sample port).
    """

    profile = sphere.beam_profile
    if profile is None:
        return
    if measurement != "reflectance":
        raise ValueError("beam_profile is for reflectance readings (a transmittance specimen is lit from outside the "
                         "sphere); remove it for a transmittance reading")
    if beam != "collimated":
        raise ValueError(f"beam_profile traces a collimated beam: give beam='collimated' (got {beam!r})")
    port = sphere.port("sample")
    axis = port.axis
    offset = sphere.radius * port.cos_half_angle(sphere.radius) + port.depth - port.proud
    centre = axis * offset
    travel = -(frame @ local)
    u = frame[:, 0] - (frame[:, 0] @ travel) * travel
    u /= np.linalg.norm(u)
    v = np.cross(travel, u)
    a, b = profile.half_sizes()
    beta = math.radians(profile.divergence)
    worst = 0.0
    for phi in np.linspace(0.0, 2.0 * math.pi, 64, endpoint=False):
        edge = (a * math.cos(phi), b * math.sin(phi)) if profile.shape != "rectangle" else (
            a * np.sign(math.cos(phi)), b * np.sign(math.sin(phi)))
        for psi in np.linspace(0.0, 2.0 * math.pi, 16, endpoint=False):
            direction = math.cos(beta) * travel + math.sin(beta) * (math.cos(psi) * u + math.sin(psi) * v)
            along = direction @ axis
            if not along > 0.05:
                raise ValueError(f"beam_profile: theta_i plus the divergence ({profile.divergence:g} deg) turn beam "
                                 "rays away from the sample port; reduce the divergence")
            point = centre + edge[0] * u + edge[1] * v
            start = point - (point @ axis / along) * direction
            worst = max(worst, float(np.linalg.norm(start)))
    if not worst < sphere.radius:
        raise ValueError(f"beam_profile: the beam is too wide for the sphere (a ray's line starts {worst:.3g} mm "
                         f"from the centre, the radius is {sphere.radius:g} mm); reduce width, height or divergence")
