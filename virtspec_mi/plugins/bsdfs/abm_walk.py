"""
The ABM leaf random walk shared by ``abm_b`` and ``abm_u``
==========================================================

A leaf is a stack of K = 6 flat, laterally infinite interfaces between tissues
(leaf normal +z, adaxial surface on top; interface 0 at the top). A ray carries only
its interface index k and its direction ω. Each interface event is, in this order:

1. an absorption test for the slab just crossed (only the mesophyll absorbs): the ray
   is absorbed when −ln ξ · g(cos θ) < α t, with g(c) = cos(c) when the sieve-and-detour
   switch is on (the NPSG default) and g(c) = c (plain Beer–Lambert) when off;
2. a Fresnel choice (unpolarised, total internal reflection → R = 1): reflect with
   probability F, else refract;
3. a Warn cosine-lobe perturbation of the new direction about the specular one,
   p(ω) ∝ cos^e θ_p with e the interface's aspect ratio (e = ∞: none), resampled
   while the perturbed ray leaves the hemisphere the unperturbed one went to.

The walk ends when the ray leaves through the top (k = −1), the bottom (k = K) or is
absorbed. Analog Monte Carlo: unit weight for an exit, 0 for absorption. The walk is
written as resumable steps (``walk_start``/``walk_step``/``walk_done``/``walk_sample``,
the :class:`virtspec_mi.kernel.walk.RandomWalk` protocol): ``BSDF.sample`` runs them to the
end as one Dr.Jit symbolic loop, and the ray kernel drives them itself so that a SIMD lane
whose walk ends starts its next ray; random numbers from
:func:`virtspec_mi.kernel.walk.walk_rng`. Wavelength-dependent quantities (α·d_m and the three
refractive indices) are Dr.Jit arrays on the data grid gathered per lane from
``si.wavelengths[0]``: many wavelengths share one compiled kernel. The per-(interface,
direction) table (media, slab, the Warn lobes' powers 1/(e + 1)) is read by a tree of selects
rather than a per-step ``dr.gather`` (cheaper on AVX2), its powers as opaque values (one kernel
for every leaf); a lobe sample on the wrong side is retried in a step of its own.

Conventions
-----------
- **Sides.** ``side = "adaxial"`` puts the leaf's adaxial surface on the specimen's
  upper side (normal +z), ``"abaxial"`` turns the leaf over. Light arriving from above
  (the instrument's θi ∈ [0°, 90°]) then strikes that surface; back-lit rays
  (wi·n < 0) strike the other one. The instrument counts by the specimen's
  hemispheres, so **reflectance is always the light leaving on the lit side** — the
  reference's R for abaxial incidence (its "abax 8°" = ``side="abaxial"``, θi = 8°).
- ``sampled_type`` is ``GlossyReflection`` when the ray leaves on the side it came
  from, else ``GlossyTransmission``; ``sampled_component`` is 0 / 1, or
  :data:`virtspec_mi.kernel.walk.CAPPED_COMPONENT` for a walk that reached ``max_steps``
  interface events (or, never seen in practice, 1000 rejected lobe samples).
- No ``eval``/``pdf``: a sample-only BSDF (both return 0).
- ``wavelength_range = (400, 2500)`` nm: the instrument refuses other wavelengths
  with a ``ValueError`` before tracing.
- **Parameters through ``mi.traverse``.** Every numeric parameter of
  :data:`LEAF_DEFAULTS` (``thickness`` … the aspect ratios) shows as
  ``specimen.bsdf.NAME`` (an opaque ``Float64``); setting it and calling ``update()``
  checks it as at load time (``ValueError``; the leaf is left as it was) and rebuilds the
  α·d_m table (an evaluated array) and the lobe powers (opaque): one compiled walk
  serves every value. ``sieve_detour``, ``side``, ``lookup`` and ``max_steps`` are code
  (a new value compiles a new kernel) and are not exposed.

References
----------
Baranoski & Rokne (1997), CGF 16(3); Baranoski (2006), RSE 100:335–347; Baranoski & Eng
(2007), IEEE TGRS 45(8):2593–2599 (sieve and detour). The event order and its semantics
follow the NPSG reference C++ implementation (BSD-3), https://github.com/turtlesoupy/ABM-U-and-ABM-B-CPP:
``run_abm.cpp`` (the walk, ``freePathLength``, the lobe sampling), ``abm_interfaces.cpp``,
``abmb_interfaces.cpp`` and ``abmu_interfaces.cpp``.
"""

from __future__ import annotations

import math
import textwrap
from typing import Any, NamedTuple

import drjit as dr
import mitsuba as mi
import numpy as np


from virtspec_mi.plugins.leaf_data import (
    GRID,
    GRID_STEP,
    LOOKUPS,
    WAVELENGTH_RANGE,
    load_leaf_data,
    mesophyll_absorption,
)
from virtspec_mi.base.checks import FLOAT32_MAX, FLOAT32_MIN_NORMAL, check_float32
from virtspec_mi.plugins.bsdfs.sampled_only import SampledOnlyBSDF
from virtspec_mi.plugins.specimen import Parameter
from virtspec_mi.kernel.walk import CAPPED_COMPONENT, walk_rng, walk_to_end

__all__ = [
    "AIR",
    "CUTICLE",
    "MESOPHYLL",
    "ANTIDERMAL",
    "Interface",
    "ABMLeaf",
    "leaf_parameters",
    "WALKING",
    "EXIT_TOP",
    "EXIT_BOTTOM",
    "ABSORBED",
    "CAPPED",
]

# Media (refractive index): air n = 1, cuticle n_c(λ), mesophyll n_m(λ), antidermal wall n_a(λ).
AIR, CUTICLE, MESOPHYLL, ANTIDERMAL = 0, 1, 2, 3
# Walk states.
WALKING, EXIT_TOP, EXIT_BOTTOM, ABSORBED, CAPPED = 0, 1, 2, 3, 4
MAX_LOBE_TRIES: int = 1000
"""Rejected Warn-lobe samples after which a walk is reported capped (P ≈ 2⁻¹⁰⁰⁰ for a valid ray)."""


PARAMETER_DOCS: tuple[tuple[str, str, Any, str], ...] = (
    # name, type, default (None: the leaf's, from LEAF_DEFAULTS), meaning
    ("thickness", "float", None, "Whole-leaf thickness h in m (> 0)."),
    ("mesophyll_fraction", "float", None,
     "Fraction f_m of the leaf thickness that is mesophyll, 0 < f_m ≤ 1; d_m = f_m · h."),
    ("chlorophyll_a", "float", None, "Chlorophyll a per unit mesophyll volume, kg m⁻³ (= 1000 × the NPSG "
                                     "form's g cm⁻³), ≥ 0."),
    ("chlorophyll_b", "float", None, "Chlorophyll b, kg m⁻³, ≥ 0 (it shares chlorophyll a's coefficient)."),
    ("carotenoids", "float", None, "Carotenoids, kg m⁻³, ≥ 0."),
    ("protein", "float", None, "Protein, kg m⁻³, ≥ 0 (the NPSG online form's 0.078059 g cm⁻³ for soybean "
                               "drops a digit; the reference's samples/lopex_0219_0220.json holds "
                               "0.0787059)."),
    ("cellulose", "float", None, "Cellulose, kg m⁻³, ≥ 0 (corn: the NPSG online form's split of the sample "
                                 "file's 0 + 59.245619, the same sum)."),
    ("lignin", "float", None, "Lignin, kg m⁻³, ≥ 0 (it uses the cellulose coefficient)."),
    ("cuticle_aspect_ratio", "float", None,
     "σ_cu, cuticle undulations (lobe exponent; lower = more diffuse), > 0 (NPSG: 1–50)."),
    ("epidermis_aspect_ratio", "float", None, "σ_ep, epidermal cell caps, > 0."),
    ("palisade_aspect_ratio", "float", None, "σ_pa, palisade cell caps, > 0."),
    ("spongy_aspect_ratio", "float", None, "σ_sp, spongy mesophyll cell caps (ABM-U: all mesophyll), > 0."),
    ("sieve_detour", "boolean", "true", "Sieve and detour effects (Baranoski & Eng 2007; the NPSG default): "
                                         "the absorption test uses the path t / cos(cos θ); false = plain "
                                         "Beer–Lambert, t / cos θ."),
    ("side", "string", '"adaxial"', "Leaf surface facing the specimen's upper side (+z), where the "
                                     "instrument's light arrives: ``adaxial`` or ``abaxial`` (the leaf turned "
                                     "over). Reflectance is always the light leaving on the lit side."),
    ("lookup", "string", '"step"', "Spectral lookup on the 5 nm data grid: ``step`` = ⌊(λ − 400)/5⌋ as the "
                                    "NPSG C++ reference (551 nm reads the 550 nm data), ``linear`` = "
                                    "interpolation (NPSG MATLAB)."),
    ("data_dir", "string", '""', "Directory of the NPSG data files; empty = the environment variable "
                                  "``VIRTSPEC_LEAF_DATA`` if set, else the data shipped with the package "
                                  "(see :mod:`virtspec_mi.plugins.leaf_data`)."),
    ("max_steps", "integer", "100000", "Cap on interface events per walk; a walk reaching it is counted in "
                                        "``Result.capped`` (never in R, T or A). The longest soybean walks "
                                        "are ≈ 200 events."),
)
"""Every parameter of the ABM leaf plugins: name, type, default and meaning, written once."""


def parameter_docs(defaults: dict[str, float]) -> str:
    """The Parameters section of an ABM plugin's docstring, with that leaf's ``defaults``."""

    lines = []
    for name, kind, default, meaning in PARAMETER_DOCS:
        if default is None and name not in defaults:
            continue
        shown = f"{defaults[name]:.10g}" if default is None else default
        lines.append(f"{name} : {kind}, default {shown}")
        lines.extend("    " + line for line in textwrap.wrap(meaning, 84))
    return "\n".join(lines)


LEAF_DEFAULTS: tuple[tuple[str, float, float | None], ...] = (
    # parameter               soybean (ABM-B)  corn (ABM-U)   SI units; NPSG samples/lopex_*.json × 1000
    ("thickness",              1.66e-4,         2.04e-4),
    ("mesophyll_fraction",     0.5,             0.8),
    ("chlorophyll_a",          3.9775,          2.895146),
    ("chlorophyll_b",          1.1613,          0.79866),
    ("carotenoids",            1.1323,          0.658895),
    ("protein",                78.7059,         53.08714),
    ("cellulose",              37.7565,         53.18709),
    ("lignin",                 10.7441,         6.05853),
    ("cuticle_aspect_ratio",   5.0,             10.0),
    ("epidermis_aspect_ratio", 5.0,             5.0),
    ("palisade_aspect_ratio",  1.0,             None),
    ("spongy_aspect_ratio",    5.0,             5.0),
)
"""Default parameters of the two leaves: soybean (LOPEX 0219/0220, ``abm_b``) and corn
(LOPEX 0141/0142, ``abm_u``; no palisade layer), one row per parameter."""


def leaf_defaults(column: int) -> dict[str, float]:
    """The defaults of one leaf of :data:`LEAF_DEFAULTS` (0: soybean, 1: corn), in table order."""

    return {name: values[column] for name, *values in LEAF_DEFAULTS if values[column] is not None}


_UNITS: dict[str, str] = {"thickness": "m", "mesophyll_fraction": "1", "chlorophyll_a": "kg/m3",
                          "chlorophyll_b": "kg/m3", "carotenoids": "kg/m3", "protein": "kg/m3", "cellulose": "kg/m3",
                          "lignin": "kg/m3"}


def leaf_parameters(defaults: dict[str, float]) -> tuple[Parameter, ...]:
    """
    The specimen parameters of a leaf with ``defaults`` (its numeric parameters): bounds
    as the plugin checks them (> 0 or >= 0: lowest 0, none above; the mesophyll fraction
    at most 1), units as :data:`PARAMETER_DOCS` states them (aspect ratios: pure numbers).
    """

    meanings = {name: meaning for name, _, _, meaning in PARAMETER_DOCS}
    return tuple(Parameter(name, 0.0, 1.0 if name == "mesophyll_fraction" else math.inf, _UNITS.get(name, "1"),
                           meanings[name].partition(",")[0].rstrip(".")) for name in defaults)


class Interface(NamedTuple):
    """
    One interface of the stack (NPSG C++ ``abm_interfaces.cpp``).

    ``above``/``below`` are media; ``e_da``, ``e_db``, ``e_ub``, ``e_ua`` name the
    aspect-ratio parameter used as the lobe exponent (``None`` = ∞, no perturbation)
    for: going down and reflected, going down and refracted, going up and reflected,
    going up and refracted. ``slab_above``/``slab_below`` = (a, b): the slab on that
    side has optical thickness α·d_m·(a + b·u), u ~ U(0, 1) once per ray (ABM-U's
    random split of the mesophyll); (0, 0) = not absorbing.
    """

    above: int
    below: int
    e_da: str | None
    e_db: str | None
    e_ub: str | None
    e_ua: str | None
    slab_above: tuple[float, float] = (0.0, 0.0)
    slab_below: tuple[float, float] = (0.0, 0.0)


# name -> (check, allowed range in words); applied to every numeric parameter.
_POSITIVE = (lambda v: v > 0, "a finite number > 0")
_NON_NEGATIVE = (lambda v: v >= 0, "a finite number >= 0")
_CHECKS: dict[str, tuple[Any, str]] = {
    "thickness": _POSITIVE,
    "mesophyll_fraction": (lambda v: 0 < v <= 1, "a number with 0 < mesophyll_fraction <= 1"),
    "chlorophyll_a": _NON_NEGATIVE,
    "chlorophyll_b": _NON_NEGATIVE,
    "carotenoids": _NON_NEGATIVE,
    "protein": _NON_NEGATIVE,
    "cellulose": _NON_NEGATIVE,
    "lignin": _NON_NEGATIVE,
    "cuticle_aspect_ratio": _POSITIVE,
    "epidermis_aspect_ratio": _POSITIVE,
    "palisade_aspect_ratio": _POSITIVE,
    "spongy_aspect_ratio": _POSITIVE,
}
_SIDES = ("adaxial", "abaxial")
# Row code of the per-(interface, direction) table: bits 0-1 medium the ray comes from,
# bits 2-3 medium it goes to, bits 4-6 the slab just crossed: optical thickness
# α·d_m·(a + b·u) with a = bit 4, b = +1 (bit 5) or -1 (bit 6).
_SLAB_BITS = {(0.0, 0.0): 0, (1.0, 0.0): 16, (0.0, 1.0): 32, (1.0, -1.0): 16 | 64}


def _cos_unit(x: mi.Float) -> mi.Float:
    """cos x for 0 ≤ x ≤ 1 (the sieve-detour factor of a cosine): Taylor series to x¹², error < 2e-9."""

    x2 = x * x
    poly = dr.fma(x2, 1.0 / 479001600.0, -1.0 / 3628800.0)
    for coefficient in (1.0 / 40320.0, -1.0 / 720.0, 1.0 / 24.0, -0.5, 1.0):
        poly = dr.fma(poly, x2, coefficient)
    return poly


def _pick(values: list, index: mi.UInt32) -> Any:
    """
    ``values[index]`` for a short list of Dr.Jit scalars, as a tree of selects on the bits of
    ``index`` (a per-lane ``dr.gather`` from a tiny table costs more on AVX2).
    """

    level = list(values)
    bit = 0
    while len(level) > 1:
        take = (index & (1 << bit)) != 0
        level = [dr.select(take, level[i + 1], level[i]) if i + 1 < len(level) else level[i]
                 for i in range(0, len(level), 2)]
        bit += 1
    return level[0]


class ABMLeaf(SampledOnlyBSDF):
    """
    Base of the ABM leaf plugins: parameters, spectral tables and the random walk.

    Subclasses set :attr:`PLUGIN` (registry name), :attr:`DEFAULTS` (every numeric
    parameter with its default) and :attr:`INTERFACES` (the six-interface table).
    """

    PLUGIN: str = ""
    DEFAULTS: dict[str, float] = {}
    INTERFACES: tuple[Interface, ...] = ()
    wavelength_range: tuple[float, float] = WAVELENGTH_RANGE
    """Wavelengths (nm) the specimen is defined for; the instrument checks readings against it."""
    walk_steps: float = 10.0
    """Mean events per walk (lobe retries included), a queueing hint for the ray kernel
    (:func:`virtspec_mi.kernel.walk.walk_steps`): measured 10.2 over the soybean spectrum
    (400–2500 nm, θi = 8°), 5.9 at 551 nm, 15.7 at 800 nm."""

    def __init__(self, props: mi.Properties) -> None:
        super().__init__(props)
        self.params = {name: self._number(props, name, default) for name, default in self.DEFAULTS.items()}
        self.sieve_detour = self._choice(props, "sieve_detour", True, (True, False))
        self.side = self._choice(props, "side", "adaxial", _SIDES)
        self.lookup = self._choice(props, "lookup", "step", LOOKUPS)
        self.data_dir = props.get("data_dir", "")
        if not isinstance(self.data_dir, str):
            raise ValueError(f"{self.PLUGIN}: 'data_dir' must be a string path (got {self.data_dir!r})")
        steps = props.get("max_steps", 100_000)
        if isinstance(steps, bool) or not isinstance(steps, int) or not 1 <= steps < 2**31:
            raise ValueError(f"{self.PLUGIN}: 'max_steps' must be an integer, 1 <= max_steps < 2^31 (got {steps!r})")
        self.max_steps = steps
        self._build_tables()
        both_sides = mi.BSDFFlags.FrontSide | mi.BSDFFlags.BackSide
        self.m_components = [
            mi.BSDFFlags.GlossyReflection | both_sides,
            mi.BSDFFlags.GlossyTransmission | both_sides | mi.BSDFFlags.NonSymmetric,
        ]
        self.m_flags = self.m_components[0] | self.m_components[1]

    # -- parameters -------------------------------------------------------------------

    def _number(self, props: mi.Properties, name: str, default: float) -> float:
        return self._checked(name, props.get(name, default))

    def _checked(self, name: str, value: Any) -> float:
        check, allowed = _CHECKS[name]
        return check_float32(f"{self.PLUGIN}: '{name}'", value, f"be {allowed}", check)

    def exposed_parameters(self) -> dict[str, float]:
        """Every numeric parameter (``thickness``, ``chlorophyll_a`` …, the aspect ratios) for ``mi.traverse``."""

        return dict(self.params)

    def set_parameters(self, values: dict[str, float]) -> None:
        """
        New numeric parameters (each checked as at load time; ``ValueError`` leaves the leaf
        as it was), then the spectral table α·d_m and the lobe powers rebuilt as data:
        evaluated arrays and opaque scalars, so the walk's kernel is not recompiled.
        """

        unknown = sorted(set(values) - set(self.params))
        if unknown:
            raise ValueError(f"{self.PLUGIN}: no parameter {unknown[0]!r} (known: {', '.join(self.params)})")
        checked = {name: self._checked(name, value) for name, value in values.items()}
        if any(checked[name] != self.params[name] for name in checked):
            self.params = {**self.params, **checked}
            self._derived_tables()

    def _choice(self, props: mi.Properties, name: str, default: Any, allowed: tuple) -> Any:
        value = props.get(name, default)
        if value not in allowed or type(value) is not type(default):
            words = " or ".join(repr(a).lower() if isinstance(a, bool) else repr(a) for a in allowed)
            raise ValueError(f"{self.PLUGIN}: '{name}' must be {words} (got {value!r})")
        return value

    @property
    def mesophyll_thickness(self) -> float:
        """d_m = f_m · h in m (NPSG C++ ``buildInterfaces``)."""

        return self.params["mesophyll_fraction"] * self.params["thickness"]

    def absorption_coefficient(self) -> np.ndarray:
        """α(λ) of the mesophyll on the data grid (m⁻¹), for this leaf's concentrations."""

        p = self.params
        return mesophyll_absorption(
            self.data, chlorophyll_a=p["chlorophyll_a"], chlorophyll_b=p["chlorophyll_b"],
            carotenoids=p["carotenoids"], protein=p["protein"], cellulose=p["cellulose"], lignin=p["lignin"],
        )

    def _build_tables(self) -> None:
        """Spectral tables (per grid wavelength) and per-(interface, direction) rows as Dr.Jit arrays."""

        self.data = load_leaf_data(self.data_dir)
        self._n_c = mi.Float(self.data.n_cuticle)
        self._n_m = mi.Float(self.data.n_mesophyll)
        self._n_a = mi.Float(self.data.n_antidermal)
        self._derived_tables()

    def _derived_tables(self) -> None:
        """α·d_m per grid wavelength and the per-(interface, direction) rows, from :attr:`params`."""

        # α·d_m beyond float32 (a leaf metres thick, concentrations of 1e30) absorbs every
        # ray that enters the mesophyll, as the largest float32 does: no overflow to inf.
        tau = np.minimum(self.absorption_coefficient() * self.mesophyll_thickness, FLOAT32_MAX)
        self._tau = mi.Float(tau)
        # The Warn lobe cos θp = ξ^(1/(e + 1)) takes its power p = 1/(e + 1) from the table (a
        # multiply per event, not a division); e = ∞ (no perturbation) is p = 0. A finite e so
        # large that p falls below the smallest normal float32 keeps that smallest power: ξ^p
        # is the same either way (1 for ξ ≥ 2⁻²⁴, 0 for ξ = 0), and the lobe is still sampled (p > 0).
        power = {None: 0.0, **{name: max(1.0 / (self.params[name] + 1.0), FLOAT32_MIN_NORMAL)
                               for name in self.params if name.endswith("_aspect_ratio")}}
        codes, powers = [], []  # row 2k: moving down at interface k; row 2k + 1: moving up
        for face in self.INTERFACES:
            for n1, n2, e_refl, e_refr, slab in (
                (face.above, face.below, face.e_da, face.e_db, face.slab_above),
                (face.below, face.above, face.e_ub, face.e_ua, face.slab_below),
            ):
                codes.append(n1 | n2 << 2 | _SLAB_BITS[slab])
                powers += [power[e_refl], power[e_refr]]
        # Row codes are structural (literals); lobe powers are opaque: one kernel for every leaf.
        self._row_code = [mi.UInt32(c) for c in codes]
        self._row_power = [dr.opaque(mi.Float, p) for p in powers]

    # -- sampling ---------------------------------------------------------------------

    def _spectral(self, wavelength: mi.Float) -> tuple[mi.Float, mi.Float, mi.Float, mi.Float]:
        """α·d_m, n_c, n_m, n_a per lane (``lookup``: step = ⌊(λ − 400)/5⌋, or linear)."""

        last = GRID.size - 1
        x = (wavelength - WAVELENGTH_RANGE[0]) * (1.0 / GRID_STEP)
        tables = (self._tau, self._n_c, self._n_m, self._n_a)
        if self.lookup == "step":
            j = mi.UInt32(dr.clip(dr.floor(x), 0, last))
            return tuple(dr.gather(mi.Float, t, j) for t in tables)
        j = mi.UInt32(dr.clip(dr.floor(x), 0, last - 1))
        f = dr.clip(x - mi.Float(j), 0.0, 1.0)
        return tuple(dr.lerp(dr.gather(mi.Float, t, j), dr.gather(mi.Float, t, j + 1), f) for t in tables)

    def sample(self, ctx, si, sample1, sample2, active=True):
        return self.walk_sample(walk_to_end(self, self.walk_start(si, sample1, sample2, active)))

    # -- the walk as resumable steps (virtspec_mi.kernel.walk.RandomWalk) ----------------
    # State: (rng, status, w, k, steps, tau_u, tau, n_c, n_m, n_a, from_top) per lane —
    # the generator (WalkRNG), walk status, direction of travel (leaf frame), interface index, events so
    # far, the two slab thicknesses, the three refractive indices and whether light came in
    # through the top.

    def walk_start(self, si, sample1, sample2, active=True):
        """The walk state of each lane entering the leaf along ``-si.wi`` (see :class:`RandomWalk`)."""

        rng = walk_rng(sample1, sample2)
        tau, n_c, n_m, n_a = self._spectral(si.wavelengths[0])
        flip = -1.0 if self.side == "abaxial" else 1.0  # leaf z = flip · specimen z
        w = mi.Vector3f(-si.wi.x, -si.wi.y, -flip * si.wi.z)  # direction of travel, leaf frame
        from_top = w.z < 0.0
        k = dr.select(from_top, mi.Int32(0), mi.Int32(len(self.INTERFACES) - 1))
        u = rng.next_float32()  # ABM-U's mesophyll split (unused by ABM-B's table)
        alive = mi.Bool(active) & dr.full(mi.Bool, True, dr.width(sample1))
        status = dr.select(alive, mi.UInt32(WALKING), mi.UInt32(ABSORBED))
        return (rng, status, w, k, mi.UInt32(0), tau * u, tau, n_c, n_m, n_a, from_top, mi.Bool(False), mi.Bool(False),
                mi.UInt32(0))

    def walk_done(self, state):
        """True where the walk has ended (exit, absorption or cap)."""

        return state[1] != WALKING

    def walk_sample(self, state):
        """The ``(BSDFSample3f, weight)`` of finished walks."""

        status, w, from_top = state[1], state[2], state[10]
        flip = -1.0 if self.side == "abaxial" else 1.0
        exits = (status == EXIT_TOP) | (status == EXIT_BOTTOM)
        reflected = (status == EXIT_TOP) == from_top
        bs = dr.zeros(mi.BSDFSample3f)
        bs.wo = mi.Vector3f(w.x, w.y, flip * w.z)
        bs.pdf = dr.select(exits, 1.0, 0.0)
        bs.eta = 1.0
        bs.sampled_component = dr.select(
            status == CAPPED, mi.UInt32(CAPPED_COMPONENT), dr.select(reflected, mi.UInt32(0), mi.UInt32(1))
        )
        bs.sampled_type = dr.select(
            reflected, mi.UInt32(+mi.BSDFFlags.GlossyReflection), mi.UInt32(+mi.BSDFFlags.GlossyTransmission)
        )
        return bs, dr.select(exits, mi.Spectrum(1.0), mi.Spectrum(0.0))

    def walk_step(self, state):
        """
        One step (NPSG C++ ``run_abm.cpp``) of the lanes the caller runs: an interface event —
        absorption test, Fresnel choice and one Warn-lobe sample — or, for a lane whose
        lobe sample fell on the wrong side, the next lobe sample of that event. The lobe's
        retries are steps of their own (no loop inside a step), so a packet of lanes never
        waits for one lane's retries; each step draws four numbers of its ray's stream, so a
        ray's walk is the same whichever lane runs it.
        """

        rng, status, w, k, steps, tau_u, tau, n_c, n_m, n_a, from_top, retry, reflect_before, tries = state
        last = len(self.INTERFACES) - 1
        fresh = ~retry
        down = w.z < 0.0
        row = mi.UInt32(dr.clip(k, 0, last)) * 2 + dr.select(down, mi.UInt32(0), mi.UInt32(1))
        code = _pick(self._row_code, row)
        m1, m2 = code & 3, (code >> 2) & 3
        slab = dr.select((code & 16) != 0, tau, 0.0) + dr.select(
            (code & 32) != 0, tau_u, dr.select((code & 64) != 0, -tau_u, 0.0))
        cos_i = dr.abs(w.z)
        # Four numbers per step, drawn first and unmasked (a retry uses the last two): all four
        # hashes run in parallel, none waits for the absorption test or the Fresnel choice.
        u_absorb, u_fresnel, u_cos, u_phi = (rng.next_float32() for _ in range(4))
        # 1. absorption in the slab just crossed: p = -ln ξ / α · g(cos θ) < t, ξ ∈ (0, 1]
        g = _cos_unit(cos_i) if self.sieve_detour else cos_i
        absorbed = fresh & (-dr.log(1.0 - u_absorb) * g < slab)
        # 2. Fresnel choice (a retry keeps its event's choice)
        n1 = dr.select(m1 == CUTICLE, n_c, dr.select(m1 == MESOPHYLL, n_m, dr.select(m1 == ANTIDERMAL, n_a, 1.0)))
        n2 = dr.select(m2 == CUTICLE, n_c, dr.select(m2 == MESOPHYLL, n_m, dr.select(m2 == ANTIDERMAL, n_a, 1.0)))
        fresnel, cos_t, _, eta_ti = mi.fresnel(cos_i, n2 / n1)
        reflect = dr.select(fresh, u_fresnel < fresnel, reflect_before)
        # 3. new direction: mirror, or refraction (tangential part scaled by n1/n2)
        specular = dr.select(
            reflect,
            mi.Vector3f(w.x, w.y, -w.z),
            mi.Vector3f(eta_ti * w.x, eta_ti * w.y, dr.select(down, -1.0, 1.0) * dr.abs(cos_t)),
        )
        power = _pick(self._row_power, row * 2 + dr.select(reflect, mi.UInt32(0), mi.UInt32(1)))
        go_down = down ^ reflect
        # 4. one Warn-lobe sample about the specular direction; wrong side: retried next step
        frame = mi.Frame3f(specular)
        perturb = ~absorbed & (power > 0.0)
        cos_p = dr.exp2(dr.log2(u_cos) * power)  # ξ^(1/(e + 1))
        sin_p = dr.safe_sqrt(1.0 - cos_p * cos_p)
        sin_phi, cos_phi = dr.sincos(dr.two_pi * u_phi)
        local = mi.Vector3f(sin_p * cos_phi, sin_p * sin_phi, cos_p)
        z = dr.fma(frame.n.z, local.z, dr.fma(frame.t.z, local.y, frame.s.z * local.x))  # as Frame3f.to_world
        tries = dr.select(fresh, mi.UInt32(0), tries) + dr.select(perturb, mi.UInt32(1), mi.UInt32(0))
        wrong_side = perturb & (((z < 0.0) != go_down) | (z == 0.0))
        retry = wrong_side & (tries < MAX_LOBE_TRIES)
        lobe_failed = wrong_side & ~retry
        turned = frame.to_world(local)
        new_w = dr.select(perturb, mi.Vector3f(turned.x, turned.y, z), specular)
        # 5. next state (a lane that retries keeps its state)
        stay = absorbed | retry
        k_new = dr.select(stay, k, k + dr.select(go_down, mi.Int32(1), mi.Int32(-1)))
        w = dr.select(stay, w, new_w)
        steps_new = steps + 1
        status_new = dr.select(
            absorbed,
            mi.UInt32(ABSORBED),
            dr.select(k_new < 0, mi.UInt32(EXIT_TOP),
                      dr.select(k_new > last, mi.UInt32(EXIT_BOTTOM), mi.UInt32(WALKING))),
        )
        status_new = dr.select(lobe_failed | ((status_new == WALKING) & (steps_new >= self.max_steps)),
                               mi.UInt32(CAPPED), status_new)
        status = dr.select(retry, status, status_new)
        steps = dr.select(retry, steps, steps_new)
        return (rng, status, w, k_new, steps, tau_u, tau, n_c, n_m, n_a, from_top, retry, reflect, tries)

    # -- the rest of the BSDF interface ------------------------------------------------

    def to_string(self) -> str:
        params = ", ".join(f"{name}={value:g}" for name, value in self.params.items())
        return (f"{type(self).__name__}[{params}, sieve_detour={self.sieve_detour}, side={self.side}, "
                f"lookup={self.lookup}, max_steps={self.max_steps}]")
