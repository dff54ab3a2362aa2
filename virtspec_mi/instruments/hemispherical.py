"""
The spectrophotometer: hemispherical readings
=============================================

The paper's instrument (Baranoski et al. 2001): the specimen lit from the emitter disk,
every ray's fate tallied — reflected into the upper hemisphere, transmitted into the
lower one, absorbed — giving reflectance ρ = m/N (eq. 2), transmittance τ and
absorptance α = 1 − ρ − τ per reading, with the certificate of the ray budget
(:mod:`virtspec_mi.budgets.rules`). :func:`virtspec_mi.measure` and
:func:`virtspec_mi.sweep` take their readings with :class:`Hemispherical`: no options
beside the :class:`~virtspec_mi.settings.Settings` and no exit hook (the fates are what
it tallies); the result is a :class:`~virtspec_mi.results.hemispherical.Result` over
(wavelength, θi, parameter dims). A two-stage rule sizes each reading from its pilot's
R, T and A (or R and T together, ``joint``).

Every measurement is keyed (reading k owns the global ray indices [k·stride,
k·stride + N): its counts depend on (seed, k) only; resumable, on Dask workers):
``measure`` is a sweep's reading at one θi.

References
----------
Baranoski et al. (2001), eqs. (2), (23); Figs. 5 and 6.
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np

from virtspec_mi.engine.parameters import ParameterSpace
from virtspec_mi.engine.plan import Columns, Plan
from virtspec_mi.engine.readings import shares_wavelengths
from virtspec_mi.engine.tally import Tally
from virtspec_mi.instruments.base import Instrument, reading_grid, reading_labels
from virtspec_mi.results.hemispherical import Result
from virtspec_mi.settings import Options, Settings

__all__ = ["Hemispherical", "hemispherical_result"]


class Hemispherical(Instrument):
    """The spectrophotometer (see the module docstring)."""

    name: ClassVar[str] = "hemispherical"
    options: ClassVar[type[Options] | None] = None
    result: ClassVar[type] = Result

    def init(self, bench: Any, settings: Settings, options: Options | None, theta_i: np.ndarray,
             parameters: ParameterSpace | None) -> Plan:
        self.bench = bench
        self.plan = Plan(settings.updated(theta_i=float(theta_i[0])), theta_i, parameters,
                         columns=Columns.fates(settings.joint), scene=self.scene, instrument=self.name)
        return self.plan

    def postprocess(self, tally: Tally) -> Result:
        return hemispherical_result(self.bench, self.plan, tally, self.scene, self.source)

    def warn_if_uncertified(self, result: Result, stacklevel: int = 2) -> None:
        result.warn_if_uncertified(stacklevel=stacklevel + 2)


def hemispherical_result(bench: Any, plan: Plan, tally: Tally, scene: str = "", source: dict | None = None
                         ) -> Result:
    """
    The hemispherical reading of ``plan``'s readings (one group) from their tallies: a
    :class:`~virtspec_mi.results.hemispherical.Result` over (wavelength, θi, parameter dims),
    recording the scene's fingerprint ``scene`` and its ``source``.
    """

    space = plan.parameters
    dims, coords = reading_labels(plan)
    return Result(
        dims=dims, coords=coords,
        counts=tally.counts.map(lambda v: reading_grid(plan, v)),
        pilot=None if tally.pilot is None else tally.pilot.map(lambda v: reading_grid(plan, v)),
        settings=plan.settings, geometry=bench.geometry, seconds=tally.seconds, scene=scene,
        wavelength_independent=shares_wavelengths(bench),
        parameters=None if space is None else space.as_dict(), source=source)
