"""
Shared pieces of random-walk specimens
======================================

Layered and turbid specimens (``abm_b``/``abm_u``, ``turbid_slab``) run an analog
random walk. They share three conventions with the ``spectrophotometer`` integrator:

- **Random numbers.** ``sample()`` receives only ``sample1`` and ``sample2``; the
  walk draws its numbers from a PCG32 seeded by the bits of those three uniforms
  (:func:`walk_rng`), so the walk is a pure function of the instrument's counter-based
  stream and counts stay independent of chunking, lane count and thread count.
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
``mi.PCG32``): the kernel keeps it as loop state and never looks inside.

References
----------
Baranoski et al. (2001), Sect. 3 (each ray is reflected, transmitted or absorbed).
"""

from __future__ import annotations

from typing import Any, Protocol, runtime_checkable

__all__ = ["CAPPED_COMPONENT", "RandomWalk", "is_random_walk", "walk_rng", "walk_steps", "walk_to_end"]

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
    rays (:func:`virtspec_mi.kernel.tracer.walk_plan`), never for a count.
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


def walk_rng(sample1: Any, sample2: Any) -> Any:
    """A per-lane ``mi.PCG32`` seeded from the bits of ``sample1`` and ``sample2``."""

    import drjit as dr
    import mitsuba as mi

    u0 = dr.reinterpret_array(mi.UInt32, mi.Float(sample1))
    u1 = dr.reinterpret_array(mi.UInt32, mi.Float(sample2.x))
    u2 = dr.reinterpret_array(mi.UInt32, mi.Float(sample2.y))
    rng = mi.PCG32()
    rng.seed(mi.sample_tea_64(u0, u1), mi.sample_tea_64(u2, u0 ^ u1))
    return rng
