"""
Keyed readings of an instrument on a loaded scene: :func:`keyed_reading`
========================================================================

What every keyed measurement shares, whoever asks for it — the API's :func:`virtspec_mi.sweep`,
:func:`virtspec_mi.gonio`, :func:`virtspec_mi.sphere_measure` and :func:`virtspec_mi.take`, and the
applications that take readings (fits, tables, Klems files): the settings resolved over the
scene's integrator and the instrument's options, the call's incidence angles and specimen
parameter points, the instrument's plan (``init``) traced by the engine with a checkpoint
(held by one run at a time, named by an interrupt), in this process or on Dask workers
(:mod:`virtspec_mi.runtime.scaleout`), then its result (``postprocess``), written atomically
to ``out`` when given, and the checkpoint removed once the result is safe.

The keywords are checked once, where they enter (the API, an application's own boundary);
this module takes them as they are.

References
----------
Dubovik et al. (2021), Eradiate's ``Experiment`` (init, process, postprocess),
https://eradiate.readthedocs.io.
"""

from __future__ import annotations

import inspect
import os
from contextlib import ExitStack, contextmanager
from dataclasses import dataclass, fields
from pathlib import Path
from typing import Any, ClassVar, Iterator

import numpy as np

from virtspec_mi.base import interrupts
from virtspec_mi.base.checks import parse_theta_i
from virtspec_mi.base.files import WriteError, check_distinct, check_name_length
from virtspec_mi.engine.bench import Bench
from virtspec_mi.engine.checkpoint import checkpoint_for, claim, kept_in, remove
from virtspec_mi.engine.parameters import parameter_space
from virtspec_mi.engine.plan import Plan
from virtspec_mi.engine.readings import in_process_runner
from virtspec_mi.instruments import INSTRUMENTS, commanding
from virtspec_mi.results.io import check_output
from virtspec_mi.results.kinds import read_result as read_any
from virtspec_mi.results.readings import Result
from virtspec_mi.results.zarr import SUFFIX as ZARR_SUFFIX
from virtspec_mi.results.zarr import ZarrTable
from virtspec_mi.runtime.scene import LoadedScene
from virtspec_mi.settings import Options, Settings, option, resolve, true_or_false

__all__ = ["take", "keyed_reading", "read_result", "instrument_for", "scene_options", "incidence_angles", "RunOptions"]


def _as_given(value: Any) -> Any:
    """A run keyword is taken as given here; :func:`keyed_reading` checks it where it is used."""

    return value


@dataclass(frozen=True)
class RunOptions(Options):
    """
    The keywords of a run, beside the settings and the instrument's options, declared
    once: the API's run functions (``measure``, ``sweep``, ``gonio``, ``sphere_measure``,
    ``take`` and the generated ones, ``vm.gloss``) have their signatures built from them
    (:func:`virtspec_mi.settings.keywords`, with their defaults) and take them apart with
    :meth:`split`; :func:`keyed_reading` uses them.
    """

    title: ClassVar[str] = "run keywords"

    theta_i: Any = option(None, _as_given, "incidence angles in degrees: a number, a sequence or 'start:stop:step' "
                          "(default: the scene's)")
    parameters: dict[str, Any] | None = option(None, _as_given, "specimen parameters, name -> values")
    points: bool = option(False, _as_given, "parameters holds explicit points (one dim 'point')")
    defines: dict[str, Any] | None = option(None, _as_given, "values of an XML scene's $name parameters")
    checkpoint: str | os.PathLike | None = option(None, _as_given, "the checkpoint (JSON) a run resumes from")
    out: str | os.PathLike | None = option(None, _as_given, "the result file written when the run completes")
    progress: bool | None = option(None, _as_given, "a progress bar: True, False or None (when worth it)")
    workers: Any = option(None, _as_given, "Dask workers: a number, a scheduler address or a Client")
    task_readings: int | None = option(None, _as_given, "readings per Dask task (default: from the ray rate)")

    @classmethod
    def keyword_parameters(cls) -> list[inspect.Parameter]:
        """The run keywords as keyword-only parameters with their defaults and types (not ``None`` for all)."""

        return [inspect.Parameter(item.name, inspect.Parameter.KEYWORD_ONLY, default=item.default,
                                  annotation=item.type) for item in fields(cls)]

    @classmethod
    def split(cls, given: dict[str, Any], only: tuple[str, ...] | None = None) -> tuple[dict[str, Any], dict[str, Any]]:
        """
        ``given`` (a run function's keywords) as the run keywords — each of ``only`` (default:
        every one), its default where not given — and the others (the settings and the
        instrument's options, which :func:`virtspec_mi.settings.resolve` checks).
        """

        names = cls.names() if only is None else only
        defaults = {item.name: item.default for item in fields(cls)}
        return {name: given.get(name, defaults[name]) for name in names}, {
            name: value for name, value in given.items() if name not in names}


def keyed_reading(name: str, caller: str, what: str, scene: LoadedScene, given: dict[str, Any], **run: Any) -> Any:
    """
    The keyed reading (:func:`_keyed`) of the instrument ``name`` of ``scene`` (loaded once,
    where it entered the API) with the keywords ``given`` of ``caller`` over the scene's
    settings and the instrument's options.
    """

    declared = INSTRUMENTS[name].options
    settings, *options = resolve(caller, given, scene_options(scene.bench, Settings),
                                 *(() if declared is None else (scene_options(scene.bench, declared),)))
    return _keyed(name, what, scene, settings, options[0] if options else None, **run)


def _keyed(name: str, what: str, scene: LoadedScene, settings: Settings, options: Any, *, theta_i: Any,
           parameters: dict[str, Any] | None, points: bool, checkpoint: Any, out: Any, progress: bool | None,
           workers: Any, task_readings: int | None) -> Any:
    """
    One keyed measurement (``what``, in messages) with the instrument ``name`` of the registry, as
    :func:`sweep`, :func:`gonio` and :func:`sphere_measure` take it: the call's
    incidence angles (distinct) and specimen parameter points parsed here, the
    instrument's plan (:meth:`~virtspec_mi.instruments.base.Instrument.init`) traced
    with a checkpoint (``out``'s ``OUT.partial.json`` by default, held by one run at a
    time), in this process or on Dask workers, then its result: written atomically to
    ``out`` when given (a plan without a kernel hook fills a Zarr store batch by batch),
    and the checkpoint removed once the result is safe.
    """

    checkpoint, out = _file_path(checkpoint, "checkpoint"), _file_path(out, "out")
    if out is not None:
        check_output(out)
        checkpoint = checkpoint if checkpoint is not None else checkpoint_for(out)
    check_distinct([("out", out), ("checkpoint", checkpoint)], [("scene", scene.given)])  # never over the scene file
    bench = scene.bench
    space = parameter_space(bench, parameters or {}, points=true_or_false("points")(points))
    angles = incidence_angles(settings, INSTRUMENTS[name].angles if theta_i is None else theta_i, what)
    if len(np.unique(settings.wavelengths)) != len(settings.wavelengths):
        raise ValueError(f"wavelengths of {what} must be distinct (got repeated values)")
    instrument = instrument_for(name, scene)
    plan = instrument.init(bench, settings, options, angles, space)
    with ExitStack() as held:
        held.enter_context(_naming(checkpoint))  # an interrupt (SIGINT/SIGTERM) names the file to resume from
        if checkpoint is not None:  # one run per checkpoint, writable: checked before any cluster or tracing
            held.enter_context(claim(checkpoint))
        runner = held.enter_context(_runner(scene, workers, task_readings, plan))
        if out is not None and out.suffix.lower() == ZARR_SUFFIX and plan.hooks is None:  # fills as batches finish
            identity = {"scene": instrument.scene, **plan.settings.as_dict(), "theta_i": [float(t) for t in angles],
                        **({} if space is None else {"parameters": space.as_dict()})}
            table = ZarrTable(out, plan.settings.wavelengths, angles, identity, pilot=plan.adaptive, parameters=space)
            runner = table.stream(runner or in_process_runner(bench, plan))
        result = instrument.postprocess(instrument.process(plan, checkpoint=checkpoint, progress=progress,
                                                           runner=runner))
        if checkpoint is not None:
            _finish(result, out, checkpoint)
    instrument.warn_if_uncertified(result, stacklevel=3)  # at the caller of sweep, gonio, sphere_measure
    return result


def instrument_for(name: str, scene: LoadedScene) -> Any:
    """The instrument ``name`` of the registry for ``scene``: its fingerprint and its source recorded."""

    return INSTRUMENTS[name](scene.fingerprint, scene.source)


@contextmanager
def _naming(checkpoint: Path | None) -> Iterator[None]:
    """An interrupt (``KeyboardInterrupt``: :mod:`virtspec_mi.base.interrupts`) raised inside names ``checkpoint``."""

    try:
        yield
    except KeyboardInterrupt as stop:
        if getattr(stop, "checkpoint", None) is None and getattr(stop, "written", None) is None:
            stop.checkpoint = checkpoint  # type: ignore[attr-defined]
        raise


@contextmanager
def _runner(scene: LoadedScene, workers: Any, task_readings: int | None, plan: Plan) -> Iterator[Any]:
    """``None`` (the engine's in-process default) or a Dask runner of ``plan`` on ``workers``, held for the run."""

    if workers is None:
        if task_readings is not None:
            raise ValueError(f"task_readings needs workers (got task_readings={task_readings!r}, workers=None)")
        yield None
        return
    from virtspec_mi.runtime import scaleout  # imports dask.distributed: only when it is used

    scaleout.check_workers(workers)
    scaleout.check_task_readings(task_readings)
    scaleout.portable_scene(scene.given)  # refused before any cluster starts
    with scaleout.connect(workers) as client:
        yield scaleout.dask_runner(client, scene.given, scene.fingerprint, plan, task_readings, defines=scene.defines)


def _file_path(value: Any, name: str) -> Path | None:
    """``value`` (a file path or ``None``) as a ``Path``; ``ValueError`` naming ``name`` otherwise."""

    if value is None:
        return None
    if not isinstance(value, (str, os.PathLike)):
        raise ValueError(f"{name} must be a file path (str or os.PathLike) or None (got {type(value).__name__} "
                         f"{value!r})")
    check_name_length(name, value)
    return Path(value)


def _finish(result: Any, out: Path | None, checkpoint: Path) -> None:
    """
    Write ``result`` to ``out`` (when given), then remove the checkpoint — with signals held
    (a KeyboardInterrupt inside the NetCDF writer's file lock can hang the process): one that
    came meanwhile acts once the file is whole, the interrupt then naming the file written
    (``written``), nothing to resume.
    """

    if out is not None and out.suffix.lower() == ".nc":  # the writer's imports (seconds) before signals are held
        from virtspec_mi.results.io import warm_writer

        warm_writer()
    try:
        with interrupts.deferred():
            if out is not None:
                _write(result, out, checkpoint)
            remove(checkpoint)  # the readings are safe: returned, and written to out when given
    except KeyboardInterrupt as stop:
        stop.checkpoint, stop.written = None, out  # type: ignore[attr-defined]
        raise


def _write(result: Result, out: Path, checkpoint: Path) -> None:
    """Write ``result`` to ``out``; if that fails the error says where the finished readings are kept."""

    try:
        result.write(out)
    except WriteError as error:  # names out and the cause, carries the result; the checkpoint's state added
        raise error.keeping(kept_in(checkpoint), result) from None


def incidence_angles(settings: Settings, theta_i: Any, what: str) -> np.ndarray:
    """The incidence angles of a call: ``theta_i`` as given, else the settings'; distinct."""

    angles = np.array(parse_theta_i(settings.theta_i if theta_i is None else theta_i))
    if len(np.unique(angles)) != len(angles):
        raise ValueError(f"theta_i of {what} must be distinct (got repeated values)")
    return angles


def scene_options(bench: Bench, kind: type) -> Any:
    """The options of class ``kind`` that the scene's integrator holds, else the defaults."""

    held = getattr(bench.integrator, "options", {}) if bench.integrator is not None else {}
    return held.get(kind) or kind()


def take(word: str, scene: LoadedScene, *, theta_i: Any = None, parameters: dict[str, Any] | None = None,
         points: bool = False, checkpoint: Any = None, out: Any = None, progress: bool | None = None,
         workers: Any = None, task_readings: int | None = None, **given: Any) -> Any:
    """
    The keyed reading of the instrument whose subcommand or API function is ``word``
    (``"sweep"``, ``"gonio"`` …: :func:`virtspec_mi.instruments.commanding`) on a loaded
    scene, with the keywords of that API function — how an application takes its readings
    through the instrument seam (init, process, postprocess) without the API above it.
    """

    return keyed_reading(commanding(word).name, word, f"a {word} reading", scene, given, theta_i=theta_i,
                         parameters=parameters, points=points, checkpoint=checkpoint, out=out, progress=progress,
                         workers=workers, task_readings=task_readings)


def read_result(path: str | os.PathLike) -> Any:
    """
    The result in a file of any instrument's kind (:func:`virtspec_mi.results.kinds.read_result`,
    every instrument of the registry loaded): how an application reads back readings it wrote.
    """

    return read_any(path)
