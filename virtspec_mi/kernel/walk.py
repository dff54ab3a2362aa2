"""
Shared pieces of random-walk specimens
======================================

Layered and turbid specimens (``abm_b``/``abm_u``, ``turbid_slab``) run an analog
random walk. They share three conventions with the ``spectrophotometer`` integrator:

- **Random numbers.** ``sample()`` receives only ``sample1`` and ``sample2``; the
  walk draws its numbers from a :class:`WalkRNG` seeded by the bits of those three
  uniforms (:func:`walk_rng`), so the walk is a pure function of the instrument's
  counter-based stream and counts stay independent of chunking, lane count and thread count.
- **Capped walks.** A walk stopped by a step cap has no fate. The BSDF reports it by
  setting ``bs.sampled_component = CAPPED_COMPONENT`` (weight 0); the integrator counts
  such rays in ``Result.capped``, apart from reflected, transmitted and absorbed, so a
  cap is never silently folded into a tally.
- **Resumable steps.** A walk specimen declares its walk as steps (the
  :class:`RandomWalk` protocol): ``walk_start`` (walk state in, from the surface
  interaction and the two samples), ``walk_step`` (one event), ``walk_done`` and
  ``walk_sample`` (the finished walk as the ``(BSDFSample3f, weight)`` that ``sample()``
  returns). ``sample()`` stays a complete Mitsuba BSDF: it runs the steps to the end
  (:func:`walk_to_end`). The ray kernel (:mod:`virtspec_mi.kernel.tracer`) drives the
  same steps itself, so that a SIMD lane whose walk ends starts the next ray of its
  queue instead of idling until the longest walk of its packet ends; a ray's events and
  random numbers are the same either way, so are the counts.

A specimen may also declare ``walk_steps``, its mean number of events per walk
(:func:`walk_steps`): the kernel picks how it queues the rays from it, the counts never
depend on it.

A walk state is any Dr.Jit PyTree (a tuple of Dr.Jit arrays and structs such as
:class:`WalkRNG`): the kernel keeps it as loop state and never looks inside.

References
----------
Baranoski et al. (2001), Sect. 3 (each ray is reflected, transmitted or absorbed).
G.L. Steele, D. Lea, C.H. Flood (2014), *Fast splittable pseudorandom number generators*,
OOPSLA '14, 453–472 (a Weyl sequence hashed by a mixing function: :class:`WalkRNG`).
"""

from __future__ import annotations

from typing import Any, Protocol, runtime_checkable

from virtspec_mi.kernel.rng import hash32, to_unit

__all__ = ["CAPPED_COMPONENT", "RandomWalk", "WalkRNG", "is_random_walk", "walk_rng", "walk_steps", "walk_to_end"]

CAPPED_COMPONENT: int = 0xFFFFFFFF
"""``BSDFSample3f.sampled_component`` of a walk that reached its step cap."""


@runtime_checkable
class RandomWalk(Protocol):
    """
    A BSDF whose ``sample()`` is a random walk, declared as resumable steps.

    - ``walk_start(si, sample1, sample2, active)`` → state: the walk of each lane from
      ``si`` (``wi``, ``wavelengths``) and the samples of ``sample()``; inactive lanes
      start finished (absorbed: weight 0).
    - ``walk_step(state)`` → state: one event of every lane the caller lets through. The
      caller runs it only on lanes whose walk is not done (a symbolic loop or
      conditional masks the others), so it needs no mask of its own.
    - ``walk_done(state)`` → ``mi.Bool``: the walk has ended (exit, absorption or cap).
    - ``walk_sample(state)`` → ``(mi.BSDFSample3f, mi.Spectrum)``: what ``sample()``
      returns for a finished walk.

    ``sample()`` must equal ``walk_sample(walk_to_end(self, walk_start(...)))`` lane for lane.
    """

    def walk_start(self, si: Any, sample1: Any, sample2: Any, active: Any) -> Any: ...

    def walk_step(self, state: Any) -> Any: ...

    def walk_done(self, state: Any) -> Any: ...

    def walk_sample(self, state: Any) -> tuple[Any, Any]: ...


def is_random_walk(bsdf: Any) -> bool:
    """True when ``bsdf`` declares the :class:`RandomWalk` steps (the kernel then drives them)."""

    return isinstance(bsdf, RandomWalk)


def walk_steps(bsdf: Any) -> float | None:
    """
    The mean number of events per walk that a walk specimen declares (optional attribute
    ``walk_steps``; ``None`` when it declares none): a hint for how the kernel queues its
    rays (:func:`virtspec_mi.kernel.queue.walk_plan`), never for a count.
    """

    steps = getattr(bsdf, "walk_steps", None)
    return None if steps is None else float(steps)


def walk_to_end(walk: RandomWalk, state: Any) -> Any:
    """Run ``walk``'s steps on ``state`` until every lane's walk is done (one symbolic loop)."""

    import drjit as dr

    return dr.while_loop(
        state=(state,),
        cond=lambda state: ~walk.walk_done(state),
        body=lambda state: (walk.walk_step(state),),
        labels=("walk",),
        label="walk",
    )[0]


class _VariantStruct(type):
    """Metaclass of :class:`WalkRNG`: its ``DRJIT_STRUCT`` (fields and types) in the active Mitsuba variant."""

    @property
    def DRJIT_STRUCT(cls) -> dict[str, Any]:  # noqa: N802 (the name Dr.Jit looks for)
        import mitsuba as mi

        return {"x": mi.UInt32, "stride": mi.UInt32}


class WalkRNG(metaclass=_VariantStruct):
    """
    A per-ray stream of random numbers for a walk: a Weyl sequence x_i = x_0 + i·s (mod 2³²)
    with a per-ray odd stride s, each term hashed by the bijective ``hash32`` ("triple32") of
    :mod:`virtspec_mi.kernel.rng`:

        u_i = hash32(x_0 + i·s) / 2³²,  i = 1, 2, …

    (24-bit resolution, as :func:`~virtspec_mi.kernel.rng.to_unit`).

    Two 32-bit words of state per lane and one 32-bit hash per number: no 64-bit
    multiply (PCG32's, emulated on AVX2), so a draw costs a few SIMD instructions. Within a
    ray the terms x_i are distinct for 2³² draws (s is odd); rays differ in both x_0 and s.
    The interface is ``mi.PCG32``'s for what walks use: ``next_uint32(mask)`` and
    ``next_float32(mask)`` advance only the lanes of ``mask``. A Dr.Jit PyTree (its two
    words ``x``, ``stride``), so it can be loop state.

    References
    ----------
    H. Weyl (1916), *Über die Gleichverteilung von Zahlen mod. Eins*, Math. Ann. 77, 313–352
    (x_0 + i·s is equidistributed); G.L. Steele, D. Lea, C.H. Flood (2014), *Fast splittable
    pseudorandom number generators*, OOPSLA '14, 453–472 (a Weyl sequence hashed by a mixing
    function); the "triple32" hash: :mod:`virtspec_mi.kernel.rng`.
    """

    def __init__(self, x: Any = None, stride: Any = None) -> None:
        self.x = x
        self.stride = stride

    def next_uint32(self, mask: Any = True) -> Any:
        """The next 32 random bits of each lane of ``mask`` (others: their current bits, not advanced)."""

        import drjit as dr

        self.x = self.x + (self.stride if mask is True else dr.select(mask, self.stride, 0))
        return hash32(self.x)

    def next_float32(self, mask: Any = True) -> Any:
        """The next uniform in [0, 1) (24-bit resolution) of each lane of ``mask``."""

        import mitsuba as mi

        return to_unit(self.next_uint32(mask), mi.Float)


_SEED_KEYS = (0x6A09E667, 0xBB67AE85)  # two constants (√2, √3 fractions) keying the seed hashes


def walk_rng(sample1: Any, sample2: Any) -> WalkRNG:
    """
    A per-lane :class:`WalkRNG` seeded from the bits of ``sample1`` and ``sample2`` (72
    random bits: the instrument's three 24-bit uniforms): x_0 = hash32(hash32(b_0 ⊕ k_0) ⊕ b_1),
    s = hash32(x_0 ⊕ b_2 ⊕ k_1) | 1.
    """

    import drjit as dr
    import mitsuba as mi

    b0 = dr.reinterpret_array(mi.UInt32, mi.Float(sample1))
    b1 = dr.reinterpret_array(mi.UInt32, mi.Float(sample2.x))
    b2 = dr.reinterpret_array(mi.UInt32, mi.Float(sample2.y))
    x = hash32(hash32(b0 ^ _SEED_KEYS[0]) ^ b1)
    return WalkRNG(x, hash32(x ^ b2 ^ _SEED_KEYS[1]) | 1)
