"""
The expected-value detector: each bounce scores its chance of reaching the detector
===================================================================================

:class:`ExpectedSphereLayout` walks the sphere as
:class:`~virtspec_mi.instruments.sphere.walk.SphereLayout` does (same flights, holders,
baffle and port caps, same first interaction with the specimen) but scores detection by its
**expected value** (next-event estimation; Prokhorov, Mekhontsev & Hanssen 2003 score every
diffuse bounce of their sphere Monte Carlo alike). Each ray carries a weight w and a score s
(0 at the start):

- **the start**: w is the first interaction's BSDF weight (at most 1), and a ray the
  specimen's roulette absorbed walks too (its sampled direction, its weight): the roulette
  is replaced by its expectation. The first interaction itself — and so the hemispherical
  counts of the same rays — is the counting route's, ray for ray;
- **absorption**: the wall and the baffle multiply w by ρw(λ), a disk (specimen, standard)
  by its BSDF sample's weight, in place of the roulette;
- **a wall re-emission** at x: the Lambertian emission from a point of a sphere's wall lands
  uniformly over the sphere's surface (its irradiance is uniform: the sphere's defining
  property; Goebel 1967), so its next flight ends in the detector's cap with probability
  exactly f_d = A_cap/(4πR²) = (1 − cos α)/2 — unless the baffle lies in between. A point y
  drawn uniformly on the cap stands for that flight: when x sees y past the baffle,
  s += w·f_d, w ← w·(1 − f_d), and the ray flies to a point z drawn uniformly on the sphere
  *outside* the detector's cap (the emission conditioned on missing the detector); when the
  baffle hides y, w is kept and the ray flies to y (into the baffle) with probability f_d,
  else to z;
- **a baffle re-emission** at b: K = :data:`BAFFLE_SPLIT` Lambertian directions (the plain
  walk's and K − 1 more), h of which reach the detector's cap (nothing lies between: the
  baffle clears every holder's plane, and a chord between two points outside a port's
  segment stays outside it): s += w·h/K, w ← w·(K − h)/K, and the ray flies along one of
  the K − h that miss, drawn uniformly;
- **a flight that ends in the detector's cap** (from a disk: the specimen's emission is not
  a sphere wall's) adds w to s and ends the walk;
- **Russian roulette**: a weight below θ(1 − s) (θ = :data:`ROULETTE`) lives on as θ(1 − s)
  with probability w/(θ(1 − s)), else the walk ends on the wall; a weight below
  :data:`SMALLEST_WEIGHT` ends it.

**The score's mean is the detection probability.** Each rule keeps the expected detected
weight: a roulette or a weight in its place have the same expectation; at a wall point the
split gives w·f_d·σ now (σ: the share of the cap seen past the baffle) and the rest of the
emission's outcomes, each with its own probability, later (the flight to z stands for the
emission conditioned on missing the cap, the flight to a hidden y for its share
f_d·(1 − σ)); at the baffle the K directions are exchangeable, so the miss flown is a
Lambertian direction conditioned on missing, with the weight of the misses. The last rule
ends a walk that could still have scored less than its weight: the detector fraction lies
in [E s, E s + SMALLEST_WEIGHT].

**Every score lies in [0, 1].** s + w starts at most 1 and no rule raises it (a split moves
weight into the score; the roulette lifts w to at most 1 − s), so s ≤ 1: an interval for a
bounded mean certifies the detector fraction (:func:`virtspec_mi.budgets.scores.score_interval`).

**Exact sums.** A ray's score is rounded to a multiple of 1/S (S = :data:`SCORE_SCALE`)
stochastically, q = ⌊sS⌋ + [u < sS − ⌊sS⌋] (u: random dimension
:data:`ROUNDING_DIMENSION` of the ray), so q/S keeps the score's mean up to the uniform's
24-bit resolution (E q/S − E s ∈ [0, 2⁻²⁴/S), :data:`ROUNDING_BIAS`) and lies in [0, 1]; the
walk sums q and q² per reading (``detector_score``, ``detector_score_squares``) as exact
whole numbers, like every count. The score itself is computed in the walk's ``float32``
arithmetic, as its geometry is.

Only a sphere whose wall bounces' chance of detection is known exactly takes it
(:func:`expected_layout`): knife-edge circular ports, one detector port that counts every ray
reaching it (no field of view), a Lambertian wall (no mirror share, no wall BSDF), the
bench's pencil beam; a baffle is allowed. Any other sphere is refused with the feature named.

Random numbers: a step's four of the plain walk (``WALK_BASE + 4b + j``), which a wall event
leaves unused (ρw is a weight, the cosine direction is replaced), draw z (j = 1, 2) and y
(j = 0, 3); the roulette, the choice of y and the baffle's directions draw
``EXPECTED_BASE + _STRIDE·b + j``, apart from the walk's for every step cap allowed.

References
----------
Goebel (1967), Appl. Opt. 6(1), 125 (the sphere's uniform irradiance, the cap fraction);
Prokhorov, Mekhontsev & Hanssen (2003), Appl. Opt. 42(19), 3832 (next-event estimation in
sphere Monte Carlo); Maurer & Pontil (2009), COLT, Theorem 4 (the certificate).
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from typing import Any, Sequence

from virtspec_mi.kernel.counts import Fate
from virtspec_mi.kernel.hooks import ChunkRays
from virtspec_mi.kernel.rng import GOLDEN, hash32, to_unit
from virtspec_mi.instruments.sphere.walk import _ACTIVE, WALK_BASE, SphereFate, SphereLayout, _vec, holder_frame

__all__ = ["BAFFLE_SPLIT", "EXPECTED_BASE", "ROULETTE", "ROUNDING_BIAS", "ROUNDING_DIMENSION", "SCORE_SCALE",
           "SCORE_SUMS", "SMALLEST_WEIGHT", "ExpectedSphereLayout",
           "expected_layout"]

SCORE_SCALE: int = 1 << 15
"""S: a ray's score is summed as a whole number q in [0, S] (q² ≤ 2³⁰: the sums of 2³² rays fit in int64)."""

SCORE_SUMS: tuple[str, str] = ("detector_score", "detector_score_squares")
"""The per-reading sums of q and q² (:data:`SCORE_SCALE`) the expected-value walk adds to the counts."""

EXPECTED_BASE: int = 1 << 26
"""First random-number dimension of the expected-value walk's own draws (step b: ``EXPECTED_BASE + _STRIDE·b + j``)."""

ROUNDING_DIMENSION: int = WALK_BASE - 32
"""The random-number dimension of a ray's stochastic rounding of its score (below a traced beam's)."""

_UNIT_RESOLUTION: float = 2.0 ** -24
"""The resolution of :func:`~virtspec_mi.kernel.rng.to_unit`: the rounding's bias is below this over S."""

ROUNDING_BIAS: float = _UNIT_RESOLUTION / SCORE_SCALE
"""E q/S − E s lies in [0, ROUNDING_BIAS): taken off a score interval's lower end."""

ROULETTE: float = 0.1
"""θ: a walk whose weight w falls below θ(1 − s) (s its score) plays Russian roulette: it lives on with weight
θ(1 − s) with probability w/(θ(1 − s)), else ends on the wall (unbiased, and s + w stays ≤ 1)."""

BAFFLE_SPLIT: int = 8
"""K: a baffle re-emission scores the share of K Lambertian directions that reach the detector and flies on along
one of those that miss, with its weight times the share that miss (module docstring)."""

_STRIDE: int = 2 + 2 * BAFFLE_SPLIT
"""Random-number dimensions of the expected-value walk's own per step (``EXPECTED_BASE + _STRIDE·b + j``)."""

SMALLEST_WEIGHT: float = 2.0 ** -20
"""A walk ends (on the wall) when its weight falls below this: it could still have scored less than its weight,
so the detector fraction is at most SMALLEST_WEIGHT above the mean score (added to a score interval's upper end)."""


@dataclass(frozen=True, eq=False)
class ExpectedSphereLayout(SphereLayout):
    """
    A plain sphere layout scored by the expected-value detector (module docstring). Parameters
    beyond :class:`~virtspec_mi.instruments.sphere.walk.SphereLayout`'s:

    Parameters
    ----------
    detector : tuple
        (axis (3 floats), R cos α): the detector port's cap, x·c ≥ R cos α.
    detector_fraction : float
        f_d = (1 − cos α)/2, the cap's share of the sphere's surface.
    detector_frame : tuple
        (c, e₁, e₂): the detector's axis and two unit vectors normal to it and to each other.
    """

    detector: tuple = ((0.0, 0.0, 1.0), 0.0)
    detector_fraction: float = 0.0
    detector_frame: tuple = ((0.0, 0.0, 1.0), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0))

    carried = ("weight", "score")
    sums = ("wall_reflections", "weight_violations", "rounded_weights", *SCORE_SUMS)

    def entering(self, lanes: dict) -> Any:
        """The plain walk's, and the rays the specimen's roulette absorbed at their first interaction: their
        BSDF sample's weight is their walk's weight (:meth:`carried_starts`) in place of the roulette."""

        return super().entering(lanes) | ((lanes["fate"] == int(Fate.ABSORBED)) & (lanes["weight"] > 0.0))

    def carried_starts(self, lanes: dict) -> dict[str, Any]:
        """Weight: the first interaction's BSDF weight (at most 1); score: 0."""

        import drjit as dr
        import mitsuba as mi

        weight = dr.clip(mi.Float(lanes["weight"]), 0.0, 1.0)
        return {"weight": weight, "score": dr.zeros(mi.Float, dr.width(weight))}

    def carried_sums(self, carried: dict[str, Any], rays: ChunkRays) -> dict[str, Any]:
        """q and q² of every ray's score, q = ⌊sS⌋ + [u < sS − ⌊sS⌋] (stochastic rounding: module docstring)."""

        import drjit as dr
        import mitsuba as mi

        score = dr.clip(carried["score"], 0.0, 1.0)  # s + w ≤ 1 holds up to float32 rounding
        count = dr.width(score)
        index = rays.ray_index(dr.arange(mi.UInt32, count), rays.slot)
        root = dr.opaque(mi.UInt32, rays.root)
        u = to_unit(hash32(index ^ hash32(root + mi.UInt32(ROUNDING_DIMENSION) * GOLDEN)), mi.Float)
        scaled = score * float(SCORE_SCALE)  # exact: a power of two
        whole = dr.floor(scaled)
        q = mi.UInt32(whole) + dr.select(u < scaled - whole, mi.UInt32(1), mi.UInt32(0))
        return {SCORE_SUMS[0]: q, SCORE_SUMS[1]: q * q}

    def step(self, state: dict, ray_index: Any, root: Any, rho_w: Any, wavelength: Any, bsdfs: list,
             *columns: Any) -> dict:
        """The plain walk's step, then the score: a detected flight adds w; a wall re-emission is split."""

        import drjit as dr
        import mitsuba as mi

        out = super().step(state, ray_index, root, mi.Float(1.0), wavelength, bsdfs, *columns)  # ρw: a weight
        active = state["fate"] == _ACTIVE
        weight, score = state["weight"], state["score"]
        detected = active & (out["fate"] == int(SphereFate.DETECTED))
        score = score + dr.select(detected, weight, 0.0)
        diffuse = active & (out["walls"] > state["walls"])  # re-emitted by the sphere wall or the baffle
        weight = dr.select(diffuse, weight * rho_w, weight) * dr.minimum(out["held"], 1.0)  # a disk's BSDF weight
        emitted = diffuse & (out["last"] == 0)  # by the sphere wall
        x = out["p"]
        # the plain step's numbers of this step (the same expressions: Dr.Jit computes them once); at a wall event
        # it used none of them (ρw = 1: u0 decides nothing; u1, u2 drew the direction replaced here; u3 is a holder's)
        keys = [hash32(root + (mi.UInt32(WALK_BASE + j) + 4 * state["bounces"]) * GOLDEN) for j in range(4)]
        u = [to_unit(hash32(ray_index ^ key), mi.Float) for key in keys]
        own = [hash32(root + (mi.UInt32(EXPECTED_BASE + j) + _STRIDE * state["bounces"]) * GOLDEN)
               for j in range(1 if self.baffle is None else 2)]
        v = [to_unit(hash32(ray_index ^ key), mi.Float) for key in own]
        axis, e1, e2 = (_vec(column) for column in self.detector_frame)
        radius = self.radius
        cos_alpha = self.detector[1] / radius

        def on_sphere(cos_theta: Any, u_phi: Any) -> Any:
            sin_theta = dr.safe_sqrt(1.0 - cos_theta * cos_theta)
            sin_phi, cos_phi = dr.sincos(dr.two_pi * u_phi)
            return radius * (cos_theta * axis + (sin_theta * cos_phi) * e1 + (sin_theta * sin_phi) * e2)

        inward = -dr.normalize(x)

        def toward(point: Any) -> Any:
            gap = point - x
            return dr.select(dr.squared_norm(gap) > 1e-12 * radius * radius, dr.normalize(gap), inward)

        elsewhere = toward(on_sphere(-1.0 + u[1] * (1.0 + cos_alpha), u[2]))  # uniform outside the detector's cap
        f_d = self.detector_fraction
        if self.baffle is None:
            seen = emitted
            new_d = dr.select(emitted, elsewhere, out["d"])
        else:
            cap_point = on_sphere(1.0 - u[0] * (1.0 - cos_alpha), u[3])  # uniform on the detector's cap
            to_cap = toward(cap_point)
            centre, normal, baffle_radius = _vec(self.baffle[0]), _vec(self.baffle[1]), self.baffle[2]
            t_b = dr.dot(centre - x, normal) / dr.dot(to_cap, normal)
            on_disk = dr.squared_norm(x + t_b * to_cap - centre) <= baffle_radius * baffle_radius
            hidden = (t_b > 0.0) & (t_b < dr.norm(cap_point - x)) & on_disk
            seen = emitted & ~hidden
            into_baffle = emitted & hidden & (v[1] < f_d)
            new_d = dr.select(emitted, dr.select(into_baffle, to_cap, elsewhere), out["d"])
        score = score + dr.select(seen, weight * f_d, 0.0)
        weight = dr.select(seen, weight * (1.0 - f_d), weight)
        if self.baffle is not None:  # a baffle re-emission: K directions, their hits scored, one miss flown
            baffle = diffuse & (out["last"] == 3)
            hits, chosen = dr.if_stmt(
                (x, state["d"], out["d"], state["bounces"], ray_index, root), baffle,
                lambda *args: self._split(*args), lambda *_: (mi.Float(0.0), mi.Vector3f(out["d"])),
                label="sphere_baffle_split")
            share = hits * (1.0 / BAFFLE_SPLIT)
            score = score + dr.select(baffle, weight * share, 0.0)
            weight = dr.select(baffle, weight * (1.0 - share), weight)
            new_d = dr.select(baffle, chosen, new_d)
        # roulette: a weight below θ(1 − s) lives on as θ(1 − s) with probability w/(θ(1 − s)); s + w stays ≤ 1
        floor = ROULETTE * (1.0 - score)
        low = (out["fate"] == _ACTIVE) & (weight < floor)
        lives = v[0] * floor < weight
        ended = (low & ~lives) | ((out["fate"] == _ACTIVE) & (weight < SMALLEST_WEIGHT))
        weight = dr.select(low & lives, floor, weight)
        fate = dr.select(ended, mi.UInt32(int(SphereFate.WALL)), out["fate"])
        return {**out, "d": new_d, "fate": fate, "weight": weight, "score": score}


    @staticmethod
    def _lives(u: Any, weight: Any) -> Any:
        """A disk's BSDF weight is the walk's weight (``held``): a ray it returns lives on whatever its weight."""

        return weight > 0.0

    def _split(self, b: Any, incoming: Any, first: Any, bounces: Any, ray_index: Any, root: Any) -> tuple[Any, Any]:
        """
        At a baffle point ``b``: :data:`BAFFLE_SPLIT` Lambertian directions (the plain step's ``first`` and K − 1
        more about the side the ray came from), how many reach the detector's cap (nothing lies between: the
        baffle clears every holder's plane), and one of those that miss, drawn uniformly (``first`` if all hit).
        """

        import drjit as dr
        import mitsuba as mi

        normal = _vec(self.baffle[1])
        facing = dr.select(dr.dot(incoming, normal) > 0.0, -normal, normal)
        frame = mi.Frame3f(facing)
        axis, threshold = _vec(self.detector[0]), self.detector[1]
        radius2 = self.radius * self.radius
        keys = [hash32(root + (mi.UInt32(EXPECTED_BASE + 2 + j) + _STRIDE * bounces) * GOLDEN)
                for j in range(2 * BAFFLE_SPLIT - 1)]
        w = [to_unit(hash32(ray_index ^ key), mi.Float) for key in keys]
        directions = [first] + [dr.normalize(frame.to_world(mi.warp.square_to_cosine_hemisphere(
            mi.Point2f(w[2 * k], w[2 * k + 1])))) for k in range(BAFFLE_SPLIT - 1)]
        missed = []
        for d in directions:
            along = dr.dot(b, d)
            t = -along + dr.safe_sqrt(along * along - (dr.squared_norm(b) - radius2))
            missed.append(dr.dot(b + t * d, axis) < threshold)
        count = sum(dr.select(m, mi.UInt32(1), mi.UInt32(0)) for m in missed)
        pick = mi.UInt32(dr.floor(w[-1] * mi.Float(count)))
        chosen, seen = mi.Vector3f(first), mi.UInt32(0)
        for d, m in zip(directions, missed):
            chosen = dr.select(m & (seen == pick), d, chosen)
            seen = seen + dr.select(m, mi.UInt32(1), mi.UInt32(0))
        return mi.Float(BAFFLE_SPLIT) - mi.Float(count), chosen


_PLAIN_PORT = (("depth", 0.0, "a port wall (depth > 0)"), ("shape", "circle", "a non-circular port"),
               ("aperture", None, "a holder mask (aperture)"), ("field_of_view", None, "a detector field of view"),
               ("proud", 0.0, "a specimen standing proud of its port (proud > 0)"))


def expected_layout(sphere: Any, holders: Sequence[Any], caps: Sequence[int | None], max_bounces: int,
                    wavelengths: Sequence[float]) -> ExpectedSphereLayout:
    """
    The :class:`ExpectedSphereLayout` of one configuration (the arguments of
    :meth:`~virtspec_mi.instruments.sphere.geometry.Sphere.layout`), or ``ValueError`` naming
    ``detector='expected'`` and the feature of ``sphere`` it cannot score exactly.
    """

    refused = "detector='expected' scores detection where a wall bounce's chance of reaching the detector is exact"
    for port in sphere.ports:
        for name, plain, what in _PLAIN_PORT:
            if getattr(port, name) != plain:
                raise ValueError(f"{refused}; port {port.name!r} has {what}: use detector='counted' for this sphere")
    for name, plain, what in (("beam_profile", None, "a traced beam (beam_profile)"),
                              ("wall_specular", 0.0, "a mirror share of the wall (wall_specular > 0)"),
                              ("wall_bsdf", None, "a wall BSDF (wall_bsdf)")):
        if getattr(sphere, name) != plain:
            raise ValueError(f"{refused}; the sphere has {what}: use detector='counted' for this sphere")
    detectors = [j for j, action in enumerate(caps) if action == int(SphereFate.DETECTED)]
    if len(detectors) != 1:
        raise ValueError(f"{refused}: it needs exactly one detector port (got {len(detectors)}): use "
                         "detector='counted' for this sphere")
    layout = sphere.layout(holders, caps, max_bounces, wavelengths)
    if type(layout) is not SphereLayout:  # a feature the checks above do not name
        raise ValueError(f"{refused}; this sphere is not a plain one: use detector='counted'")
    port = sphere.ports[detectors[0]]
    radius = sphere.radius
    values = {f.name: getattr(layout, f.name) for f in fields(SphereLayout)}
    frame = holder_frame(port.axis, True)  # columns e₁, e₂, c
    return ExpectedSphereLayout(**values, detector=(tuple(float(v) for v in port.axis),
                                                    radius * port.cos_half_angle(radius)),
                                detector_fraction=float(sphere.cap_fraction(port)),
                                detector_frame=tuple(tuple(float(v) for v in frame[:, k]) for k in (2, 0, 1)))
