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
``workers``, ``task_readings``: declared once, :class:`~virtspec_mi.runtime.reading.RunOptions`,
and each function's signature built from them). Every function here is thin: it parses its keywords at
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
from :mod:`virtspec_mi.base.checks`), names a reading's quantities (:data:`QUANTITIES`) and
the checkpoint a call with ``out`` keeps (:func:`checkpoint_for`: ``OUT.partial.json``,
named when an interrupt comes before the run names it).

References
----------
Baranoski et al. (2001), eqs. (2), (23), (24); Figs. 5 and 6.
"""

from __future__ import annotations

import inspect
import os
from typing import Any

from virtspec_mi.base.checks import parse_theta_i, parse_values, parse_wavelengths
from virtspec_mi.engine.checkpoint import checkpoint_for
from virtspec_mi.engine.parameters import parameter_space
from virtspec_mi.instruments import INSTRUMENTS, commanding
from virtspec_mi.kernel.counts import QUANTITIES
from virtspec_mi.results.readings import fluctuation
from virtspec_mi.runtime.reading import RunOptions, instrument_for, keyed_reading, scene_options
from virtspec_mi.runtime.scene import LoadedScene, loaded
from virtspec_mi.settings import Settings, resolve
from virtspec_mi.settings import keywords as signature

__all__ = ["measure", "sweep", "gonio", "read_result", "read_gonio", "fluctuation", "sphere_measure", "take", "alias",
           "aliases",
           # what the command line takes from the layers below (see the module docstring)
           "parse_theta_i", "parse_wavelengths", "parse_values", "QUANTITIES", "checkpoint_for"]


_MEASURE_RUN: tuple[str, ...] = ("parameters", "defines", "progress")
"""The run keywords :func:`measure` takes (one reading: θi is a setting; no checkpoint, file or workers)."""


def measure(scene: Any, *, target: Any = None, **keywords: Any) -> Any:
    """
    Measure the specimen of ``scene`` and return a certified :class:`~virtspec_mi.results.readings.Result`
    over wavelength (θi a scalar label).

    Parameters
    ----------
    scene
        XML path, scene dict or loaded ``mi.Scene`` with ``emitter`` and ``specimen`` disks;
        or a :class:`~virtspec_mi.runtime.scene.LoadedScene` (:func:`virtspec_mi.runtime.scene.loaded`: its
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
        returns a :class:`~virtspec_mi.applications.targets.result.DerivedResult`
        (:mod:`virtspec_mi.applications.targets`). ``wavelengths``, ``mu``, ``rays``,
        ``pilot_rays``, ``pilot_delta`` and ``joint`` are then the target's to
        decide (giving one is an error); ``parameters`` are not taken. ``bound`` is then the
        target's certificate: ``"betting"`` (sequential batches, a betting confidence
        sequence, :mod:`virtspec_mi.applications.targets.sequential`), ``"two-stage"``
        (a linear target's wavelengths pooled into one proportion, the exact two-stage
        rule, :mod:`virtspec_mi.applications.targets.pooled`), ``"hoeffding"`` (one batch
        sized by Hoeffding's bound) or ``"auto"`` (default: two-stage for a linear target,
        betting for the others).

    References
    ----------
    Baranoski et al. (2001), eqs. (2), (23).
    """

    run, settings = RunOptions.split(keywords, only=_MEASURE_RUN)
    parameters, progress = run["parameters"], run["progress"]
    scene = loaded(scene, run["defines"])
    bench = scene.bench
    if target is not None:
        return _measure_target(scene, parameters, target, {**settings, "progress": progress})
    settings, = resolve("measure", settings, scene_options(bench, Settings))
    space = parameter_space(bench, parameters or {})
    if space is not None and space.size != 1:
        raise ValueError("measure takes one value per parameter (a sweep takes several: use sweep)")
    instrument = instrument_for(commanding("measure").name, scene)
    result = instrument.run(bench, settings, parameters=space, progress=progress)
    result = result.squeeze("theta_i", *([] if space is None else space.dims))  # one reading: scalar labels
    instrument.warn_if_uncertified(result)
    return result


def _measure_target(scene: LoadedScene, parameters: Any, target: Any, settings: dict[str, Any]) -> Any:
    """:func:`measure` of a derived quantity (:func:`virtspec_mi.applications.targets.sequential.measure_target`)."""

    from virtspec_mi.applications.targets.sequential import measure_target

    return measure_target(scene, parameters, target, settings)


def sweep(scene: Any, *, target: Any = None, **keywords: Any) -> Any:
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
        Where the readings are traced (:mod:`virtspec_mi.runtime.scaleout`): ``None`` (default)
        in this process; an int N on a local Dask cluster of N worker processes started
        for the sweep; a scheduler address (``"tcp://host:8786"``) or a
        ``distributed.Client`` on that cluster. The counts are the same in every case;
        ``scene`` must then be an XML path (readable by every worker) or a dict. A
        cluster without workers raises ``TimeoutError`` after
        :data:`~virtspec_mi.runtime.scaleout.WORKER_TIMEOUT` seconds; ``Result.seconds`` is then
        the tracing time summed over the workers (worker-seconds, not wall time).
    task_readings
        With ``workers``: readings per Dask task; default (``None``) from the measured
        ray rate (:func:`virtspec_mi.runtime.scaleout.task_size`).
    **settings
        As for :func:`measure` (one value for the whole sweep); ``wavelengths`` must be
        distinct. With ``bound="two-stage"`` each reading is sized by its own pilot, all
        of them batched.
    target
        A derived quantity (as for :func:`measure`) certified at every θi: a
        :class:`~virtspec_mi.applications.targets.result.DerivedSweep`, each angle at δ
        (``parameters`` and ``out`` are not taken with it; ``checkpoint`` keeps every
        angle's batches, :mod:`virtspec_mi.applications.targets.resume`; ``workers`` runs
        each angle on a Dask worker).

    References
    ----------
    Baranoski et al. (2001), eq. (23), Fig. 5.
    """

    run, settings = RunOptions.split(keywords)
    defines = run.pop("defines")
    if target is not None:
        given = [name for name in ("parameters", "out") if run[name]]
        if given:
            raise ValueError(f"{', '.join(given)}: not taken with a target (each angle is one vm.measure(target=...))")
        from virtspec_mi.applications.targets.sweep import target_sweep

        return target_sweep(loaded(scene, defines), target, settings, run["theta_i"], run["checkpoint"], run["workers"],
                            run["progress"])
    return keyed_reading(commanding("sweep").name, "sweep", "a sweep", loaded(scene, defines), settings, **run)


# the signatures: the run keywords (RunOptions, declared once), the settings and the instrument's options
measure.__signature__ = signature(measure, Settings, RunOptions,  # type: ignore[attr-defined]
                                  exclude=tuple(set(RunOptions.names()) - {*_MEASURE_RUN, "theta_i"}))
sweep.__signature__ = signature(sweep, RunOptions, Settings)  # type: ignore[attr-defined]


def gonio(scene: Any, **keywords: Any) -> Any:
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

    return _keyed("gonio", "a goniophotometer reading", scene, keywords)


gonio.__signature__ = signature(gonio, RunOptions, commanding("gonio").options, Settings)  # type: ignore[attr-defined]


def read_gonio(path: str | os.PathLike) -> Any:
    """A goniophotometer reading from a file written by its ``write`` (any kind: :func:`read_result`)."""

    return commanding("gonio").result.read(path)


def read_result(path: str | os.PathLike) -> Any:
    """
    The result in a file, whatever its kind — a hemispherical reading or sweep, a
    goniophotometer reading, a sphere reading, an instrument's own kind (the registry is
    loaded: :data:`virtspec_mi.instruments.INSTRUMENTS`), and an application's: a certified
    target, a fit, an albedo table, Klems matrices, a comparison (the kinds of every row of
    :data:`virtspec_mi.applications.APPLICATIONS`) — by its format tag
    (:func:`virtspec_mi.results.kinds.read_result`), in every format its kind writes (an
    export such as a Klems XML file through the result file it accompanies).
    """

    from virtspec_mi.applications import APPLICATIONS  # noqa: F401  (every application's result kinds register)
    from virtspec_mi.results.kinds import read_result as read_any

    return read_any(path)


def sphere_measure(scene: Any, **keywords: Any) -> Any:
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

    return _keyed("sphere_measure", "a sphere reading", scene, keywords)


sphere_measure.__signature__ = signature(  # type: ignore[attr-defined]
    sphere_measure, RunOptions, Settings, commanding("sphere_measure").options)


def take(instrument: str, scene: Any, **keywords: Any) -> Any:
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
    return _keyed("take", f"a {instrument} reading", scene, keywords, instrument)


take.__signature__ = signature(take, RunOptions).replace(parameters=[  # type: ignore[attr-defined]
    *signature(take, RunOptions).parameters.values(), inspect.Parameter("options", inspect.Parameter.VAR_KEYWORD)])


def _keyed(word: str, what: str, scene: Any, given: dict[str, Any], instrument: str | None = None) -> Any:
    """
    The keyed reading of the API function ``word`` (its instrument: ``instrument``, or the one
    with that command): the run keywords of ``given`` taken apart from its settings and options.
    """

    run, options = RunOptions.split(given)
    defines = run.pop("defines")
    return keyed_reading(instrument or commanding(word).name, word, what, loaded(scene, defines), options, **run)


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

    def reading(scene: Any, **keywords: Any) -> Any:
        return take(instrument.name, scene, **keywords)

    reading.__name__ = reading.__qualname__ = name
    reading.__doc__ = (f"{command.description}\n\nGenerated from the registry: ``take({instrument.name!r}, scene, "
                       "...)`` (:func:`virtspec_mi.take`; keywords as for :func:`virtspec_mi.sweep`, and the "
                       "instrument's options).")
    kinds = (Settings,) if instrument.options is None else (Settings, instrument.options)
    reading.__signature__ = signature(reading, RunOptions, *kinds)  # type: ignore[attr-defined]
    return reading
