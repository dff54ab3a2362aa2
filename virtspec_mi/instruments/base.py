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
from typing import Any, ClassVar

import numpy as np

from virtspec_mi.engine.parameters import ParameterSpace
from virtspec_mi.engine.plan import Plan
from virtspec_mi.engine.readings import BatchRunner, run
from virtspec_mi.engine.tally import Tally
from virtspec_mi.settings import Options, Settings

__all__ = ["Instrument", "take", "reading_labels", "reading_grid"]


class Instrument(ABC):
    """
    One instrument (see the module docstring): ``init`` → plan, ``process`` → tallies,
    ``postprocess`` → result. An instance takes one measurement: ``init`` keeps what
    ``process`` and ``postprocess`` need (the bench, the plan, the options).
    """

    name: ClassVar[str]
    """Registry key and command-line subcommand."""
    options: ClassVar[type[Options] | None] = None
    """The instrument's own options beside the settings, or ``None``."""
    result: ClassVar[type]
    """The result class the instrument returns."""

    def __init__(self, scene: str = "", source: dict | None = None) -> None:
        self.scene = scene
        """Fingerprint of the scene, recorded in the plan (a checkpoint's identity) and the result."""
        self.source = source
        """The scene's name and ``-D`` defines (:func:`virtspec_mi.scene.scene_source`), recorded in the result."""
        self.bench: Any = None
        self.plan: Plan | None = None

    @abstractmethod
    def init(self, bench: Any, settings: Settings, options: Options | None, theta_i: np.ndarray,
             parameters: ParameterSpace | None) -> Plan:
        """
        Check the measurement (the rules between the settings, the options and the bench)
        and plan it: a :class:`~virtspec_mi.engine.plan.Plan` (kept as :attr:`plan`).
        ``options`` are the instrument's own (``None`` only for an instrument that has
        none), validated; ``theta_i`` the incidence angles; ``parameters`` the specimen
        parameter points, or ``None``.
        """

    def process(self, plan: Plan, *, checkpoint: Any = None, progress: bool | None = False,
                runner: BatchRunner | None = None) -> Tally:
        """
        Trace ``plan`` on the bench through the engine (:func:`virtspec_mi.engine.readings.run`),
        keyed on the reading indices (``checkpoint``, ``progress``, ``runner``: Dask workers).
        """

        return run(self.bench, plan, checkpoint=checkpoint, progress=progress, runner=runner)

    @abstractmethod
    def postprocess(self, tally: Tally) -> Any:
        """The instrument's result from the tallies of :meth:`process`."""

    def warn_if_uncertified(self, result: Any, stacklevel: int = 2) -> None:
        """
        A ``RuntimeWarning`` for every reason a reading of ``result`` escaped its
        certificate, attributed to the frame ``stacklevel`` levels up from the caller (1:
        the caller; 2, the default: its caller). None by default: an instrument whose
        result says so in its summary.
        """


def take(instrument: Instrument, bench: Any, settings: Settings, options: Options | None = None,
         theta_i: Any = None, parameters: ParameterSpace | None = None, **run: Any) -> Any:
    """
    One measurement with ``instrument``: :meth:`~Instrument.init`,
    :meth:`~Instrument.process` (``run``: ``checkpoint``, ``progress``,
    ``runner``) and :meth:`~Instrument.postprocess`. ``theta_i``: the incidence angles
    (default: ``settings.theta_i``); ``options``: the instrument's (default: their defaults).
    """

    angles = np.atleast_1d(np.asarray(settings.theta_i if theta_i is None else theta_i, dtype=np.float64))
    if options is None and instrument.options is not None:
        options = instrument.options()
    plan = instrument.init(bench, settings, options, angles, parameters)
    return instrument.postprocess(instrument.process(plan, **run))


def reading_labels(plan: Plan, theta_dim: bool = True) -> tuple[tuple[str, ...], dict[str, np.ndarray]]:
    """
    The dims and coordinates of ``plan``'s readings, as every result labels them:
    ``wavelength``, ``theta_i`` (with ``theta_dim=False`` and one angle, a scalar label),
    then the parameter dims (:attr:`~virtspec_mi.engine.parameters.ParameterSpace.dims`).
    """

    angles, space = np.asarray(plan.theta_i, dtype=np.float64), plan.parameters
    keep = theta_dim or len(angles) > 1
    dims = ("wavelength", *(("theta_i",) if keep else ()), *(() if space is None else space.dims))
    coords = {"wavelength": plan.wavelengths, "theta_i": angles if keep else np.asarray(angles[0]),
              **({} if space is None else space.coords())}
    return dims, coords


def reading_grid(plan: Plan, values: Any, group: int = 0, theta_dim: bool = True) -> np.ndarray:
    """
    ``values`` of ``plan``'s flat readings (indexed by reading first, any trailing axes)
    for reading group ``group``, laid out over the dims of :func:`reading_labels` (then
    the trailing axes): reading k = ((g·n_p + i_p)·n_θ + i_θ)·n_λ + i_λ goes to
    ``[i_λ, i_θ, *i_p]`` (i_p over the parameter dims).
    """

    _, _, n_theta, n_lam = plan.shape
    values = np.asarray(values)[group * plan.keys:(group + 1) * plan.keys]
    extra = () if plan.parameters is None else tuple(plan.parameters.shape)
    shaped = values.reshape(*extra, n_theta, n_lam, *values.shape[1:])
    p = len(extra)
    out = np.transpose(shaped, (p + 1, p, *range(p), *range(p + 2, shaped.ndim)))
    if not (theta_dim or n_theta > 1):
        out = out[:, 0]
    return out.copy()
