"""
Exit hooks: what an instrument adds to a ray's exit in the kernel
=================================================================

The ray kernel (:func:`virtspec_mi.kernel.tracer.tally_readings`) always tallies every
ray's fate (exact :class:`~virtspec_mi.kernel.counts.Counts`). An instrument that needs
more hands the call one *exit hook*: a plain-value object (picklable: a Dask worker
receives it) that gives every ray a **bin code** in [0, K) — K = :attr:`ExitHook.size`
for a ray it does not bin — and, optionally, per-ray values to sum. The kernel tallies
the codes of each reading into an exact ``int64`` histogram of K bins and the per-ray
values into per-reading sums: one tally path for every instrument.

A hook is one of two kinds (:attr:`ExitHook.needs_rays`):

- ``False``: a per-ray function of the ray's outgoing direction, fate and its reading's
  φi — and, for a hook with :attr:`ExitHook.incidence`, its reading's incidence direction
  (the RGL grid's half vectors) — (:meth:`ExitHook.bin`), compiled into the ray kernel itself — and, for a random-walk
  specimen on queued lanes, run when each ray's walk ends
  (:class:`virtspec_mi.instruments.goniophotometer.hook.BinLayout`, the goniophotometer's bins);
- ``True``: the kernel traces every ray's first interaction on its own lane (no queued
  walk) and hands the hook those lanes (:class:`ChunkRays`); the hook continues them
  (:meth:`ExitHook.exits`: :class:`virtspec_mi.instruments.sphere.walk.SphereLayout`, the
  integrating sphere's walk).

A fourth instrument plugs in a new hook type with the same members.

References
----------
Baranoski et al. (2001), Sect. 3 (every ray has one fate; counts are exact).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

__all__ = ["ChunkRays", "ExitHook"]


@dataclass
class ChunkRays:
    """
    The traced lanes of one chunk, as a hook with ``needs_rays = True`` receives them.

    Attributes
    ----------
    lanes : dict
        Symbolic per-lane values of :meth:`virtspec_mi.kernel.tracer.trace_rays`'s kernel:
        ``wo`` (specimen frame), ``target`` (specimen point, local), ``fate``,
        ``specular``, ``rare`` (bits: 1 weight violation, 2 capped, 4 rounded weight,
        8 invalid direction), ``weight``.
    slot : Any
        Each lane's reading, an index into the chunk's readings (``None``: one reading).
    root : int
        The chunk's random-number root (:func:`virtspec_mi.kernel.rng.chunk_root`).
    wavelengths : ndarray
        The wavelength (nm) of each of the chunk's readings.
    specimen : Any
        The bench's specimen BSDF.
    column : callable
        ``column(values, kind, slot)``: per-reading host ``values`` (one per reading of
        the chunk) at positions of readings ``slot`` (``None``: one reading), as Dr.Jit
        type ``kind``.
    ray_index : callable
        ``ray_index(position, slot)``: the low word of the global ray index (the random
        numbers' counter) of the rays at lane positions ``position`` of readings ``slot``.
    safe_point : callable or None
        Called by a hook that runs its own kernels between two of them (a long walk launched
        in parts): where the caller honours an interrupt (the engine's
        ``virtspec_mi.base.interrupts.check``); ``None``: nothing to call.
    """

    lanes: dict
    slot: Any
    root: int
    wavelengths: np.ndarray
    specimen: Any
    column: Callable[[np.ndarray, Any, Any], Any]
    ray_index: Callable[[Any, Any], Any]
    safe_point: Callable[[], None] | None = None


class ExitHook:
    """
    The members every exit hook has (see the module docstring); a subclass sets
    :attr:`size` and implements :meth:`bin` or :meth:`exits`.
    """

    needs_rays: bool = False
    """True: :meth:`exits` continues the traced lanes; False: :meth:`bin` per ray."""
    sums: tuple[str, ...] = ()
    """Names of the per-ray values :meth:`exits` returns, summed per reading."""
    incidence: bool = False
    """True: :meth:`bin` also receives each ray's reading's incidence direction ``wi``
    (specimen frame, unit, towards the emitter; float32)."""
    spectral: bool = False
    """True when the tally depends on the wavelength beyond the specimen's response (the
    readings of a wavelength-independent specimen then do not share rays)."""

    @property
    def size(self) -> int:
        """K: the number of bins (code K: not binned)."""

        raise NotImplementedError

    def beam_bsdf(self, specimen: Any) -> Any:
        """The BSDF the beam meets, given the bench's specimen (the specimen itself by default)."""

        return specimen

    def pairing(self, phi_i: float) -> int:
        """
        0 or 1: the kernel tallies bins two to a 64-bit word, (2m − p, 2m + 1 − p) for
        pairing p, in a reading at azimuth ``phi_i`` (degrees). Only speed depends on it
        (a SIMD packet costs one memory update per distinct word): pair the bins a
        reading's rays most often fall into side by side. 0 by default.
        """

        return 0

    def bin(self, wo: Any, fate: Any, phi_i: Any, wi: Any = None) -> Any:
        """
        Per-ray bin code (``UInt32`` in [0, K]) from the outgoing direction, fate and φi
        (degrees); ``wi``, the incidence direction, is given only to a hook with :attr:`incidence`.
        """

        raise NotImplementedError

    def exits(self, rays: ChunkRays) -> tuple[Any, dict[str, Any]]:
        """Per-ray bin codes and the per-ray values named by :attr:`sums` (evaluated or symbolic)."""

        raise NotImplementedError
