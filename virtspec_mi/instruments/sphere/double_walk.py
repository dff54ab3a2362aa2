"""
The double-sphere walk: a specimen between a reflectance sphere and a transmittance sphere
==========================================================================================

:class:`DoubleSphereLayout` is :class:`~virtspec_mi.instruments.sphere.walk.SphereLayout`
for two spheres that share one specimen (IAD's double-sphere configuration, Pickering et
al. 1993): the **reflectance sphere** (sphere 0, its centre at the origin) holds the
specimen in its sample port, lit through its entrance port; the **transmittance sphere**
(sphere 1) is placed behind it, its entrance port's plane on the same plane, the two
port axes opposite. Both spheres are plain values in the reflectance sphere's
coordinates (the transmittance sphere moved there by a rigid motion:
:func:`virtspec_mi.instruments.sphere.double.double_layout`), so the layout is
picklable and imports nothing above the kernel, as the single sphere's.

A walking ray carries the sphere it is in (``last`` holds ``sphere << 8 | surface``).
One step is one flight and one surface event, as in the single sphere, with that
sphere's radius, centre, port caps, wall reflectance, holder planes and baffle:

- the **specimen** is one disk seen from both sides (two planes, one per sphere, the
  same BSDF and frame; its normal faces the reflectance sphere and the beam): a ray
  the BSDF sends towards the reflectance sphere's side walks on there, towards the
  other side in the transmittance sphere — the cross-talk through the specimen (light
  of one sphere that the specimen passes into the other) is walked, not modelled;
- a crossing of the specimen's plane **outside the disk** passes into the other sphere
  where the other port is open that far (the gap between a specimen smaller than its
  ports), else it is lost through the port;
- a sphere that is **absent** (the reflectance sphere's calibration has no
  transmittance sphere behind its standard; the transmittance sphere's 100 % reading
  has no reflectance sphere in front of its open port) makes every ray towards it lost
  through the port it leaves by.

Each sphere's detector has its own fate code: the reflectance sphere's is
:attr:`~virtspec_mi.instruments.sphere.walk.SphereFate.DETECTED`, the transmittance
sphere's ``LOST + j`` of its detector port j (the instrument names it). Random numbers,
the lanes and the launches are the single walk's (:meth:`SphereLayout._loop`), so the
counts are exact integers, bit-reproducible and independent of chunking.

References
----------
Pickering, Prahl, van Wieringen, Beek, Sterenborg & van Gemert (1993), *Double-
integrating-sphere system for measuring the optical properties of tissue*, Appl. Opt.
32(4), 399–410; S. A. Prahl, *Inverse Adding-Doubling* manual (the double-sphere
configuration); Goebel (1967).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from virtspec_mi.kernel.counts import Fate
from virtspec_mi.kernel.hooks import ChunkRays
from virtspec_mi.kernel.rng import GOLDEN, hash32, to_unit
from virtspec_mi.instruments.sphere.walk import _ACTIVE, WALK_BASE, SphereFate, SphereLayout, _vec

__all__ = ["START", "DoubleSphereLayout"]

START: int = 0xFFFF
"""``last`` of a walk's start on the specimen: the sphere is chosen by the direction there."""


@dataclass(frozen=True, eq=False)
class DoubleSphereLayout(SphereLayout):
    """
    Two spheres around one specimen as plain values (see the module docstring). The
    fields of :class:`~virtspec_mi.instruments.sphere.walk.SphereLayout` keep their
    meaning where one sphere has them (``radius``: the reflectance sphere's; ``ports``:
    both spheres' ports, the reflectance sphere's first; ``wall``: the reflectance
    sphere's ρw; ``baffle`` unused), and:

    Parameters
    ----------
    caps : tuple
        (sphere, axis, threshold, fate code): a port cap of ``sphere`` (wall points x with
        (x − centre)·axis ≥ threshold).
    planes : tuple
        (axis, offset, centre, sphere, holder, pair, pair_radius, port): a holder's plane
        x·axis = offset seen from ``sphere`` (axis pointing out of it), the holder's index,
        the plane of the same disk seen from the other sphere (−1: none), how far the
        other port is open (mm) and the port (index) a ray leaves this sphere by there.
    spheres : tuple
        Per sphere (centre (3 floats), radius, present).
    baffles : tuple
        (sphere, centre, unit normal, radius) of each baffle.
    specimen_axis : tuple
        The reflectance sphere's sample-port axis (pointing out of it, into the other sphere).
    entries : tuple
        The specimen's plane seen from sphere 0 and from sphere 1 (indices into ``planes``).
    transmittance_wall : tuple
        ρw of the transmittance sphere at every wavelength of ``wall``.
    """

    spheres: tuple = ()
    baffles: tuple = ()
    specimen_axis: tuple = (0.0, 0.0, -1.0)
    entries: tuple = (0, 1)
    transmittance_wall: tuple = ()

    start_last = START

    def extra_columns(self, wavelengths: np.ndarray) -> tuple:
        """The transmittance sphere's ρw at the readings' wavelengths."""

        grid = np.asarray(self.wall[0], dtype=np.float64)
        values = np.asarray(self.transmittance_wall, dtype=np.float64)
        index = np.minimum(np.searchsorted(grid, wavelengths), len(grid) - 1)
        return (values[index],)

    def _toward(self, into_reflectance: Any) -> Any:
        """The fate of a ray that leaves the specimen into sphere 0 (``into_reflectance``) or sphere 1."""

        import drjit as dr
        import mitsuba as mi

        codes = []
        for side in (0, 1):
            present = self.spheres[side][2]
            other = self.planes[self.entries[1 - side]]  # an absent side: lost through the port it leaves by
            codes.append(mi.UInt32(_ACTIVE) if present else mi.UInt32(SphereFate.lost(other[7])))
        return dr.select(into_reflectance, codes[0], codes[1])

    # -- the chunk: first interactions in, bin codes and sums out -------------------------

    def exits(self, rays: ChunkRays) -> tuple[Any, dict[str, Any]]:
        """As the single sphere's: a ray the specimen sends to either side walks that sphere (present)."""

        import drjit as dr
        import mitsuba as mi

        lanes = rays.lanes
        first_fate = lanes["fate"]
        start, wo_world = self._leaving_specimen(lanes, self.planes[self.entries[0]][2])
        left = (first_fate == int(Fate.REFLECTED)) | (first_fate == int(Fate.TRANSMITTED))
        fate = self._first_fate(lanes, dr.select(
            left, self._toward(dr.dot(wo_world, _vec(self.specimen_axis)) < 0.0), mi.UInt32(int(SphereFate.HOLDER0))))
        rare, hemisphere = self._first_rare_and_hemisphere(lanes)
        slot = rays.slot
        dr.eval(start, wo_world, fate, rare, hemisphere, *(() if slot is None else (slot,)))
        walking = dr.compress(fate == _ACTIVE)
        walls = dr.zeros(mi.UInt32, dr.width(fate))
        if dr.width(walking):
            fate, rare, walls = self._loop(walking, start, wo_world, fate, rare, rays)
        return hemisphere * self.codes + fate, self._walk_sums(walls, rare)

    # -- one step ---------------------------------------------------------------------------

    def step(self, state: dict, ray_index: Any, root: Any, rho_w: Any, wavelength: Any, bsdfs: list,
             *columns: Any) -> dict:
        """One flight and one surface event of every lane still walking, in the sphere it is in."""

        import drjit as dr
        import mitsuba as mi

        (rho_t,) = columns
        p, d, last = state["p"], state["d"], state["last"]
        active = state["fate"] == _ACTIVE
        started = last == START
        sphere = dr.select(started, dr.select(dr.dot(d, _vec(self.specimen_axis)) < 0.0, mi.UInt32(0), mi.UInt32(1)),
                           last >> 8)
        entry = dr.select(sphere == 0, mi.UInt32(self.entries[0] + 1), mi.UInt32(self.entries[1] + 1))
        previous = dr.select(started, entry, last & 0xFF)
        in_t = sphere == 1
        (c0, r0, _), (c1, r1, _) = self.spheres
        centre = dr.select(in_t, _vec(c1), _vec(c0))
        radius = dr.select(in_t, mi.Float(r1), mi.Float(r0))
        pc = p - centre
        b = dr.dot(pc, d)
        c = dr.squared_norm(pc) - radius * radius
        t = -b + dr.safe_sqrt(b * b - c)
        surface = mi.UInt32(0)
        for k, plane in enumerate(self.planes):
            axis, offset, own = _vec(plane[0]), plane[1], plane[3]
            cos_d = dr.dot(d, axis)
            t_k = (offset - dr.dot(p, axis)) / cos_d
            hit = (sphere == own) & (cos_d > 0.0) & (t_k > 0.0) & (t_k < t) & (previous != k + 1)
            t = dr.select(hit, t_k, t)
            surface = dr.select(hit, mi.UInt32(k + 1), surface)
        first_baffle = len(self.planes) + 1
        for j, (own, b_centre, b_normal, b_radius) in enumerate(self.baffles):
            bc, bn = _vec(b_centre), _vec(b_normal)
            t_b = dr.dot(bc - p, bn) / dr.dot(d, bn)
            on_disk = dr.squared_norm(p + t_b * d - bc) <= b_radius * b_radius
            hit = (sphere == own) & (previous != first_baffle + j) & (t_b > 0.0) & (t_b < t) & on_disk
            t = dr.select(hit, t_b, t)
            surface = dr.select(hit, mi.UInt32(first_baffle + j), surface)
        x = p + t * d

        keys = [hash32(root + (mi.UInt32(WALK_BASE + j) + 4 * state["bounces"]) * GOLDEN) for j in range(4)]
        u = [to_unit(hash32(ray_index ^ key), mi.Float) for key in keys]

        fate = state["fate"]
        on_wall = active & (surface == 0)
        for own, axis, threshold, action in self.caps:
            inside = (sphere == own) & (dr.dot(x - _vec(self.spheres[own][0]), _vec(axis)) >= threshold)
            fate = dr.select(on_wall & inside & (fate == _ACTIVE), mi.UInt32(action), fate)
        on_baffle = active & (surface >= first_baffle)
        diffuse = (on_wall & (fate == _ACTIVE)) | on_baffle
        xc = x - centre
        inward = -dr.normalize(xc)
        for j, (_, _, b_normal, _) in enumerate(self.baffles):
            bn = _vec(b_normal)
            inward = dr.select(surface == first_baffle + j, dr.select(dr.dot(d, bn) > 0.0, -bn, bn), inward)
        survives = u[0] < dr.select(in_t, rho_t, rho_w)
        fate = dr.select(diffuse & ~survives, mi.UInt32(int(SphereFate.WALL)), fate)
        local = mi.warp.square_to_cosine_hemisphere(mi.Point2f(u[1], u[2]))
        new_d = dr.normalize(mi.Frame3f(inward).to_world(local))
        new_p = dr.select(surface == 0, centre + xc * (radius / dr.norm(xc)), x)
        new_sphere, new_surface = sphere, surface
        walls = state["walls"] + dr.select(diffuse & survives, mi.UInt32(1), mi.UInt32(0))
        rare = state["rare"]

        # the holders: a disk seen from one plane (a standard) or two (the specimen, one per sphere)
        for h, holder in enumerate(self.holders):
            seen = [k for k, plane in enumerate(self.planes) if plane[4] == h]
            on_holder = mi.Bool(False)
            for k in seen:
                axis, _, p_centre, own, _, pair, pair_radius, port = self.planes[k]
                on_plane = active & (surface == k + 1)
                q2 = dr.squared_norm(x - _vec(p_centre))
                outside = on_plane & (q2 > holder.radius * holder.radius)
                lost = mi.UInt32(SphereFate.lost(port))
                if pair >= 0 and self.spheres[1 - own][2]:
                    passes = outside & (q2 <= pair_radius * pair_radius)
                    new_sphere = dr.select(passes, mi.UInt32(1 - own), new_sphere)
                    new_surface = dr.select(passes, mi.UInt32(pair + 1), new_surface)
                    fate = dr.select(outside & ~passes, lost, fate)
                else:
                    fate = dr.select(outside, lost, fate)
                on_holder = on_holder | on_plane
            p_centre = self.planes[seen[0]][2]
            q = x - _vec(p_centre)
            lit = on_holder & (dr.squared_norm(q) <= holder.radius * holder.radius)
            wo_world, w, invalid, capped = self._holder_sampled(holder, bsdfs[h], q, d, lit, u, wavelength,
                                                                "double_sphere_holder")
            lives = u[3] < w
            if len(seen) == 2:  # the specimen: on to the side it sends the ray to
                into_r = dr.dot(wo_world, _vec(self.specimen_axis)) < 0.0
                code = self._toward(into_r)
                new_sphere = dr.select(lit, dr.select(into_r, mi.UInt32(0), mi.UInt32(1)), new_sphere)
                new_surface = dr.select(lit, dr.select(into_r, mi.UInt32(self.entries[0] + 1),
                                                       mi.UInt32(self.entries[1] + 1)), new_surface)
            else:  # a standard: back into its sphere, or out through its port
                k = seen[0]
                into = dr.dot(wo_world, _vec(self.planes[k][0])) < 0.0
                code = dr.select(into, mi.UInt32(_ACTIVE), mi.UInt32(SphereFate.lost(self.planes[k][7])))
            code = dr.select(lives, code, mi.UInt32(int(SphereFate.HOLDER0) + min(h, 1)))
            fate, rare, new_d = self._holder_settled(lit, code, w, invalid, capped, wo_world, fate, rare, new_d)

        bounces = state["bounces"] + dr.select(active, mi.UInt32(1), mi.UInt32(0))
        fate = dr.select((fate == _ACTIVE) & (bounces >= self.max_bounces), mi.UInt32(int(SphereFate.CAPPED)), fate)
        new_last = (new_sphere << 8) | new_surface
        return {"p": dr.select(active, new_p, p), "d": dr.select(active, new_d, d),
                "last": dr.select(active, new_last, last), "fate": fate, "bounces": bounces, "walls": walls,
                "rare": rare}
