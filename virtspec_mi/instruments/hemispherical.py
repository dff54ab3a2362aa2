"""
The spectrophotometer: hemispherical readings
=============================================

The paper's instrument (Baranoski et al. 2001): the specimen lit from the emitter disk,
every ray's fate tallied — reflected into the upper hemisphere, transmitted into the
lower one, absorbed — giving reflectance ρ = m/N (eq. 2), transmittance τ and
absorptance α = 1 − ρ − τ per reading, with the certificate of the ray budget
(:mod:`virtspec_mi.budgets.rules`). :func:`virtspec_mi.measure` and
:func:`virtspec_mi.sweep` take their readings with :class:`Hemispherical`: no options
beside the :class:`~virtspec_mi.settings.Settings`; the result is a
:class:`~virtspec_mi.results.hemispherical.Result`.

A measurement is keyed (a sweep: reading k owns the global ray indices
[k·stride, k·stride + N), resumable, on Dask workers) or not (``measure``: consecutive
ray ranges, as it has always numbered its rays). An unkeyed measurement of one specimen
parameter point sets the point on the scene for the reading and gives the scene its
own values back afterwards.

References
----------
Baranoski et al. (2001), eqs. (2), (23); Figs. 5 and 6.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any, ClassVar

import numpy as np

from virtspec_mi.engine.parameters import ParameterSpace, apply_point, current_values
from virtspec_mi.engine.readings import run
from virtspec_mi.instruments.base import Instrument, Plan
from virtspec_mi.results.hemispherical import Result
from virtspec_mi.settings import Options, Settings

__all__ = ["Hemispherical"]


class Hemispherical(Instrument):
    """The spectrophotometer (see the module docstring)."""

    name: ClassVar[str] = "hemispherical"
    options: ClassVar[type[Options] | None] = None
    result: ClassVar[type] = Result

    def init(self, bench: Any, settings: Settings, options: Options | None, theta_i: np.ndarray,
             parameters: ParameterSpace | None) -> Plan:
        self.bench = bench
        return Plan(settings, theta_i, parameters)

    def process(self, plan: Plan, *, keyed: bool = True, checkpoint: Any = None, progress: bool | None = False,
                runner: Any = None) -> Result:
        space = plan.parameters
        if keyed or space is None:
            return run(self.bench, plan.settings, plan.theta_i, keyed=keyed, scene=self.scene, checkpoint=checkpoint,
                       progress=progress, parameters=space, runner=runner)
        if space.size != 1:
            raise ValueError("an unkeyed measurement takes one value per parameter (a sweep takes several)")
        original = current_values(self.bench, space.keys)
        try:
            apply_point(self.bench, space.keys, space.point(0))
            result = run(self.bench, plan.settings, plan.theta_i, keyed=False, progress=progress)
        finally:
            apply_point(self.bench, space.keys, original)
        return replace(result, parameters=space.as_dict(),
                       coords={**result.coords, **{n: np.asarray(v[0]) for n, v in space.coords().items()}})

    def postprocess(self, tally: Result) -> Result:
        return tally
