"""
``spectrophotometer``: the virtual integrating-sphere instrument as a Mitsuba integrator
========================================================================================

A thin adapter: it reads the measurement settings and the options of its instrument
from its XML/dict parameters with the one reader
(:meth:`virtspec_mi.settings.Options.from_parameters`) and, on ``mi.render``, measures
the scene's specimen with that instrument of the registry
(:data:`virtspec_mi.instruments.INSTRUMENTS`, chosen by the ``instrument`` parameter:
any row, an outside instrument's too).
The tracing itself — rays from the emitter disk, the specimen BSDF, fates and exact
tallies — is :mod:`virtspec_mi.kernel.tracer`.

Parameters
----------
instrument : string, default "hemispherical"
    The instrument of the registry that measures (``hemispherical``, ``goniophotometer``,
    ``sphere``, ``gloss`` or an outside one); its options are parameters too. Without it,
    a goniophotometer option makes it ``goniophotometer`` (scenes written before it).
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
``integrator.last_reading`` as a :class:`~virtspec_mi.instruments.goniophotometer.result.GonioResult`;
:func:`virtspec_mi.gonio` on the scene uses them as its defaults):
``theta_o_bins`` (integer or string of edges, default 18 per hemisphere),
``phi_o_bins`` (integer or string of edges, default 36), ``binning`` (``uniform``,
``projected``, or ``rgl``: the cells of an RGL ``.bsdf``'s grid, the reading an
:class:`~virtspec_mi.instruments.goniophotometer.rgl_reading.RGLReading`), ``rgl_resolution``
(integer, default 32), ``fold_phi`` (boolean), ``hemispheres`` (``both``, ``reflection``,
``transmission``), ``guarantee`` (``union``, ``union-exact``, ``dkw``, ``relative``),
``relative_tolerance`` and ``brdf_floor`` (floats). A bad bin specification raises
``ValueError`` naming the parameter. ``mi.render(scene, seed=s, spp=n)``
returns a ``TensorXf`` of shape ``(len(wavelengths), 3)``: per wavelength (rows, in the
order given) the reflectance, transmittance and absorptance. ``spp`` > 0 sets the rays
per reading (0 ≤ ``spp`` ≤ 2³² − 1; 0: from the settings); ``seed`` is added to the
``seed`` parameter. The full :class:`~virtspec_mi.results.readings.Result` is kept in
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

from virtspec_mi.base.checks import MAX_RAYS, shown_value
from virtspec_mi.engine.bench import read_bench
from virtspec_mi.instruments import INSTRUMENTS
from virtspec_mi.settings import Settings

__all__ = ["Spectrophotometer", "check_spp", "clear_render_errors", "instrument_of"]

_WORD = 1 << 32


class Spectrophotometer(mi.SamplingIntegrator):
    """The instrument as a Mitsuba integrator (see the module docstring)."""

    plugin = "spectrophotometer"
    """The plugin's name, in its messages."""

    def __init__(self, props: mi.Properties) -> None:
        super().__init__(props)
        try:
            self.instrument = INSTRUMENTS[self.instrument_name(props)]
            self.settings = Settings.from_parameters(props)
            kind = self.instrument.options
            self.instrument_options = None if kind is None else kind.from_parameters(props)
        except (ValueError, TypeError) as error:
            raise ValueError(f"{self.plugin}: {error}") from None
        self.options = {Settings: self.settings, **({} if kind is None else {kind: self.instrument_options})}
        """The options the scene holds, by class: the API's defaults (:func:`virtspec_mi.take` …)."""
        self.last_reading = None

    def instrument_name(self, parameters: Any) -> str:
        """The instrument of the registry this integrator measures with (:func:`instrument_of`)."""

        return instrument_of(parameters)

    def render(self, scene, sensor=None, seed=0, spp=0, develop=True, evaluate=True):
        rays = check_spp(spp)
        settings = self.settings.updated(seed=(self.settings.seed + int(seed)) % _WORD, rays=rays or None)
        instrument = self.instrument()
        reading = instrument.run(read_bench(scene), settings, self.instrument_options).squeeze()  # one theta_i
        instrument.warn_if_uncertified(reading, stacklevel=2)
        self.last_reading = reading
        return mi.TensorXf(self.last_reading.rendered())

    def sample(self, scene, sampler, ray, medium=None, active=True):
        return mi.Spectrum(0.0), mi.Bool(False), []

    def to_string(self) -> str:
        return f"Spectrophotometer[{self.instrument.name}; {self.settings}]"


def instrument_of(parameters: Any) -> str:
    """
    The instrument an integrator's parameters name (``instrument``); without it, the one
    instrument whose own options they give (a goniophotometer's bins: scenes written
    before the parameter), else the first row of the registry (the spectrophotometer).
    ``ValueError`` naming the registry's instruments for any other name, or the
    instruments when the options of several are given.
    """

    if "instrument" in parameters:
        name = parameters.get("instrument")
        if name not in INSTRUMENTS:
            raise ValueError(f"instrument must be one of {', '.join(INSTRUMENTS)} (got {name!r})")
        return name
    given = [row.name for row in INSTRUMENTS.values() if row.options is not None and row.options.parameters_in(parameters)]
    if len(given) > 1:
        raise ValueError(f"the parameters are options of several instruments ({', '.join(given)}): name one with "
                         "the parameter instrument")
    return given[0] if given else next(iter(INSTRUMENTS))


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
    :mod:`virtspec_mi.base.interrupts`) as themselves, not as the ``RuntimeError``
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
