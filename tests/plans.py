"""
Plans for tests that trace readings below the API: the spectrophotometer's own plan
(:class:`virtspec_mi.instruments.hemispherical.Hemispherical`), traced with
:func:`virtspec_mi.engine.readings.trace_readings`.
"""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np

from virtspec_mi.engine.plan import Plan
from virtspec_mi.engine.readings import trace_readings
from virtspec_mi.instruments.hemispherical import Hemispherical


def hemispherical_plan(bench: Any, settings: Any, theta_i: Sequence[float] | None = None,
                       parameters: Any = None) -> Plan:
    """The spectrophotometer's plan of ``settings`` over ``theta_i`` (default: the settings' one angle)."""

    angles = np.atleast_1d(np.asarray(settings.theta_i if theta_i is None else theta_i, dtype=np.float64))
    return Hemispherical().init(bench, settings, None, angles, parameters)


def take_readings(bench: Any, readings: Sequence[tuple[float, float, float]], settings: Any,
                  offsets: Any = None) -> tuple[Any, Any]:
    """The counts (and a two-stage pilot's, else ``None``) of every (λ, θi, φi) of ``readings``, at ``offsets``."""

    tally = trace_readings(bench, hemispherical_plan(bench, settings), 0, readings, offsets)
    return tally.counts, tally.pilot
