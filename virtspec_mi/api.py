"""
The measurement API: :func:`measure`, :func:`sweep`, :func:`read_result`, :func:`fluctuation`
===========================================================================================

:func:`measure` takes a scene (XML path, dict or ``mi.Scene``), resolves the settings
(explicit keywords, then the scene's ``spectrophotometer`` integrator, then the
defaults of :class:`~virtspec_mi.settings.Settings`), sizes each reading with the ray
budget and returns a :class:`~virtspec_mi.results.hemispherical.Result` with the dim ``wavelength``:
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

Both take every setting of :class:`~virtspec_mi.settings.Settings` as a keyword (their
signatures are derived from it); a bad value raises ``ValueError`` naming the setting
and its allowed range.

References
----------
Baranoski et al. (2001), eqs. (2), (23), (24); Figs. 5 and 6.
"""

from __future__ import annotations

import inspect
import os
from contextlib import ExitStack, contextmanager
from dataclasses import replace
from pathlib import Path
from typing import Any, Iterator

import numpy as np

from virtspec_mi.engine.checkpoint import checkpoint_for, claim, kept_in, remove
from virtspec_mi.files import WriteError
from virtspec_mi.checks import parse_theta_i
from virtspec_mi.engine.readings import gonio_reading, in_process_runner, measure_reading, run
from virtspec_mi.geometry.bins import GONIO_PARAMETERS
from virtspec_mi.results.goniophotometer import GonioResult
from virtspec_mi.engine.bench import Bench
from virtspec_mi.engine.parameters import apply_point, current_values, parameter_space
from virtspec_mi.results.hemispherical import Result
from virtspec_mi.results.io import check_output
from virtspec_mi.scene import find_bench, scene_fingerprint
from virtspec_mi.settings import Settings, settings_keywords, with_settings
from virtspec_mi.geometry.sphere import SPHERE_SETTING_NAMES, Sphere, SphereSettings
from virtspec_mi.instruments.sphere import measure_sphere
from virtspec_mi.results.sphere import SphereResult
from virtspec_mi.results.zarr import SUFFIX as ZARR_SUFFIX
from virtspec_mi.results.zarr import ZarrTable

__all__ = ["measure", "sweep", "gonio", "read_result", "read_gonio", "fluctuation", "sphere_measure"]


def measure(scene: Any, *, parameters: dict[str, Any] | None = None, defines: dict[str, Any] | None = None,
            progress: bool | None = None, **settings: Any) -> Result:
    """
    Measure the specimen of ``scene`` and return a certified :class:`~virtspec_mi.results.hemispherical.Result`
    over wavelength (θi a scalar label).

    Parameters
    ----------
    scene
        XML path, scene dict or loaded ``mi.Scene`` with ``emitter`` and ``specimen`` disks.
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

    References
    ----------
    Baranoski et al. (2001), eqs. (2), (23).
    """

    instrument = find_bench(scene, defines)
    settings = with_settings(_scene_settings(instrument), settings, "measure")
    space = parameter_space(instrument, parameters or {})
    if space is not None and space.size != 1:
        raise ValueError("measure takes one value per parameter (a sweep takes several: use sweep)")
    if space is None:
        result = measure_reading(instrument, settings, progress=progress)
    else:
        original = current_values(instrument, space.keys)
        try:
            apply_point(instrument, space.keys, space.point(0))
            result = measure_reading(instrument, settings, progress=progress)
        finally:
            apply_point(instrument, space.keys, original)
        result = replace(result, parameters=space.as_dict(),
                         coords={**result.coords, **{n: np.asarray(v[0]) for n, v in space.coords().items()}})
    result.warn_if_uncertified(stacklevel=3)
    return result


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
    **settings: Any,
) -> Result:
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

    References
    ----------
    Baranoski et al. (2001), eq. (23), Fig. 5.
    """

    checkpoint, out = _file_path(checkpoint, "checkpoint"), _file_path(out, "out")
    if out is not None:
        check_output(out)
        checkpoint = checkpoint if checkpoint is not None else checkpoint_for(out)
    instrument = find_bench(scene, defines)
    base = with_settings(_scene_settings(instrument), settings, "sweep")
    space = parameter_space(instrument, parameters or {}, points=points)
    angles = np.array(parse_theta_i(base.theta_i if theta_i is None else theta_i))
    resolved = base.updated(theta_i=float(angles[0]))
    for name, values in (("theta_i", angles), ("wavelengths", np.array(resolved.wavelengths))):
        if len(np.unique(values)) != len(values):
            raise ValueError(f"{name} of a sweep must be distinct (got repeated values)")
    fingerprint = scene_fingerprint(scene, instrument, defines)
    with ExitStack() as held:
        if checkpoint is not None:  # one run per checkpoint, writable: checked before any cluster or tracing
            held.enter_context(claim(checkpoint))
        runner = held.enter_context(_runner(scene, defines, workers, task_readings, fingerprint, resolved, angles,
                                            space))
        if out is not None and out.suffix.lower() == ZARR_SUFFIX:  # the store fills as the batches finish
            identity = {"scene": fingerprint, **resolved.as_dict(), "theta_i": [float(t) for t in angles],
                        **({} if space is None else {"parameters": space.as_dict()})}
            table = ZarrTable(out, resolved.wavelengths, angles, identity, pilot=resolved.adaptive, parameters=space)
            runner = table.stream(runner or in_process_runner(instrument, resolved, theta_i=angles, parameters=space))
        result = run(instrument, resolved, angles, keyed=True, scene=fingerprint, checkpoint=checkpoint,
                     progress=progress, parameters=space, runner=runner)
        if checkpoint is not None:
            if out is not None:
                _write(result, out, checkpoint)
            remove(checkpoint)  # the readings are safe: returned, and written to out when given
    result.warn_if_uncertified(stacklevel=3)
    return result


@contextmanager
def _runner(scene: Any, defines: dict[str, Any] | None, workers: Any, task_readings: int | None, fingerprint: str,
            settings: Settings, angles: np.ndarray, space: Any) -> Iterator[Any]:
    """``None`` (the engine's in-process default) or a Dask runner on ``workers``, held for the sweep."""

    if workers is None:
        if task_readings is not None:
            raise ValueError(f"task_readings needs workers (got task_readings={task_readings!r}, workers=None)")
        yield None
        return
    from virtspec_mi import scaleout  # imports dask.distributed: only when it is used

    scaleout.check_workers(workers)
    scaleout.check_task_readings(task_readings)
    scaleout.portable_scene(scene)  # refused before any cluster starts
    with scaleout.connect(workers) as client:
        yield scaleout.dask_runner(client, scene, fingerprint, settings, task_readings, defines=defines,
                                   theta_i=angles, parameters=space)


def _file_path(value: Any, name: str) -> Path | None:
    """``value`` (a file path or ``None``) as a ``Path``; ``ValueError`` naming ``name`` otherwise."""

    if value is None:
        return None
    if not isinstance(value, (str, os.PathLike)):
        raise ValueError(f"{name} must be a file path (str or os.PathLike) or None (got {type(value).__name__} "
                         f"{value!r})")
    return Path(value)


def _write(result: Result, out: Path, checkpoint: Path) -> None:
    """Write ``result`` to ``out``; if that fails the error says where the finished readings are kept."""

    try:
        result.write(out)
    except WriteError as error:  # names out and the cause, carries the result; the checkpoint's state added
        raise error.keeping(kept_in(checkpoint), result) from None


measure.__signature__ = settings_keywords(measure)  # type: ignore[attr-defined]
sweep.__signature__ = settings_keywords(sweep)  # type: ignore[attr-defined]


def gonio(scene: Any, *, theta_i: Any = None, out: str | os.PathLike | None = None, **options: Any) -> GonioResult:
    """
    A certified goniophotometer reading of ``scene``: the spectrophotometer's readings
    over every (wavelength, θi), with every escaping ray also binned by its outgoing
    direction (θo, φo) in the specimen frame (:class:`~virtspec_mi.results.goniophotometer.GonioResult`).

    Parameters
    ----------
    scene
        XML path, scene dict or loaded ``mi.Scene`` (as for :func:`measure`).
    theta_i
        Incidence angles in degrees (as for :func:`sweep`); default: the scene's θi (or 0).
    out
        File to write (``.nc``, ``.csv`` or ``.json``), checked before any tracing.
    **options
        The goniophotometer parameters (:data:`~virtspec_mi.geometry.bins.GONIO_PARAMETERS`:
        ``theta_o_bins``, ``phi_o_bins``, ``binning``, ``fold_phi``, ``hemispheres``,
        ``guarantee``, ``relative_tolerance``, ``brdf_floor``) and every setting of
        :class:`~virtspec_mi.settings.Settings` (a fixed budget); one left ``None`` comes
        from the scene's ``spectrophotometer`` integrator, else from its default. Without
        ``rays``, N is sized by ``guarantee`` at ``mu`` and ``delta`` over the K bins
        (:func:`virtspec_mi.budgets.rules.gonio_rays`).

    References
    ----------
    Baranoski et al. (2001), eq. (23), Sect. 6; :mod:`virtspec_mi.budgets.bins`.
    """

    out = check_output(_file_path(out, "out")) if out is not None else None
    instrument = find_bench(scene)
    given = {name: options.pop(name) for name in list(options) if name in GONIO_PARAMETERS}
    scene_gonio = instrument.integrator.gonio if instrument.integrator is not None else {}
    spec = {**scene_gonio, **{name: value for name, value in given.items() if value is not None}}
    base = with_settings(_scene_settings(instrument), options, "gonio")
    angles = np.array(parse_theta_i(base.theta_i if theta_i is None else theta_i))
    if len(np.unique(angles)) != len(angles):
        raise ValueError("theta_i of a goniophotometer reading must be distinct (got repeated values)")
    if base.adaptive:
        raise ValueError("bound must be a fixed budget for a goniophotometer reading (hoeffding, chebyshev, "
                         "exact, or rays given); N is sized by guarantee= over the bins")
    result = gonio_reading(instrument, base, spec, angles, scene=scene_fingerprint(scene, instrument))
    result.result.warn_if_uncertified(stacklevel=3)
    if out is not None:
        result.write(out)
    return result


def _gonio_signature() -> inspect.Signature:
    """:func:`gonio`'s signature: its own parameters, the goniophotometer parameters, then the settings."""

    own = settings_keywords(gonio)
    parameters = list(own.parameters.values())
    extra = [inspect.Parameter(name, inspect.Parameter.KEYWORD_ONLY, default=None) for name in GONIO_PARAMETERS]
    return own.replace(parameters=[*parameters[:3], *extra, *parameters[3:]])


gonio.__signature__ = _gonio_signature()  # type: ignore[attr-defined]


def read_gonio(path: str | os.PathLike) -> GonioResult:
    """A goniophotometer reading from a file written by its ``write`` (any kind: :func:`read_result`)."""

    return GonioResult.read(path)


def read_result(path: str | os.PathLike) -> Any:
    """
    The result in a file, whatever its kind — a hemispherical reading or sweep, a
    goniophotometer reading, a sphere reading — by its format tag
    (:func:`virtspec_mi.results.kinds.read_result`).
    """

    from virtspec_mi.results.kinds import read_result as read_any

    return read_any(path)


def fluctuation(a: Result | np.ndarray, b: Result | np.ndarray, quantity: str = "reflectance") -> float:
    """
    Average magnitude of the fluctuations between two sweeps, eq. (24):

        Δ = Σᵢ |ρᵢ^(N_j) − ρᵢ^(N_{j−1})| / n

    over the n readings of the sweeps (all their (wavelength, θi) pairs), for
    ``quantity`` (reflectance by default). ``a`` and ``b`` are results over the same grid
    (typically at successive ray densities N_{j−1} and N_j), or arrays of one shape.

    References
    ----------
    Baranoski et al. (2001), eq. (24), Fig. 6a.
    """

    if isinstance(a, Result) and isinstance(b, Result):
        for name in ("wavelengths", "theta_i"):
            if not np.array_equal(getattr(a, name), getattr(b, name)):
                raise ValueError(f"fluctuation needs sweeps over the same {name} (they differ)")
        a, b = a.quantity(quantity), b.quantity(quantity)
    a, b = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    if a.shape != b.shape or a.size == 0:
        raise ValueError(f"fluctuation needs two non-empty arrays of one shape (got {a.shape} and {b.shape})")
    return float(np.mean(np.abs(a - b)))


def sphere_measure(scene: Any, *, sphere: Sphere | None = None, **settings: Any) -> SphereResult:
    """
    Read the specimen of ``scene`` as a physical integrating sphere would: a
    :class:`~virtspec_mi.results.sphere.SphereResult` over wavelength (the reading
    ρ_std·p_sample/p_standard with its certified interval, the hemispherical reading of
    the same rays, the instrument error, every count of both configurations).

    Parameters
    ----------
    scene
        XML path, scene dict or ``mi.Scene`` with ``emitter`` and ``specimen`` disks; its
        ``integrating_sphere`` integrator (if any) gives the sphere and the settings.
    sphere
        A :class:`~virtspec_mi.geometry.sphere.Sphere` (overrides the scene's).
    **settings
        Any setting of :class:`~virtspec_mi.settings.Settings` and of
        :class:`~virtspec_mi.geometry.sphere.SphereSettings` (``measurement``, ``specular``,
        ``method``, ``standard``, ``max_bounces``); ``None`` keeps the scene's value.

    References
    ----------
    Baranoski et al. (2001), eqs. (2), (23); Goebel (1967).
    """

    instrument = find_bench(scene)
    integrator = instrument.integrator
    own = {k: settings.pop(k) for k in list(settings) if k in SPHERE_SETTING_NAMES}
    base = with_settings(_scene_settings(instrument), settings, "sphere_measure")
    options = getattr(integrator, "sphere_settings", None) or SphereSettings()
    options = options.updated(**own)
    sphere = sphere if sphere is not None else getattr(integrator, "sphere", None)
    if not isinstance(sphere, Sphere):
        raise ValueError("sphere_measure needs a sphere: an 'integrating_sphere' integrator in the scene or "
                         "sphere=Sphere(...)")
    fingerprint = scene_fingerprint(scene, instrument)
    return measure_sphere(instrument, sphere, base, options, scene=fingerprint)


def _sphere_signature() -> Any:
    """``sphere_measure``'s signature: the settings, then the sphere settings, as keywords."""

    import inspect

    signature = settings_keywords(sphere_measure)
    extra = [inspect.Parameter(name, inspect.Parameter.KEYWORD_ONLY, default=None) for name in SPHERE_SETTING_NAMES]
    return signature.replace(parameters=[*signature.parameters.values(), *extra])


sphere_measure.__signature__ = _sphere_signature()  # type: ignore[attr-defined]


def _scene_settings(instrument: Bench) -> Settings:
    """The settings of the scene's ``spectrophotometer`` integrator, else the defaults."""

    return instrument.integrator.settings if instrument.integrator is not None else Settings()
