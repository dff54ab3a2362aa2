"""
The instrument seam: init, process, postprocess
===============================================

An :class:`Instrument` turns a bench (the emitter and specimen disks of a loaded scene,
:class:`virtspec_mi.engine.bench.Bench`), the common :class:`~virtspec_mi.settings.Settings`
and its own options into its result, in three steps (as Eradiate's ``Experiment``):

1. :meth:`Instrument.init` — the rules between the settings, the options and the bench
   (what one instrument cannot take, e.g. a diffuse beam into an integrating sphere),
   and the *plan*: what the engine traces (the readings over wavelength × θi × specimen
   parameter points, the rays of each, and what a ray's exit adds in the kernel);
2. :meth:`Instrument.process` — the engine traces the plan into exact tallies;
3. :meth:`Instrument.postprocess` — the tallies become the instrument's result.

Every instrument declares, as class attributes, its ``name`` (its key in
:data:`virtspec_mi.instruments.INSTRUMENTS` and its command-line subcommand), its
``options`` (an :class:`~virtspec_mi.settings.Options` class, or ``None``) and its
``result`` (the result class it returns). A new instrument is one module of
:mod:`virtspec_mi.instruments` with one such class, and one row of the registry.

:func:`take` runs the three steps.

References
----------
Eradiate: ``eradiate.experiments.Experiment`` (init, process, postprocess).
Baranoski et al. (2001), Sect. 3 (the instrument).
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from virtspec_mi.engine.parameters import ParameterSpace
from virtspec_mi.settings import Options, Settings

__all__ = ["Plan", "Instrument", "take"]


@dataclass(frozen=True)
class Plan:
    """
    What a measurement traces: the settings, the incidence angles and the specimen
    parameter points (the readings: wavelength × θi × points). Transitional: the
    engine's keyed plan replaces it.
    """

    settings: Settings
    theta_i: np.ndarray
    parameters: ParameterSpace | None = None


class Instrument(ABC):
    """
    One instrument (see the module docstring): ``init`` → plan, ``process`` → tallies,
    ``postprocess`` → result. An instance takes one measurement: ``init`` keeps what
    ``postprocess`` needs.
    """

    name: ClassVar[str]
    """Registry key and command-line subcommand."""
    options: ClassVar[type[Options] | None] = None
    """The instrument's own options beside the settings, or ``None``."""
    result: ClassVar[type]
    """The result class the instrument returns."""

    def __init__(self, scene: str = "") -> None:
        self.scene = scene
        """Fingerprint of the scene, recorded in the result."""

    @abstractmethod
    def init(self, bench: Any, settings: Settings, options: Options | None, theta_i: np.ndarray,
             parameters: ParameterSpace | None) -> Any:
        """Check the measurement and plan it (see the module docstring)."""

    @abstractmethod
    def process(self, plan: Any, *, keyed: bool = True, checkpoint: Any = None, progress: bool | None = False,
                runner: Any = None) -> Any:
        """Trace ``plan`` through the engine: exact tallies."""

    @abstractmethod
    def postprocess(self, tally: Any) -> Any:
        """The instrument's result from the tallies of :meth:`process`."""


def take(instrument: Instrument, bench: Any, settings: Settings, options: Options | None = None,
         theta_i: Any = None, parameters: ParameterSpace | None = None, **run: Any) -> Any:
    """
    One measurement with ``instrument``: :meth:`~Instrument.init`,
    :meth:`~Instrument.process` (``run``: ``keyed``, ``checkpoint``, ``progress``,
    ``runner``) and :meth:`~Instrument.postprocess`. ``theta_i``: the incidence angles
    (default: ``settings.theta_i``).
    """

    angles = np.atleast_1d(np.asarray(settings.theta_i if theta_i is None else theta_i, dtype=np.float64))
    plan = instrument.init(bench, settings, options, angles, parameters)
    return instrument.postprocess(instrument.process(plan, **run))
