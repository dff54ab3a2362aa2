"""
``spectrophotometer``: the virtual integrating-sphere instrument as a Mitsuba integrator
========================================================================================

A thin adapter: it reads the measurement settings (and the goniophotometer's options)
from its XML/dict parameters with the one reader
(:meth:`virtspec_mi.settings.Options.from_parameters`) and, on ``mi.render``, measures
the scene's specimen with the instrument of the registry
(:data:`virtspec_mi.instruments.INSTRUMENTS`: ``hemispherical``, or ``goniophotometer``).
The tracing itself — rays from the emitter disk, the specimen BSDF, fates and exact
tallies — is :mod:`virtspec_mi.kernel.tracer`.

Parameters
----------
theta_i : float, default 0
    Polar incidence angle in degrees, 0 ≤ θi ≤ 90.
phi_i : float, default 0
    Azimuthal incidence angle in degrees (from the specimen's local x axis).
wavelengths : string or float, default "551"
    Wavelengths in nm: numbers and ``start:stop:step`` ranges, comma/space separated;
    each 0.001 ≤ λ ≤ 10⁶ nm, at most 100,000 of them.
mu : float, default 0.005
    Certified tolerance μ of each reading, 0 < μ < 0.5.
delta : float, default 0.01
    Allowed failure probability δ, 0 < δ < 1.
rays : integer, default: from the bound
    Rays per reading (overrides the bound), 1 ≤ rays ≤ 2³² − 1.
bound : string, default "hoeffding"
    Ray budget: ``hoeffding`` (eq. 23), ``chebyshev`` (eq. 15), ``exact`` (smallest N
    certified by the exact binomial law) or ``two-stage`` (pilot batch, then a fresh
    batch sized per reading; see :mod:`virtspec_mi.budgets.twostage`).
joint : boolean, default false
    Certify reflectance and transmittance together (each at δ/2).
pilot_rays : integer, default ⌈10/μ⌉
    Two-stage pilot rays per reading, 1 ≤ pilot_rays ≤ 2³² − 1.
pilot_delta : float, default δ/10
    Two-stage pilot failure probability, 0 < pilot_delta < δ.
beam : string, default "conical"
    ``conical`` (conical-hemispherical), ``collimated`` (directional-hemispherical) or
    ``diffuse`` (hemispherical-hemispherical: incidence directions cosine-distributed
    over the upper hemisphere, aimed at uniform points of the specimen disk; θi and
    φi are not used).
sampling : string, default "jittered"
    Disk sampling: ``jittered`` (eq. 4), ``random`` (eq. 3) or ``concentric``.
seed : integer, default 0
    Seed of the counter-based random numbers, 0 ≤ seed < 2³².
chunk_size : integer, default 4194304
    Rays per kernel launch, 1024 ≤ chunk_size ≤ 2²⁵ (bounds memory; results do not
    depend on it).

Notes
-----
These are the fields of :class:`virtspec_mi.settings.Settings` (the one definition;
this list is checked against it by the tests).

Goniophotometer parameters (the options of
:class:`virtspec_mi.instruments.goniophotometer.GonioOptions`, the one definition; any of
them makes ``mi.render`` take a goniophotometer reading, kept in
``integrator.last_reading`` as a :class:`~virtspec_mi.results.goniophotometer.GonioResult`;
:func:`virtspec_mi.gonio` on the scene uses them as its defaults):
``theta_o_bins`` (integer or string of edges, default 18 per hemisphere),
``phi_o_bins`` (integer or string of edges, default 36), ``binning`` (``uniform`` or
``projected``), ``fold_phi`` (boolean), ``hemispheres`` (``both``, ``reflection``,
``transmission``), ``guarantee`` (``union``, ``union-exact``, ``dkw``, ``relative``),
``relative_tolerance`` and ``brdf_floor`` (floats). A bad bin specification raises
``ValueError`` naming the parameter. ``mi.render(scene, seed=s, spp=n)``
returns a ``TensorXf`` of shape ``(len(wavelengths), 3)``: per wavelength (rows, in the
order given) the reflectance, transmittance and absorptance. ``spp`` > 0 sets the rays
per reading (0 ≤ ``spp`` ≤ 2³² − 1; 0: from the settings); ``seed`` is added to the
``seed`` parameter. The full :class:`~virtspec_mi.results.hemispherical.Result` is kept in
``integrator.last_reading``. The scene needs a sensor for ``mi.render`` (any; it is not
used).

A bad ``spp`` (or any input the engine refuses) raises ``ValueError`` naming it. Dr.Jit
runs ``mi.render`` inside a custom operation that turns every exception into a
``RuntimeError``; :func:`clear_render_errors` wraps ``mi.render`` (installed by
:func:`virtspec_mi.runtime.mitsuba`) so that this integrator's ``ValueError`` reaches
the caller as itself; other integrators and errors are untouched.
"""

from __future__ import annotations

import functools
from typing import Any, Callable

import mitsuba as mi
import numpy as np

from virtspec_mi.checks import MAX_RAYS, shown_value
from virtspec_mi.engine.bench import read_bench
from virtspec_mi.instruments import INSTRUMENTS
from virtspec_mi.instruments.base import take
from virtspec_mi.instruments.goniophotometer import GonioOptions
from virtspec_mi.settings import Settings

__all__ = ["Spectrophotometer", "check_spp", "clear_render_errors"]

_WORD = 1 << 32


class Spectrophotometer(mi.SamplingIntegrator):
    """The instrument as a Mitsuba integrator (see the module docstring)."""

    def __init__(self, props: mi.Properties) -> None:
        super().__init__(props)
        try:
            self.settings = Settings.from_parameters(props)
            self.gonio_options = GonioOptions.from_parameters(props) if GonioOptions.parameters_in(props) else None
        except ValueError as error:
            raise ValueError(f"spectrophotometer: {error}") from None
        self.options = {Settings: self.settings, GonioOptions: self.gonio_options}
        """The options the scene holds, by class: the API's defaults (:func:`virtspec_mi.gonio` …)."""
        self.last_reading = None

    def render(self, scene, sensor=None, seed=0, spp=0, develop=True, evaluate=True):
        rays = check_spp(spp)
        settings = self.settings.updated(seed=(self.settings.seed + int(seed)) % _WORD, rays=rays or None)
        bench = read_bench(scene)
        if self.gonio_options is not None:
            self.last_reading = take(INSTRUMENTS["goniophotometer"](), bench, settings, self.gonio_options)
            reading = self.last_reading.result.squeeze()
        else:
            reading = take(INSTRUMENTS["hemispherical"](), bench, settings).squeeze()
            self.last_reading = reading
        reading.warn_if_uncertified(stacklevel=2)
        table = np.stack([reading.reflectance, reading.transmittance, reading.absorptance], axis=1)
        return mi.TensorXf(table.astype(np.float32))

    def sample(self, scene, sampler, ray, medium=None, active=True):
        return mi.Spectrum(0.0), mi.Bool(False), []

    def to_string(self) -> str:
        return f"Spectrophotometer[{self.settings}]"


def check_spp(spp: Any) -> int:
    """``mi.render``'s ``spp``: a whole number, 0 (rays from the settings) ≤ spp ≤ 2³² − 1."""

    if isinstance(spp, bool) or not isinstance(spp, (int, np.integer)) or not 0 <= spp <= MAX_RAYS:
        raise ValueError(f"spectrophotometer: spp must be a whole number with 0 <= spp <= {MAX_RAYS} "
                         f"(the rays per reading; 0: from the settings) (got {shown_value(spp)})")
    return int(spp)


def clear_render_errors(render: Callable) -> Callable:
    """
    ``mi.render`` that re-raises this integrator's ``ValueError`` (bad ``spp``, settings,
    wavelengths …) and an interrupt (``KeyboardInterrupt``: Ctrl-C, or SIGTERM under
    :mod:`virtspec_mi.engine.interrupts`) as themselves, not as the ``RuntimeError``
    Dr.Jit's custom operation makes of them; everything else as ``render`` does.
    """

    if getattr(render, "clears_spectrophotometer_errors", False):
        return render

    @functools.wraps(render)
    def wrapper(scene: Any, *args: Any, **kwargs: Any) -> Any:
        try:
            return render(scene, *args, **kwargs)
        except RuntimeError as error:
            integrator = kwargs.get("integrator") or (args[2] if len(args) > 2 else None)
            if integrator is None and isinstance(scene, mi.Scene):
                integrator = scene.integrator()
            if isinstance(integrator, Spectrophotometer) and isinstance(error.__cause__,
                                                                        (ValueError, KeyboardInterrupt)):
                raise error.__cause__ from None
            raise

    wrapper.clears_spectrophotometer_errors = True  # type: ignore[attr-defined]
    return wrapper
