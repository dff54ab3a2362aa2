"""
The measurement API: :func:`measure`, :func:`sweep`, :func:`gonio`, :func:`sphere_measure`, :func:`take`
========================================================================================================

:func:`measure` takes a scene (XML path, dict or ``mi.Scene``), resolves the settings
(explicit keywords, then the scene's ``spectrophotometer`` integrator, then the
defaults of :class:`~virtspec_mi.settings.Settings`), sizes each reading with the ray
budget and returns a :class:`~virtspec_mi.results.readings.Result` with the dim ``wavelength``:
reflectance ρ = m/N (eq. 2), transmittance τ and absorptance α = 1 − ρ − τ per
wavelength, with the exact counts behind them and the certificate they give.

:func:`sweep` measures a grid (wavelength × θi) at one φi — the paper's Fig. 5 or a
spectrum — and returns the same type with dims ``(wavelength, theta_i)``; with
``parameters`` also over specimen parameters (a grid: one dim per parameter; or
explicit points: the dim ``point``; :mod:`virtspec_mi.engine.parameters`). Its reading
k (k = (i_p·n_θ + i_θ)·n_λ + i_λ, i_p the parameter point) owns the global ray indices
[k·stride, k·stride + N): its counts depend on (seed, k) only, which makes a sweep
resumable from a checkpoint and its readings independent of how they are batched
(:func:`virtspec_mi.engine.readings.take_keyed_readings`).

:func:`gonio` (the goniophotometer) and :func:`sphere_measure` (the integrating sphere)
take their readings the same keyed way, with the same keywords (``theta_i``,
``parameters``, ``points``, ``defines``, ``checkpoint``, ``out``, ``progress``,
``workers``, ``task_readings``). Every function here is thin: it parses its keywords at
the boundary — every setting of :class:`~virtspec_mi.settings.Settings` and every option
of its instrument (its signature is built from their fields,
:func:`virtspec_mi.settings.keywords`; a bad value raises ``ValueError`` naming it and
its allowed range, an unknown name ``TypeError``) — and runs the instrument of the
registry (:data:`virtspec_mi.instruments.INSTRUMENTS`). :func:`take` reads with any
instrument of the registry by name (a fourth instrument is one module and one row
there): the same keyed engine run, checkpoints and Dask included.

The command line (:mod:`virtspec_mi.cli`) reaches the layers below through this module
only (``tests/test_architecture.py``): it reads its flags with the parsers the API reads
its keywords with (:func:`parse_theta_i`, :func:`parse_wavelengths`, :func:`parse_values`,
from :mod:`virtspec_mi.checks`), names a reading's quantities (:data:`QUANTITIES`) and
the checkpoint a call with ``out`` keeps (:func:`checkpoint_for`: ``OUT.partial.json``,
named when an interrupt comes before the run names it).

References
----------
Baranoski et al. (2001), eqs. (2), (23), (24); Figs. 5 and 6.
"""

from __future__ import annotations

import os
from contextlib import ExitStack, contextmanager
from pathlib import Path
from typing import Any, Iterator

import numpy as np

from virtspec_mi.checks import parse_theta_i, parse_values, parse_wavelengths
from virtspec_mi.engine.bench import Bench
import virtspec_mi.interrupts as interrupts
from virtspec_mi.engine.checkpoint import checkpoint_for, claim, kept_in, remove
from virtspec_mi.engine.parameters import parameter_space
from virtspec_mi.files import WriteError
from virtspec_mi.engine.plan import Plan
from virtspec_mi.engine.readings import in_process_runner
from virtspec_mi.instruments import INSTRUMENTS, commanding
from virtspec_mi.kernel.counts import QUANTITIES
from virtspec_mi.results.readings import Result, fluctuation
from virtspec_mi.results.io import check_output
from virtspec_mi.results.zarr import SUFFIX as ZARR_SUFFIX
from virtspec_mi.results.zarr import ZarrTable
from virtspec_mi.scene import LoadedScene, loaded
from virtspec_mi.settings import Settings, keywords, resolve, true_or_false

__all__ = ["measure", "sweep", "gonio", "read_result", "read_gonio", "fluctuation", "sphere_measure", "take", "alias",
           "aliases",
           # what the command line takes from the layers below (see the module docstring)
           "parse_theta_i", "parse_wavelengths", "parse_values", "QUANTITIES", "checkpoint_for"]


def measure(scene: Any, *, parameters: dict[str, Any] | None = None, defines: dict[str, Any] | None = None,
            progress: bool | None = None, target: Any = None, **settings: Any) -> Any:
    """
    Measure the specimen of ``scene`` and return a certified :class:`~virtspec_mi.results.readings.Result`
    over wavelength (θi a scalar label).

    Parameters
    ----------
    scene
        XML path, scene dict or loaded ``mi.Scene`` with ``emitter`` and ``specimen`` disks;
        or a :class:`~virtspec_mi.scene.LoadedScene` (:func:`virtspec_mi.scene.loaded`: its
        bench, fingerprint and source resolved once), which every function here takes as
        it is — an application reading one scene many times loads it once.
    parameters
        Specimen parameters to set for this reading, name → one number (names as for
        :func:`sweep`); the scene gets its own values back afterwards.
    defines
        Values of an XML scene's ``$name`` parameters, name → value (``mitsuba -D``).
    **settings
        Any setting of :class:`~virtspec_mi.settings.Settings` (``theta_i``, ``phi_i``,
        ``wavelengths``, ``mu``, ``delta``, ``rays``, ``bound``, ``joint``,
        ``pilot_rays``, ``pilot_delta``, ``beam``, ``sampling``, ``seed``,
        ``chunk_size``); one left ``None`` comes from the scene's ``spectrophotometer``
        integrator when it has one, else from the default.
    progress
        ``True``: always a tqdm bar of the readings on stderr; ``False``: never; ``None``
        (default): only when stderr is a terminal and the readings are expected to last
        more than ~2 s (a spectrum of many wavelengths).
    target
        A derived quantity to certify instead of a spectrum (``vm.colour(...)``,
        ``vm.band(...)``, ``vm.index(...)``, ``vm.fapar(...)``): the instrument picks the
        wavelengths and the rays of each for the target's tolerance at δ and
        returns a :class:`~virtspec_mi.applications.derived.result.DerivedResult`
        (:mod:`virtspec_mi.applications.derived`). ``wavelengths``, ``mu``, ``rays``,
        ``pilot_rays``, ``pilot_delta`` and ``joint`` are then the target's to
        decide (giving one is an error); ``parameters`` are not taken. ``bound`` is then the
        target's certificate: ``"betting"`` (sequential batches, a betting confidence
        sequence, :mod:`virtspec_mi.applications.derived.sequential`), ``"hoeffding"``
        (one batch sized by Hoeffding's bound) or ``"auto"`` (default: betting unless a
        linear target's pilot shows it would not pay).

    References
    ----------
    Baranoski et al. (2001), eqs. (2), (23).
    """

    scene = loaded(scene, defines)
    bench = scene.bench
    if target is not None:
        return _measure_target(scene, parameters, target, settings)
    settings, = resolve("measure", settings, _scene_options(bench, Settings))
    space = parameter_space(bench, parameters or {})
    if space is not None and space.size != 1:
        raise ValueError("measure takes one value per parameter (a sweep takes several: use sweep)")
    instrument = _instrument(commanding("measure").name, scene)
    result = instrument.run(bench, settings, parameters=space, progress=progress)
    result = result.squeeze("theta_i", *([] if space is None else space.dims))  # one reading: scalar labels
    instrument.warn_if_uncertified(result)
    return result


def _measure_target(scene: LoadedScene, parameters: Any, target: Any, settings: dict[str, Any]) -> Any:
    """:func:`measure` of a derived quantity (:func:`virtspec_mi.applications.derived.sequential.certify_target`)."""

    from virtspec_mi.applications.derived.measure import REFUSED_SETTINGS
    from virtspec_mi.applications.derived.sequential import certify_target

    settings = dict(settings)
    bound = settings.pop("bound", None) or "auto"  # a target's certificate: "auto", "betting" or "hoeffding"
    given = sorted(name for name in REFUSED_SETTINGS if settings.get(name) is not None)
    if given:
        raise ValueError(f"{', '.join(given)}: a target picks its own wavelengths and rays (give its tolerance to the "
                         "target, e.g. vm.band('B04', tolerance=0.002)); leave them out")
    if parameters:
        raise ValueError("parameters: a target is measured at the scene's own specimen parameters (set them in the "
                         "scene or with defines)")
    resolved, = resolve("measure", settings, _scene_options(scene.bench, Settings))
    return certify_target(scene.bench, resolved, target, scene=scene.fingerprint, source=scene.source, bound=bound)


def sweep(
    scene: Any,
    *,
    theta_i: Any = None,
    parameters: dict[str, Any] | None = None,
    points: bool = False,
    defines: dict[str, Any] | None = None,
    checkpoint: str | os.PathLike | None = None,
    out: str | os.PathLike | None = None,
    progress: bool | None = None,
    workers: Any = None,
    task_readings: int | None = None,
    target: Any = None,
    **settings: Any,
) -> Any:
    """
    Certified readings of ``scene`` over every (wavelength, θi) pair.

    Parameters
    ----------
    scene
        XML path, scene dict or loaded ``mi.Scene`` (as for :func:`measure`).
    theta_i
        Incidence angles in degrees: a number, a sequence or a string such as
        ``"0:90:1"`` (stop included), each in [0, 90], all distinct; default: the
        scene's θi (or 0).
    parameters
        Specimen parameters to sweep, name → values (a number, a sequence, or a string
        such as ``"1e-4:2e-4:5e-5"``, stop included within rounding). Names are the
        ``mi.traverse`` keys of the specimen's BSDF (``specimen.bsdf.thickness``,
        ``specimen.bsdf.alpha.value``) or their short form (``specimen.thickness``,
        ``specimen.alpha``): see :mod:`virtspec_mi.engine.parameters`. A grid (the outer
        product) adds one result dim per parameter, named as given.
    points
        ``True``: ``parameters`` holds explicit points (equal-length lists, e.g. Latin
        hypercube samples): one dim ``point``, each parameter a coordinate along it.
    defines
        Values of an XML scene's ``$name`` parameters, name → value (``mitsuba -D``).
    checkpoint
        Path of a JSON file recording finished readings as the sweep goes; an existing
        file of the same sweep is resumed (:mod:`virtspec_mi.engine.checkpoint`; a note on
        stderr says how many readings were reused). Held by one sweep at a time (an OS
        lock; another run gets ``ValueError``) and checked writable before any tracing.
        Removed when the sweep completes — with ``out``, only once the output file is
        written. A corrupt or foreign checkpoint raises
        :class:`~virtspec_mi.engine.checkpoint.CheckpointError` and is left as it is.
    out
        Result file (``.nc``, ``.csv`` or ``.json``, :meth:`Result.write`) to write,
        atomically, when the sweep completes — or a Zarr store (``.zarr``, for tables too
        large for one file; parameter sweeps too) that receives each batch's counts as it
        finishes, region by region (:mod:`virtspec_mi.results.zarr`);
        checked before any tracing. The checkpoint defaults to ``OUT.partial.json``: if
        the write fails (a full disk …) every finished reading stays there and the same
        call, re-run, only writes.
    progress
        ``True``: always a tqdm bar on stderr; ``False``: never (and no note on
        stderr); ``None`` (default): only when stderr is a terminal and the sweep is
        expected to last more than ~2 s.
    workers
        Where the readings are traced (:mod:`virtspec_mi.scaleout`): ``None`` (default)
        in this process; an int N on a local Dask cluster of N worker processes started
        for the sweep; a scheduler address (``"tcp://host:8786"``) or a
        ``distributed.Client`` on that cluster. The counts are the same in every case;
        ``scene`` must then be an XML path (readable by every worker) or a dict. A
        cluster without workers raises ``TimeoutError`` after
        :data:`~virtspec_mi.scaleout.WORKER_TIMEOUT` seconds; ``Result.seconds`` is then
        the tracing time summed over the workers (worker-seconds, not wall time).
    task_readings
        With ``workers``: readings per Dask task; default (``None``) from the measured
        ray rate (:func:`virtspec_mi.scaleout.task_size`).
    **settings
        As for :func:`measure` (one value for the whole sweep); ``wavelengths`` must be
        distinct. With ``bound="two-stage"`` each reading is sized by its own pilot, all
        of them batched.
    target
        A derived quantity (as for :func:`measure`) certified at every θi: a
        :class:`~virtspec_mi.applications.derived.result.DerivedSweep`, each angle at δ
        (``parameters``, ``checkpoint``, ``out`` and ``workers`` are not taken with it).

    References
    ----------
    Baranoski et al. (2001), eq. (23), Fig. 5.
    """

    if target is not None:
        given = [name for name, value in (("parameters", parameters), ("checkpoint", checkpoint), ("out", out),
                                          ("workers", workers)) if value]
        if given:
            raise ValueError(f"{', '.join(given)}: not taken with a target (each angle is one vm.measure(target=...))")
        from virtspec_mi.applications.derived.result import DerivedSweep

        scene = loaded(scene, defines)
        resolved, = resolve("sweep", {k: v for k, v in settings.items() if k not in ("wavelengths", "mu", "rays",
                                                                                    "bound", "pilot_rays",
                                                                                    "pilot_delta", "joint")},
                            _scene_options(scene.bench, Settings))
        angles = _angles(resolved, theta_i, "a sweep")
        return DerivedSweep(tuple(float(t) for t in angles), tuple(
            _measure_target(scene, None, target, {**settings, "theta_i": float(t)}) for t in angles))
    return _reading(commanding("sweep").name, "sweep", "a sweep", loaded(scene, defines), settings, theta_i=theta_i,
                    parameters=parameters, points=points, checkpoint=checkpoint, out=out, progress=progress,
                    workers=workers, task_readings=task_readings)


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
    bench = scene.bench
    space = parameter_space(bench, parameters or {}, points=true_or_false("points")(points))
    angles = _angles(settings, theta_i, what)
    if len(np.unique(settings.wavelengths)) != len(settings.wavelengths):
        raise ValueError(f"wavelengths of {what} must be distinct (got repeated values)")
    instrument = _instrument(name, scene)
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


def _instrument(name: str, scene: LoadedScene) -> Any:
    """The instrument ``name`` of the registry for ``scene``: its fingerprint and its source recorded."""

    return INSTRUMENTS[name](scene.fingerprint, scene.source)


@contextmanager
def _naming(checkpoint: Path | None) -> Iterator[None]:
    """An interrupt (``KeyboardInterrupt``: :mod:`virtspec_mi.interrupts`) raised inside names ``checkpoint``."""

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
    from virtspec_mi import scaleout  # imports dask.distributed: only when it is used

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


def _angles(settings: Settings, theta_i: Any, what: str) -> np.ndarray:
    """The incidence angles of a call: ``theta_i`` as given, else the settings'; distinct."""

    angles = np.array(parse_theta_i(settings.theta_i if theta_i is None else theta_i))
    if len(np.unique(angles)) != len(angles):
        raise ValueError(f"theta_i of {what} must be distinct (got repeated values)")
    return angles


def _scene_options(bench: Bench, kind: type) -> Any:
    """The options of class ``kind`` that the scene's integrator holds, else the defaults."""

    held = getattr(bench.integrator, "options", {}) if bench.integrator is not None else {}
    return held.get(kind) or kind()


measure.__signature__ = keywords(measure, Settings)  # type: ignore[attr-defined]
sweep.__signature__ = keywords(sweep, Settings)  # type: ignore[attr-defined]


def gonio(scene: Any, *, theta_i: Any = None, parameters: dict[str, Any] | None = None, points: bool = False,
          defines: dict[str, Any] | None = None, checkpoint: str | os.PathLike | None = None,
          out: str | os.PathLike | None = None, progress: bool | None = None, workers: Any = None,
          task_readings: int | None = None, **options: Any) -> Any:
    """
    A certified goniophotometer reading of ``scene``: the spectrophotometer's readings
    over every (wavelength, θi, specimen parameter point), with every escaping ray also
    binned by its outgoing direction (θo, φo) in the specimen frame
    (:class:`~virtspec_mi.instruments.goniophotometer.result.GonioResult`), keyed as a sweep's:
    reading k traces the global rays [k·N, k·N + N) (counts depend on (seed, k) only), so
    it resumes from a checkpoint and runs on Dask workers with the same counts.

    Parameters
    ----------
    scene
        XML path, scene dict or loaded ``mi.Scene`` (as for :func:`measure`).
    theta_i, parameters, points, defines, checkpoint, out, progress, workers, task_readings
        As for :func:`sweep`: incidence angles (default: the scene's θi, or 0), specimen
        parameters (a grid, or explicit ``points``), the XML scene's ``$name`` values, the
        checkpoint (default ``OUT.partial.json`` with ``out``), the result file (``.nc``,
        ``.csv``, ``.json`` or ``.zarr``, written atomically when the reading completes,
        checked before any tracing), the progress bar and the Dask workers.
    **options
        The goniophotometer options (:class:`~virtspec_mi.instruments.goniophotometer.GonioOptions`:
        ``theta_o_bins``, ``phi_o_bins``, ``binning``, ``fold_phi``, ``hemispheres``,
        ``guarantee``, ``relative_tolerance``, ``brdf_floor``) and every setting of
        :class:`~virtspec_mi.settings.Settings`; one left ``None`` comes from the scene's
        ``spectrophotometer`` integrator, else from its default. Without ``rays``, N is
        sized by ``guarantee`` at ``mu`` and ``delta`` over the K bins (a row of
        :data:`virtspec_mi.budgets.rules.GUARANTEES`); ``bound="two-stage"`` sizes each
        reading from its pilot where the guarantee allows it (``union``, ``union-exact``),
        else it is refused with the reason.

    References
    ----------
    Baranoski et al. (2001), eq. (23), Sect. 6; :mod:`virtspec_mi.budgets.bins`.
    """

    return _reading(commanding("gonio").name, "gonio", "a goniophotometer reading", loaded(scene, defines), options,
                    theta_i=theta_i, parameters=parameters, points=points, checkpoint=checkpoint, out=out,
                    progress=progress, workers=workers, task_readings=task_readings)


gonio.__signature__ = keywords(gonio, commanding("gonio").options, Settings)  # type: ignore[attr-defined]


def read_gonio(path: str | os.PathLike) -> Any:
    """A goniophotometer reading from a file written by its ``write`` (any kind: :func:`read_result`)."""

    return commanding("gonio").result.read(path)


def read_result(path: str | os.PathLike) -> Any:
    """
    The result in a file, whatever its kind — a hemispherical reading or sweep, a
    goniophotometer reading, a sphere reading — by its format tag
    (:func:`virtspec_mi.results.kinds.read_result`), an instrument's own kind too (the
    registry is loaded: :data:`virtspec_mi.instruments.INSTRUMENTS`).
    """

    from virtspec_mi.results.kinds import read_result as read_any

    return read_any(path)


def sphere_measure(scene: Any, *, theta_i: Any = None, parameters: dict[str, Any] | None = None, points: bool = False,
                   defines: dict[str, Any] | None = None, checkpoint: str | os.PathLike | None = None,
                   out: str | os.PathLike | None = None, progress: bool | None = None, workers: Any = None,
                   task_readings: int | None = None, **settings: Any) -> Any:
    """
    Read the specimen of ``scene`` as a physical integrating sphere would: a
    :class:`~virtspec_mi.instruments.sphere.result.SphereResult` over wavelength (and θi and specimen
    parameters when several are given): the reading ρ_std·p_sample/p_standard with its
    certified interval, the hemispherical reading of the same rays, the instrument error,
    every count of both configurations. Keyed as a sweep's (reading k of a configuration
    traces the global rays [k·N, k·N + N), the same rays in both): it resumes from a
    checkpoint and runs on Dask workers with the same counts.

    Parameters
    ----------
    scene
        XML path, scene dict or ``mi.Scene`` with ``emitter`` and ``specimen`` disks; its
        ``integrating_sphere`` integrator (if any) gives the sphere and the settings.
    theta_i, parameters, points, defines, checkpoint, out, progress, workers, task_readings
        As for :func:`sweep` (every θi must bring the beam in through the entrance port).
    **settings
        Any setting of :class:`~virtspec_mi.settings.Settings` and any option of
        :class:`~virtspec_mi.instruments.sphere.SphereOptions` (``measurement``,
        ``specular``, ``method``, ``standard``, ``max_bounces``, and ``sphere``: a
        :class:`~virtspec_mi.instruments.sphere.geometry.Sphere` that overrides the scene's); ``None``
        keeps the scene's value. ``bound="two-stage"`` sizes each configuration's reading
        from its pilot's detector fraction (each at δ/2).

    References
    ----------
    Baranoski et al. (2001), eqs. (2), (23); Goebel (1967).
    """

    return _reading(commanding("sphere_measure").name, "sphere_measure", "a sphere reading", loaded(scene, defines),
                    settings, theta_i=theta_i, parameters=parameters, points=points, checkpoint=checkpoint, out=out,
                    progress=progress, workers=workers, task_readings=task_readings)


sphere_measure.__signature__ = keywords(  # type: ignore[attr-defined]
    sphere_measure, Settings, commanding("sphere_measure").options)


def take(instrument: str, scene: Any, *, theta_i: Any = None, parameters: dict[str, Any] | None = None,
         points: bool = False, defines: dict[str, Any] | None = None, checkpoint: str | os.PathLike | None = None,
         out: str | os.PathLike | None = None, progress: bool | None = None, workers: Any = None,
         task_readings: int | None = None, **options: Any) -> Any:
    """
    A reading of ``scene`` with any instrument of the registry, by its name
    (:data:`virtspec_mi.instruments.INSTRUMENTS`: ``hemispherical``, ``goniophotometer``,
    ``sphere``, ``gloss``, and any instrument added there): the instrument's plan traced
    by the engine as a sweep's is (keyed readings: counts depend on (seed, reading) only;
    resumable from a checkpoint; on Dask workers with the same counts), then its result.
    :func:`sweep`, :func:`gonio` and :func:`sphere_measure` are this call for their
    instruments, with their own documentation.

    Parameters
    ----------
    instrument
        The instrument's name in the registry.
    scene, theta_i, parameters, points, defines, checkpoint, out, progress, workers, task_readings
        As for :func:`sweep`; ``out`` needs a result kind with files (not a gloss reading).
    **options
        Every setting of :class:`~virtspec_mi.settings.Settings` and every option the
        instrument declares (its ``options`` class); ``None`` keeps the scene's value.

    References
    ----------
    Baranoski et al. (2001), eq. (23); Dubovik et al. (2021), Eradiate's ``Experiment``
    (init, process, postprocess), https://eradiate.readthedocs.io.
    """

    if not isinstance(instrument, str) or instrument not in INSTRUMENTS:
        raise ValueError(f"instrument must be one of {', '.join(INSTRUMENTS)} (got {instrument!r})")
    return _reading(instrument, "take", f"a {instrument} reading", loaded(scene, defines), options, theta_i=theta_i,
                    parameters=parameters, points=points, checkpoint=checkpoint, out=out, progress=progress,
                    workers=workers, task_readings=task_readings)


def _reading(name: str, caller: str, what: str, scene: LoadedScene, given: dict[str, Any], **run: Any) -> Any:
    """
    The keyed reading (:func:`_keyed`) of the instrument ``name`` of ``scene`` (loaded once,
    where it entered the API) with the keywords ``given`` of ``caller`` over the scene's
    settings and the instrument's options.
    """

    declared = INSTRUMENTS[name].options
    settings, *options = resolve(caller, given, _scene_options(scene.bench, Settings),
                                 *(() if declared is None else (_scene_options(scene.bench, declared),)))
    return _keyed(name, what, scene, settings, options[0] if options else None, **run)


def aliases() -> dict[str, str]:
    """
    The generated API functions: for each subcommand of an instrument of the registry that
    names no function of its own (:attr:`~virtspec_mi.instruments.command.Command.function`,
    e.g. the gloss meter's ``gloss``), the subcommand's name → its instrument's name.
    """

    return {command.name: name for name, instrument in INSTRUMENTS.items() for command in instrument.commands
            if command.function is None and command.name not in __all__}


def alias(name: str) -> Any:
    """
    The API function ``name`` of :func:`aliases`: :func:`take` with its instrument, its
    signature the settings and the instrument's options (``vm.gloss(scene, cone=2, …)`` is
    ``vm.take("gloss", scene, cone=2, …)``), its docstring the subcommand's description.
    """

    instrument = INSTRUMENTS[aliases()[name]]
    command = next(c for c in instrument.commands if c.name == name)

    def reading(scene: Any, *, theta_i: Any = None, parameters: dict[str, Any] | None = None, points: bool = False,
                defines: dict[str, Any] | None = None, checkpoint: str | os.PathLike | None = None,
                out: str | os.PathLike | None = None, progress: bool | None = None, workers: Any = None,
                task_readings: int | None = None, **options: Any) -> Any:
        return take(instrument.name, scene, theta_i=theta_i, parameters=parameters, points=points, defines=defines,
                    checkpoint=checkpoint, out=out, progress=progress, workers=workers, task_readings=task_readings,
                    **options)

    reading.__name__ = reading.__qualname__ = name
    reading.__doc__ = (f"{command.description}\n\nGenerated from the registry: ``take({instrument.name!r}, scene, "
                       "...)`` (:func:`virtspec_mi.take`; keywords as for :func:`virtspec_mi.sweep`, and the "
                       "instrument's options).")
    kinds = (Settings,) if instrument.options is None else (Settings, instrument.options)
    reading.__signature__ = keywords(reading, *kinds)  # type: ignore[attr-defined]
    return reading
