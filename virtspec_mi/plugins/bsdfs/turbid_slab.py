"""
``turbid_slab``: a scattering, absorbing slab between Fresnel boundaries
=========================================================================

A plane-parallel layer of thickness d filled with a turbid medium (absorption
coefficient μa, scattering coefficient μs, Henyey–Greenstein anisotropy g) of
refractive index n, between a medium of index n_above (the side the specimen's
normal points to) and one of index n_below. ``sample()`` runs MCML's analog photon
walk (Wang, Jacques & Zheng 1995) as one Dr.Jit symbolic loop per ray; the walk is
written as resumable steps (the :class:`virtspec_mi.kernel.walk.RandomWalk` protocol),
which the ray kernel drives itself so that a SIMD lane whose walk ends starts its next ray:

1. at the top face a Fresnel coin flip reflects the ray specularly (probability F)
   or refracts it into the slab;
2. inside, exponential free paths with μt = μa + μs; at each interaction the photon
   is absorbed with probability μa/μt (analog absorption: weights are 1 or 0), else
   scattered by the HG phase function;
3. at either face a Fresnel coin flip reflects it back (total internal reflection
   included) or lets it out: out through the top face it is *reflected*
   (wo·n > 0), out through the bottom *transmitted*.

A ray that hits the back face (wi·n < 0, e.g. back-lit conical rays) runs the same
walk from the bottom face, with the two outer media swapped.

Quantities (as the ``spectrophotometer`` counts them)
-----------------------------------------------------
- **Total reflectance** R (MCML's Rsp + Rd; iadpython's UR1 / URU) includes the
  specular reflection at the top face.
- The sampled event type tells the parts apart: a ray that leaves without any
  scattering event is a ``DeltaReflection`` / ``DeltaTransmission`` (mirror or
  straight-through direction), one that scattered at least once a
  ``DiffuseReflection`` / ``DiffuseTransmission``. The instrument counts the delta
  events as ``Result.specular_reflectance`` (Rs; CIE "regular reflectance") and
  ``Result.regular_transmittance`` (Tc, the unscattered, collimated transmittance);
  ``diffuse_reflectance`` = R − Rs (MCML's Rd), ``diffuse_transmittance`` = T − Tc.
- Rs is the top-face Fresnel reflection plus light that crossed the slab without
  scattering and came back out of the top face after internal reflection(s) — the
  "unscattered r" of iadpython. It equals MCML's Rsp whenever no unscattered light
  returns (index-matched or semi-infinite slabs, e.g. the MCML benchmarks).
- The slab is laterally infinite (a BSDF): where the light leaves is not tracked.

Parameters
----------
mu_a : float or spectrum, default 1.0
    Absorption coefficient μa ≥ 0, per length unit (e.g. cm⁻¹ with ``thickness`` in cm);
    0 or 10⁻³⁰ … 10³⁰ (:data:`COEFFICIENT_RANGE`).
mu_s : float or spectrum, default 0.0
    Scattering coefficient μs ≥ 0, in the same unit and range.
g : float or spectrum, default 0.0
    Henyey–Greenstein anisotropy, −1 ≤ g ≤ 1 (0 isotropic, ±1 pure forward/backward).
thickness : float, default 1.0
    Slab thickness d > 0 in the length unit of μa and μs, 10⁻³⁰ … 10³⁰; ``inf`` is a semi-infinite
    medium (then μa + μs must be > 0). Optical thickness is (μa + μs)·d, albedo μs/(μa + μs).
eta : float or spectrum, default 1.0
    Refractive index n > 0 of the slab, 10⁻⁶ … 10⁶ (:data:`INDEX_RANGE`, as the other two).
    A face whose relative index is within :data:`~virtspec_mi.kernel.walk_optics.NEAR_ONE`
    of 1 (but not 1) gets Fresnel's equations from η − 1, computed without cancellation
    (in float64 for numbers; exact for the float32 values of a spectrum):
    :func:`~virtspec_mi.kernel.walk_optics.cross_interface`.
eta_above : float or spectrum, default 1.0
    Refractive index > 0 of the medium above the slab (the side of the normal, where
    light comes from).
eta_below : float or spectrum, default 1.0
    Refractive index > 0 of the medium below the slab.
max_steps : integer, default 1000000
    Cap on free flights per walk (≥ 1). A walk still inside after ``max_steps`` flights
    reports ``CAPPED_COMPONENT`` (weight 0) and the instrument counts it in
    ``Result.capped``, in none of R, T and A.

Notes
-----
A spectral parameter is any Mitsuba spectrum/texture (``<spectrum name="mu_a"
value="400:12, 700:3"/>`` in XML, or ``{"type": "regular", ...}`` in a dict), read
unbounded and evaluated per ray at the ray's wavelength (channel 0 of
``si.wavelengths``). Wavelengths outside a spectrum's data (a ``regular`` spectrum's
range, an ``irregular`` one's wavelengths, an RGB colour's CIE range 360–830 nm:
:mod:`virtspec_mi.kernel.spectra`) are refused before tracing, naming the parameter.
Numbers are checked here (``ValueError`` naming the parameter and the allowed range;
booleans, non-finite values and values float32 cannot hold are refused);
spectra are checked at the wavelengths of a measurement before it is traced
(:meth:`TurbidSlab.check_wavelengths`). When every parameter is a number the slab
declares :attr:`TurbidSlab.wavelength_independent` ``True``.

``mi.traverse`` shows every parameter given as a number and ``thickness`` as
``specimen.bsdf.NAME`` (opaque ``Float64``): setting one and calling ``update()`` checks
it as above and rebuilds the walk's opaque scalars, so a parameter sweep
(:mod:`virtspec_mi.engine.parameters`) reuses the compiled kernel. A parameter given as a
spectrum is not exposed.

References
----------
L. Wang, S.L. Jacques, L. Zheng (1995), *MCML — Monte Carlo modeling of light
transport in multi-layered tissues*, Comput. Methods Programs Biomed. 47, 131–146.
S.A. Prahl, M.J.C. van Gemert, A.J. Welch (1993), *Determining the optical properties
of turbid media by using the adding-doubling method*, Appl. Opt. 32, 559–568
(UR1, UT1, URU, UTU).
"""

from __future__ import annotations

import math
from typing import Any, Callable, Sequence

import drjit as dr
import mitsuba as mi
import numpy as np

from virtspec_mi.base.checks import check_float32
from virtspec_mi.plugins.bsdfs.sampled_only import SampledOnlyBSDF
from virtspec_mi.plugins.specimen import Parameter

from virtspec_mi.kernel.spectra import check_covered
from virtspec_mi.kernel.walk import CAPPED_COMPONENT, walk_rng, walk_to_end
from virtspec_mi.kernel.walk_optics import NEAR_ONE, cross_interface, free_path, sample_hg

__all__ = ["TurbidSlab", "SLAB_COMPONENTS", "COEFFICIENT_RANGE", "INDEX_RANGE"]

SLAB_COMPONENTS: dict[str, int] = {
    "specular_reflection": 0,
    "diffuse_reflection": 1,
    "regular_transmission": 2,
    "diffuse_transmission": 3,
}
"""``bs.sampled_component`` of each exit (absorbed rays report 1 with weight 0)."""

# Ranges the walk's float32 arithmetic keeps exact enough: free paths −ln ξ/μt (−ln ξ ≤ 17)
# and depths stay finite and normal; Fresnel at relative indices up to 10¹² (η² and 1/η²).
COEFFICIENT_RANGE: tuple[float, float] = (1e-30, 1e30)
"""Nonzero μa, μs (per length unit) and finite thicknesses lie in this range."""
INDEX_RANGE: tuple[float, float] = (1e-6, 1e6)
"""Refractive indices lie in this range."""

# name: (default, lower, upper, lower bound included, smallest nonzero magnitude, meaning)
_SPECTRAL = {
    "mu_a": (1.0, 0.0, COEFFICIENT_RANGE[1], True, COEFFICIENT_RANGE[0], "absorption coefficient"),
    "mu_s": (0.0, 0.0, COEFFICIENT_RANGE[1], True, COEFFICIENT_RANGE[0], "scattering coefficient"),
    "g": (0.0, -1.0, 1.0, True, 0.0, "Henyey-Greenstein anisotropy"),
    "eta": (1.0, 0.0, INDEX_RANGE[1], False, INDEX_RANGE[0], "slab refractive index"),
    "eta_above": (1.0, 0.0, INDEX_RANGE[1], False, INDEX_RANGE[0], "refractive index above the slab"),
    "eta_below": (1.0, 0.0, INDEX_RANGE[1], False, INDEX_RANGE[0], "refractive index below the slab"),
}

# Walk states.
_INSIDE, _TOP, _BOTTOM, _ABSORBED, _CAPPED = 0, 1, 2, 3, 4


def _allowed(name: str) -> tuple[str, Callable[[Any], Any]]:
    """The range of a spectral parameter in words, and its test (works on floats and arrays)."""

    _, lower, upper, closed, smallest, _ = _SPECTRAL[name]
    words = f"{lower:g} {'<=' if closed else '<'} {name} <= {upper:g}"
    if smallest:
        words += f" ({'0 or ' if closed else ''}at least {smallest:g})"

    def test(value: Any) -> Any:
        inside = ((value >= lower) if closed else (value > lower)) & (value <= upper) & np.isfinite(value)
        return inside & ((value == 0) | (np.abs(value) >= smallest))

    return words, test


def _check_number(name: str, value: float) -> float:
    words, test = _allowed(name)
    return check_float32(f"turbid_slab: '{name}'", value, f"satisfy {words} and be finite", test)


def _check_thickness(thickness: Any) -> float:
    low, high = COEFFICIENT_RANGE
    return check_float32(
        "turbid_slab: 'thickness'", thickness, f"be a number > 0 or inf ({low:g} <= thickness <= {high:g})",
        lambda value: value == math.inf or low <= value <= high, allow_inf=True)


class TurbidSlab(SampledOnlyBSDF):
    """MCML-style analog random walk in a Fresnel-bounded HG slab (see the module docstring)."""

    PLUGIN = "turbid_slab"
    PARAMETERS = (*(Parameter(name, lower, upper, "1/length" if name.startswith("mu_") else "1", meaning)
                    for name, (_, lower, upper, _, _, meaning) in _SPECTRAL.items()),
                  Parameter("thickness", COEFFICIENT_RANGE[0], math.inf, "length (the unit of 1/mu_a)",
                            "slab thickness (inf: a semi-infinite medium)"))
    """Its parameters given as numbers (a spectrum given is not a parameter: :meth:`exposed_parameters`)."""

    def __init__(self, props: mi.Properties) -> None:
        super().__init__(props)
        self.constants: dict[str, float] = {}
        self.textures: dict[str, Any] = {}
        for name, (default, *_) in _SPECTRAL.items():
            value = props.get(name, default) if name in props else default
            if not isinstance(value, (int, float)) or isinstance(value, bool):
                try:
                    value = props.get_unbounded_texture(name)
                except Exception:
                    raise ValueError(
                        f"turbid_slab: '{name}' must be a number or a spectrum (got {value!r})"
                    ) from None
                if value.class_name() == "UniformSpectrum":  # a constant written as a spectrum
                    value = float(value.mean()[0])
            if isinstance(value, (int, float)):
                self.constants[name] = _check_number(name, value)
            else:
                self.textures[name] = value
        thickness = props.get("thickness", 1.0)
        if isinstance(thickness, str):
            thickness = float(thickness) if thickness.strip().lower() in ("inf", "infinity") else math.nan
        self.thickness = _check_thickness(thickness)
        self._check_semi_infinite(self.constants, self.thickness)
        max_steps = props.get("max_steps", 1_000_000)
        if isinstance(max_steps, bool) or not isinstance(max_steps, int) or not 1 <= max_steps < 2**31:
            raise ValueError(f"turbid_slab: 'max_steps' must be a whole number in [1, 2**31) (got {max_steps!r})")
        self.max_steps = int(max_steps)
        self.wavelength_independent = not self.textures
        self._make_opaque()
        self._max_steps = dr.opaque(mi.UInt32, self.max_steps)
        both = mi.BSDFFlags.FrontSide | mi.BSDFFlags.BackSide
        self.m_components = [
            mi.BSDFFlags.DeltaReflection | both,
            mi.BSDFFlags.DiffuseReflection | both,
            mi.BSDFFlags.DeltaTransmission | both | mi.BSDFFlags.NonSymmetric,
            mi.BSDFFlags.DiffuseTransmission | both | mi.BSDFFlags.NonSymmetric,
        ]
        self.m_flags = self.m_components[0] | self.m_components[1] | self.m_components[2] | self.m_components[3]

    def _make_opaque(self) -> None:
        # Opaque scalars: one compiled kernel serves every slab with the same parameter kinds.
        self._opaque = {name: dr.opaque(mi.Float, value) for name, value in self.constants.items()}
        self._thickness = dr.opaque(mi.Float, self.thickness)
        self._near_one = None
        if self.wavelength_independent:
            # η − 1 of each face, lit from the front and from the back, in float64 on the host: exact
            # near 1, where float32 quotients lose its digits (kernel.walk_optics, NEAR_ONE).
            eta, above, below = (self.constants[name] for name in ("eta", "eta_above", "eta_below"))
            faces = ((eta - above) / above, (eta - below) / below, (below - eta) / eta, (above - eta) / eta)
            if any(0.0 < abs(d) < NEAR_ONE for d in faces):
                self._near_one = tuple(dr.opaque(mi.Float, d) for d in faces)

    def _check_semi_infinite(self, constants: dict[str, float], thickness: float) -> None:
        mu_t = constants.get("mu_a", 1.0) + constants.get("mu_s", 1.0)
        if math.isinf(thickness) and not self.textures.keys() & {"mu_a", "mu_s"} and mu_t == 0:
            raise ValueError("turbid_slab: a semi-infinite slab (thickness = inf) needs mu_a + mu_s > 0")

    # -- parameters through mi.traverse ---------------------------------------------------

    def exposed_parameters(self) -> dict[str, float]:
        """The parameters given as numbers (``mu_a``, ``mu_s``, ``g``, the indices) and ``thickness``."""

        return {**self.constants, "thickness": self.thickness}

    def set_parameters(self, values: dict[str, float]) -> None:
        """
        New values, each checked as at load time (``ValueError`` leaves the slab as it was),
        then the opaque scalars rebuilt: the walk's kernel is not recompiled. A parameter
        given as a spectrum is not exposed (give it as a number to sweep it).
        """

        known = self.exposed_parameters()
        unknown = sorted(set(values) - set(known))
        if unknown:
            raise ValueError(f"turbid_slab: no numeric parameter {unknown[0]!r} (known: {', '.join(known)})")
        constants = {**self.constants, **{name: _check_number(name, value) for name, value in values.items()
                                          if name != "thickness"}}
        thickness = _check_thickness(values["thickness"]) if "thickness" in values else self.thickness
        self._check_semi_infinite(constants, thickness)
        if constants != self.constants or thickness != self.thickness:
            self.constants, self.thickness = constants, thickness
            self._make_opaque()

    # -- parameters per lane -------------------------------------------------------------

    def check_wavelengths(self, wavelengths: Sequence[float]) -> None:
        """
        Refuse (``ValueError`` naming the parameter, its range and the wavelength) a
        wavelength about to be traced outside a spectral parameter's data
        (:func:`virtspec_mi.kernel.spectra.check_covered`), or a spectral parameter out of
        its range there, e.g. ``g`` given as a spectrum of 1.5; called by the engine
        before tracing.
        """

        if not self.textures:
            return
        lams = np.asarray(wavelengths, dtype=np.float64)
        si = dr.zeros(mi.SurfaceInteraction3f, len(lams))
        si.wavelengths = mi.Spectrum(mi.Float(lams))
        values = {name: np.array(texture.eval(si)[0], dtype=np.float64) for name, texture in self.textures.items()}
        for name, value in values.items():
            words, test = _allowed(name)
            bad = np.flatnonzero(~test(value))
            if bad.size:
                k = bad[0]
                raise ValueError(f"turbid_slab: '{name}' (a spectrum) must satisfy {words} and be finite at every "
                                 f"wavelength traced (got {float(value[k]):.7g} at {float(lams[k])!r} nm)")
        if math.isinf(self.thickness) and values.keys() & {"mu_a", "mu_s"}:
            mu_t = sum(values.get(name, self.constants.get(name, 0.0)) for name in ("mu_a", "mu_s"))
            empty = np.flatnonzero(np.broadcast_to(mu_t, lams.shape) == 0)
            if empty.size:
                raise ValueError(f"turbid_slab: a semi-infinite slab (thickness = inf) needs mu_a + mu_s > 0 "
                                 f"(got 0 at {float(lams[empty[0]])!r} nm)")
        for name, texture in self.textures.items():  # outside a spectrum's data it reads 0, in range or not
            check_covered(texture, wavelengths, "the specimen turbid_slab", name)

    def _value(self, name: str, si: mi.SurfaceInteraction3f) -> mi.Float:
        if name in self._opaque:
            return self._opaque[name]
        return mi.Float(self.textures[name].eval(si)[0])

    # -- BSDF interface ------------------------------------------------------------------

    def sample(self, ctx, si, sample1, sample2, active=True):
        return self.walk_sample(walk_to_end(self, self.walk_start(si, sample1, sample2, active)))

    # -- the walk as resumable steps (virtspec_mi.kernel.walk.RandomWalk) -------------------
    # State: (rng, status, direction, depth, scattered, steps, front, optics) per lane — the
    # generator (WalkRNG), walk status, propagation direction and depth (−z) in the mirrored slab, whether
    # it scattered, free flights so far, whether light came from the front, and the optics
    # (μt, albedo, g, the faces' relative indices η_top and η_bottom, and the outer media's
    # index ratio, ``bs.eta`` of a transmission): per lane for a spectral slab, () for a slab
    # of numbers (then computed from the numbers and ``front``: a smaller state).

    def _optics(self, si: Any, front: Any) -> tuple:
        """
        (μt, albedo, g, η_top, η_bottom, η_out/η_in, η_top − 1, η_bottom − 1) of each lane;
        the last two computed without cancellation (:func:`~virtspec_mi.kernel.walk_optics.cross_interface`
        then treats a face near η = 1 exactly), ``None`` for a slab of numbers with no face
        near 1 (nothing more is compiled: counts as before).
        """

        mu_a, mu_s, g, eta = (self._value(name, si) for name in ("mu_a", "mu_s", "g", "eta"))
        above, below = self._value("eta_above", si), self._value("eta_below", si)
        # Back-lit rays: mirror the slab so that light always enters through the top face.
        if self.wavelength_independent:  # numbers: each quotient once, then a select per lane
            eta_top = dr.select(front, eta / above, eta / below)
            eta_bottom = dr.select(front, below / eta, above / eta)
            ratio = dr.select(front, below / above, above / below)
            near = self._near_one
            d_top = None if near is None else dr.select(front, near[0], near[1])
            d_bottom = None if near is None else dr.select(front, near[2], near[3])
        else:
            outer_in = dr.select(front, above, below)
            outer_out = dr.select(front, below, above)
            eta_top, eta_bottom, ratio = eta / outer_in, outer_out / eta, outer_out / outer_in
            d_top, d_bottom = (eta - outer_in) / outer_in, (outer_out - eta) / eta  # differences: exact near 1
        mu_t = mu_a + mu_s
        return mu_t, mu_s / mu_t, g, eta_top, eta_bottom, ratio, d_top, d_bottom

    def _state_optics(self, state: tuple) -> tuple:
        return state[7] if state[7] else self._optics(None, state[6])

    def walk_start(self, si, sample1, sample2, active=True):
        """
        The walk state of each lane after the entry event: a Fresnel coin flip at the top
        face (specular reflection leaves at once), see :class:`RandomWalk`.
        """

        front = si.wi.z >= 0.0
        optics = self._optics(si, front)
        wi = mi.Vector3f(si.wi.x, si.wi.y, dr.abs(si.wi.z))
        rng = walk_rng(sample1, sample2)
        # Entry: Fresnel at the top face (specular reflection leaves at once).
        direction, reflected = cross_interface(-wi, optics[3], rng.next_float32(), optics[6])
        status = dr.select(reflected, mi.UInt32(_TOP), mi.UInt32(_INSIDE))
        status = dr.select(mi.Bool(active), status, mi.UInt32(_ABSORBED))
        status = status + dr.zeros(mi.UInt32, dr.width(sample1))
        return (rng, status, direction, mi.Float(0.0), mi.Bool(False), mi.UInt32(0), front,
                () if self.wavelength_independent else optics)

    def walk_done(self, state):
        """True where the walk has ended (exit, absorption or cap)."""

        return state[1] != _INSIDE

    def walk_sample(self, state):
        """The ``(BSDFSample3f, weight)`` of finished walks."""

        status, direction, scattered, front = state[1], state[2], state[4], state[6]
        eta_out_in = self._state_optics(state)[5]
        top = status == _TOP
        exited = top | (status == _BOTTOM)
        capped = status == _CAPPED
        bs = dr.zeros(mi.BSDFSample3f)
        bs.wo = mi.Vector3f(direction.x, direction.y, dr.select(front, direction.z, -direction.z))
        bs.pdf = dr.select(exited, 1.0, 0.0)
        bs.eta = dr.select(top, 1.0, eta_out_in)
        component = dr.select(top, mi.UInt32(0), mi.UInt32(2)) + dr.select(scattered, mi.UInt32(1), mi.UInt32(0))
        component = dr.select(exited, component, mi.UInt32(SLAB_COMPONENTS["diffuse_reflection"]))
        bs.sampled_component = dr.select(capped, mi.UInt32(CAPPED_COMPONENT), component)
        bs.sampled_type = dr.select(
            top,
            dr.select(scattered, mi.UInt32(+mi.BSDFFlags.DiffuseReflection), mi.UInt32(+mi.BSDFFlags.DeltaReflection)),
            dr.select(scattered, mi.UInt32(+mi.BSDFFlags.DiffuseTransmission),
                      mi.UInt32(+mi.BSDFFlags.DeltaTransmission)),
        )
        weight = dr.select(exited, mi.Spectrum(1.0), mi.Spectrum(0.0))
        return bs, weight

    def walk_step(self, state):
        """
        One free flight of the lanes the caller runs, in the slab −d ≤ z ≤ 0 (entered
        through its top face z = 0): it ends at a face (Fresnel coin flip: out, or reflected
        back) or at an interaction (absorbed with probability μa/μt, else HG scattering).
        ``eta_top`` = n_slab/n_above and ``eta_bottom`` = n_below/n_slab are the relative
        indices (below over above) of the two faces; after ``max_steps`` flights a walk
        still inside is capped.
        """

        rng, status, direction, depth, scattered, steps, front, optics = state
        mu_t, albedo, g, eta_top, eta_bottom, _, d_top, d_bottom = self._state_optics(state)
        thickness = self._thickness
        # Four numbers per flight, drawn first (unmasked): the free path, the event's coin (the
        # face's Fresnel choice, or absorption against scattering) and HG's two.
        u_path, u_event, u_cos, u_phi = rng.next_float32(), rng.next_float32(), rng.next_float32(), rng.next_float32()
        path = free_path(u_path, mu_t)
        direction_z = direction.z
        down = direction.z < 0.0
        to_face = dr.select(down, (thickness - depth) / -direction.z, depth / direction.z)
        to_face = dr.select(direction.z == 0.0, dr.inf, to_face)
        # Both outcomes for every lane, then a select (straight-line: no branch per packet).
        hit = path >= to_face
        d_face = None if d_top is None else dr.select(down, d_bottom, d_top)  # η − 1 of the face ahead
        at_face, reflected = cross_interface(direction, dr.select(down, eta_bottom, eta_top), u_event, d_face)
        absorbed = ~hit & (u_event >= albedo)
        turned = sample_hg(direction, g, u_cos, u_phi)
        direction = dr.select(hit, at_face, dr.select(absorbed, direction, turned))
        depth = dr.select(hit, dr.select(down, thickness, 0.0), dr.fma(path, -direction_z, depth))
        status = dr.select(hit & ~reflected, dr.select(down, mi.UInt32(_BOTTOM), mi.UInt32(_TOP)),
                           dr.select(absorbed, mi.UInt32(_ABSORBED), status))
        scattered = scattered | (~hit & ~absorbed)
        steps = steps + 1
        status = dr.select((status == _INSIDE) & (steps >= self._max_steps), mi.UInt32(_CAPPED), status)
        return (rng, status, direction, depth, scattered, steps, front, optics)

    def to_string(self) -> str:
        parts = [f"{k}={v:g}" for k, v in self.constants.items()]
        parts += [f"{k}=<spectrum>" for k in self.textures]
        return f"TurbidSlab[{', '.join(parts)}, thickness={self.thickness:g}, max_steps={self.max_steps}]"
