"""
The measurement API: :func:`measure`, :func:`sweep`, :func:`read_result`, :func:`fluctuation`
===========================================================================================

:func:`measure` takes a scene (XML path, dict or ``mi.Scene``), resolves the settings
(explicit keywords, then the scene's ``spectrophotometer`` integrator, then the
defaults of :class:`~virtspec_mi.settings.Settings`), sizes each reading with the ray
budget and returns a :class:`~virtspec_mi.result.Result` with the dim ``wavelength``:
reflectance ρ = m/N (eq. 2), transmittance τ and absorptance α = 1 − ρ − τ per
wavelength, with the exact counts behind them and the certificate they give.

:func:`sweep` measures a grid (wavelength × θi) at one φi — the paper's Fig. 5 or a
spectrum — and returns the same type with dims ``(wavelength, theta_i)``. Its reading
k (k = i_θ·n_λ + i_λ) owns the global ray indices [k·stride, k·stride + N): its counts
depend on (seed, k) only, which makes a sweep resumable from a checkpoint and its
readings independent of how they are batched (:func:`virtspec_mi.engine.run`).

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
from pathlib import Path
from typing import Any

import numpy as np

from virtspec_mi.checkpoint import checkpoint_for, claim, remove
from virtspec_mi.checks import parse_theta_i
from virtspec_mi.engine import gonio_reading, measure_reading, run
from virtspec_mi.gonio_bins import GONIO_PARAMETERS
from virtspec_mi.gonio_result import GonioResult
from virtspec_mi.instrument import Instrument
from virtspec_mi.result import Result
from virtspec_mi.results_io import check_output
from virtspec_mi.scene import find_instrument, scene_fingerprint
from virtspec_mi.settings import Settings, settings_keywords, with_settings

__all__ = ["measure", "sweep", "gonio", "read_result", "read_gonio", "fluctuation"]


def measure(scene: Any, *, progress: bool | None = None, **settings: Any) -> Result:
    """
    Measure the specimen of ``scene`` and return a certified :class:`~virtspec_mi.result.Result`
    over wavelength (θi a scalar label).

    Parameters
    ----------
    scene
        XML path, scene dict or loaded ``mi.Scene`` with ``emitter`` and ``specimen`` disks.
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

    instrument = find_instrument(scene)
    settings = with_settings(_scene_settings(instrument), settings, "measure")
    result = measure_reading(instrument, settings, progress=progress)
    result.warn_if_uncertified(stacklevel=3)
    return result


def sweep(
    scene: Any,
    *,
    theta_i: Any = None,
    checkpoint: str | os.PathLike | None = None,
    out: str | os.PathLike | None = None,
    progress: bool | None = None,
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
    checkpoint
        Path of a JSON file recording finished readings as the sweep goes; an existing
        file of the same sweep is resumed (:mod:`virtspec_mi.checkpoint`; a note on
        stderr says how many readings were reused). Held by one sweep at a time (an OS
        lock; another run gets ``ValueError``) and checked writable before any tracing.
        Removed when the sweep completes — with ``out``, only once the output file is
        written. A corrupt or foreign checkpoint raises
        :class:`~virtspec_mi.checkpoint.CheckpointError` and is left as it is.
    out
        Result file (``.nc``, ``.csv`` or ``.json``, :meth:`Result.write`) to write,
        atomically, when the sweep completes; checked before any tracing. The
        checkpoint defaults to ``OUT.partial.json``: if the write fails (a full disk …)
        every finished reading stays there and the same call, re-run, only writes.
    progress
        ``True``: always a tqdm bar on stderr; ``False``: never (and no note on
        stderr); ``None`` (default): only when stderr is a terminal and the sweep is
        expected to last more than ~2 s.
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
    instrument = find_instrument(scene)
    base = with_settings(_scene_settings(instrument), settings, "sweep")
    angles = np.array(parse_theta_i(base.theta_i if theta_i is None else theta_i))
    resolved = base.updated(theta_i=float(angles[0]))
    for name, values in (("theta_i", angles), ("wavelengths", np.array(resolved.wavelengths))):
        if len(np.unique(values)) != len(values):
            raise ValueError(f"{name} of a sweep must be distinct (got repeated values)")
    fingerprint = scene_fingerprint(scene, instrument)
    if checkpoint is None:
        result = run(instrument, resolved, angles, keyed=True, scene=fingerprint, progress=progress)
    else:
        with claim(checkpoint):  # one run per checkpoint, writable: checked before any tracing
            result = run(instrument, resolved, angles, keyed=True, scene=fingerprint, checkpoint=checkpoint,
                         progress=progress)
            if out is not None:
                _write(result, out, checkpoint)
            remove(checkpoint)  # the readings are safe: returned, and written to out when given
    result.warn_if_uncertified(stacklevel=3)
    return result


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
    except (OSError, RuntimeError) as error:  # netCDF reports some failures as RuntimeError
        failure = OSError(f"could not write {out} ({getattr(error, 'strerror', None) or error}); every finished "
                          f"reading is kept in {checkpoint}: re-run the same sweep to write it")
        failure.errno = getattr(error, "errno", None)  # e.g. errno.ENOSPC, for callers that check it
        raise failure from error


measure.__signature__ = settings_keywords(measure)  # type: ignore[attr-defined]
sweep.__signature__ = settings_keywords(sweep)  # type: ignore[attr-defined]


def gonio(scene: Any, *, theta_i: Any = None, out: str | os.PathLike | None = None, **options: Any) -> GonioResult:
    """
    A certified goniophotometer reading of ``scene``: the spectrophotometer's readings
    over every (wavelength, θi), with every escaping ray also binned by its outgoing
    direction (θo, φo) in the specimen frame (:class:`~virtspec_mi.gonio_result.GonioResult`).

    Parameters
    ----------
    scene
        XML path, scene dict or loaded ``mi.Scene`` (as for :func:`measure`).
    theta_i
        Incidence angles in degrees (as for :func:`sweep`); default: the scene's θi (or 0).
    out
        File to write (``.nc``, ``.csv`` or ``.json``), checked before any tracing.
    **options
        The goniophotometer parameters (:data:`~virtspec_mi.gonio_bins.GONIO_PARAMETERS`:
        ``theta_o_bins``, ``phi_o_bins``, ``binning``, ``fold_phi``, ``hemispheres``,
        ``guarantee``, ``relative_tolerance``, ``brdf_floor``) and every setting of
        :class:`~virtspec_mi.settings.Settings` (a fixed budget); one left ``None`` comes
        from the scene's ``spectrophotometer`` integrator, else from its default. Without
        ``rays``, N is sized by ``guarantee`` at ``mu`` and ``delta`` over the K bins
        (:func:`virtspec_mi.gonio_bounds.gonio_rays`).

    References
    ----------
    Baranoski et al. (2001), eq. (23), Sect. 6; :mod:`virtspec_mi.gonio_bounds`.
    """

    out = check_output(_file_path(out, "out")) if out is not None else None
    instrument = find_instrument(scene)
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
    """A goniophotometer reading from a file written by :meth:`GonioResult.write`."""

    return GonioResult.read(path)


def read_result(path: str | os.PathLike) -> Result:
    """A result from a file written by ``Result.write`` or printed by ``virtspec measure --json``."""

    return Result.read(path)


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


def _scene_settings(instrument: Instrument) -> Settings:
    """The settings of the scene's ``spectrophotometer`` integrator, else the defaults."""

    return instrument.integrator.settings if instrument.integrator is not None else Settings()
