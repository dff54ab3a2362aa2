"""
The spectrophotometer with rays allocated per wavelength: :class:`Allocated`
==============================================================================

A derived quantity (a colour, a band, an index: :mod:`virtspec_mi.applications.targets`)
needs readings at one θi whose rays differ from wavelength to wavelength (Nₖ ∝ |wₖ| of its
functionals). :class:`Allocated` is the spectrophotometer (:class:`~.Hemispherical`) taking
such readings through the instrument seam:

1. :meth:`Allocated.init` — the :class:`Allocation` (a wavelength grid, the rays of each,
   0: not traced, and the seed of the rays) becomes the plan of the traced wavelengths
   (its :attr:`Allocated.used` indices into the grid), each reading from its own global
   ray index k·stride (k its index in the grid, stride the most rays of one reading), so
   that readings of one allocation never share rays;
2. :meth:`Allocated.process` — one batched kernel call
   (:func:`virtspec_mi.engine.readings.trace_allocated`) at the allocation's seed;
3. :meth:`Allocated.postprocess` — the readings result over the traced wavelengths, as the
   spectrophotometer's (:func:`~virtspec_mi.instruments.base.readings_result`), recording
   the plan's settings (their own seed).

It is no row of the registry (no subcommand, no options of its own): an application that
allocates rays takes it directly, ``Allocated(scene, source).run(bench, settings, allocation)``.

References
----------
Hoeffding (1963), Theorem 2 (the allocation's tolerance); Baranoski et al. (2001), eq. (2).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from virtspec_mi.engine.parameters import ParameterSpace
from virtspec_mi.engine.plan import Plan
from virtspec_mi.engine.readings import trace_allocated
from virtspec_mi.engine.tally import Tally
from virtspec_mi.instruments.base import readings_result
from virtspec_mi.instruments.hemispherical import Hemispherical
from virtspec_mi.results.readings import Result
from virtspec_mi.settings import Settings

__all__ = ["Allocation", "Allocated"]


@dataclass(frozen=True, eq=False)
class Allocation:
    """Readings at one θi with rays of their own per wavelength of ``grid`` (0: not traced), traced at ``seed``."""

    grid: np.ndarray
    """The wavelengths (nm)."""
    rays: np.ndarray
    """Rays of each wavelength of :attr:`grid` (whole numbers ≥ 0)."""
    seed: int
    """The seed of the rays (the plan's settings keep their own)."""
    offsets: np.ndarray | None = None
    """
    The global index of each wavelength's first ray (``None``: k·stride, k its index in
    :attr:`grid`, stride the most rays of one): a reading that goes on from rays it traced
    before (a sequential target's next batch) starts where they ended.
    """


class Allocated(Hemispherical):
    """The spectrophotometer with rays allocated per wavelength (see the module docstring)."""

    def init(self, bench: Any, settings: Settings, options: Any, theta_i: np.ndarray,
             parameters: ParameterSpace | None) -> Plan:
        if not isinstance(options, Allocation):
            raise ValueError(f"an allocated reading takes an Allocation (got {type(options).__name__})")
        if parameters is not None or len(theta_i) != 1:
            raise ValueError("an allocated reading is taken at one theta_i and the scene's own specimen parameters")
        grid, rays = np.asarray(options.grid, dtype=np.float64), np.asarray(options.rays, dtype=np.int64)
        self.bench, self.allocation = bench, options
        self.used = np.flatnonzero(rays > 0)
        """The indices of the traced wavelengths in the allocation's grid."""
        theta = float(theta_i[0])
        self.readings = [(float(grid[k]), theta, float(settings.phi_i)) for k in self.used]
        self.plan = Plan(settings.updated(wavelengths=[float(w) for w in grid[self.used]]), (theta,),
                         scene=self.scene)
        return self.plan

    def process(self, plan: Plan, *, checkpoint: Any = None, progress: bool | None = False,
                runner: Any = None) -> Tally:
        if checkpoint is not None or runner is not None:
            raise ValueError("an allocated reading is traced in this process, in one call (no checkpoint, no workers)")
        rays = np.asarray(self.allocation.rays, dtype=np.int64)
        offsets = self.allocation.offsets
        offsets = self.used * int(rays.max()) if offsets is None else np.asarray(offsets, dtype=np.int64)[self.used]
        return trace_allocated(self.bench, plan.settings.updated(seed=self.allocation.seed), self.readings,
                               rays[self.used], offsets=offsets)

    def postprocess(self, tally: Tally) -> Result:
        return readings_result(self.bench, self.plan, tally, self.scene, self.source)
