"""
Targets: the quantity a user wants, its tolerance, and how to size its rays
===========================================================================

A target names a derived quantity and the tolerance it must be certified to; the
instrument (:mod:`~virtspec_mi.applications.targets.measure`) picks the wavelengths, the
rays per wavelength (Nₖ ∝ |wₖ|, :func:`~.functionals.allocate`) and the rays in all. Each
target is a small set of linear functionals (:class:`~.functionals.Functional`) stated
together at δ (δ/m each, a union bound), and a map from their certified box to what is
reported:

- :class:`BandTarget` (``vm.band``): band values, each to ±tolerance (linear: no pilot).
- :class:`FaparTarget` (``vm.fapar``): the absorbed share of the PAR photons (400–700 nm
  by default) of an illuminant, a functional of absorptance, to ±tolerance.
- :class:`IndexTarget` (``vm.index``): a normalised-difference index to ±tolerance (its
  exact interval over the bands' box, :mod:`.indices`), and its bands.
- :class:`ColourTarget` (``vm.colour``): CIE XYZ, L*a*b*, sRGB with ΔE₀₀ of the certified
  box around the estimate ≤ ``tolerance_dE00`` (:mod:`.colour`, :mod:`.delta_e`).

The targets are chosen from one table, :data:`TARGETS` (name → :class:`TargetKind`: a
constructor, whose signature gives a text's ``:`` arguments and options): the parser, the
API's messages, the command line's ``--target`` help and the package's top-level names
read it, so a new target is one constructor and one row.

The nonlinear ones need to know how steep their map is at this specimen: a small pilot
(rays spent, not in the estimates) gives the point where the tolerances of the
functionals are chosen (:meth:`Target.tolerances`); the certificate itself is computed
afterwards from the rays the second batch actually spent, so the pilot only decides
how many rays there are, never what is claimed.

References
----------
Hoeffding (1963), Theorem 2; CIE 015:2018; ASTM E308.
"""

from __future__ import annotations

import inspect
import math
import typing
from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np

from virtspec_mi.applications.targets.bands import Band, band as make_band
from virtspec_mi.base.checks import MAX_RAYS, real
from virtspec_mi.base.surface import spoken
from virtspec_mi.budgets.functionals import Functional
from virtspec_mi.applications.targets.indices import Index, index_definition
from virtspec_mi.colorimetry.cie import DEFAULT_ILLUMINANT, DEFAULT_OBSERVER

__all__ = ["Value", "Target", "BandTarget", "FaparTarget", "IndexTarget", "ColourTarget", "band", "fapar", "index",
           "colour", "albedo", "MARGIN", "colour_of", "TargetKind", "TARGETS", "target_kind"]

MARGIN: float = 0.8
"""Share of a nonlinear target's tolerance the second batch is sized for from the pilot's point (the rest
absorbs the pilot's error: the certificate is computed from the rays spent in any case)."""


@dataclass(frozen=True)
class Value:
    """One reported quantity: ``value`` within [``lower``, ``upper``] (certified jointly with the target's others)."""

    name: str
    value: float
    lower: float
    upper: float
    units: str
    long_name: str

    @property
    def half_width(self) -> float:
        """The largest distance from the value to a bound."""

        return max(self.value - self.lower, self.upper - self.value)


_SMALLEST = 1.0 / MAX_RAYS
"""No rule certifies a fraction within less than 1/N with N rays (N <= MAX_RAYS a reading): the smallest tolerance."""


def _check_tolerance(name: str, value: Any, high: float) -> float:
    if isinstance(value, (str, bytes)):
        raise ValueError(f"{name} must be a number in (0, {high:g}], not text (got {value!r})")
    try:
        value = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a number in (0, {high:g}] (got {value!r})") from None
    if not 0 < value <= high or not math.isfinite(value):
        raise ValueError(f"{name} must be a number in (0, {high:g}] (got {value!r})")
    if value < _SMALLEST:
        raise ValueError(f"{name} must be at least {_SMALLEST:.3g} (got {value:g}): no rule certifies a value within "
                         f"less with the at most {MAX_RAYS:,} rays a reading may spend")
    return value


@dataclass(frozen=True)
class Target:
    """A derived quantity and its tolerance (see the module docstring)."""

    kind: str = field(default="", init=False)

    @property
    def needs_pilot(self) -> bool:
        return False

    def functionals(self) -> list[Functional]:
        raise NotImplementedError

    def tolerances(self, estimates: np.ndarray | None, delta: float, margin: float = MARGIN) -> np.ndarray:
        """
        The tolerance each functional is sized for (from the pilot's ``estimates`` when
        nonlinear, for ``margin`` of the target's tolerance: :data:`MARGIN` by default).
        """

        raise NotImplementedError

    def values(self, estimates: np.ndarray, tolerances: np.ndarray) -> list[Value]:
        """What is reported, from the functionals' estimates and certified tolerances."""

        raise NotImplementedError

    def met(self, values: list[Value]) -> bool:
        """Whether the certified values meet the tolerance asked for."""

        raise NotImplementedError

    def describe(self) -> str:
        raise NotImplementedError

    def as_dict(self) -> dict[str, Any]:
        raise NotImplementedError


def _linear_values(functionals: list[Functional], estimates: np.ndarray, tolerances: np.ndarray) -> list[Value]:
    out = []
    for f, value, t in zip(functionals, estimates, tolerances):
        low = float(f.weights[f.weights < 0].sum())
        high = float(f.weights[f.weights > 0].sum())
        out.append(Value(f.name, float(value), max(low, float(value - t)), min(high, float(value + t)), f.units,
                         f.long_name))
    return out


@dataclass(frozen=True)
class BandTarget(Target):
    """Band values (``bands``: :class:`~.bands.Band` s) of ``quantity``, each to ±``tolerance``."""

    bands: tuple[Band, ...] = ()
    tolerance: float = 0.002
    quantity: str = "reflectance"
    kind: str = field(default="band", init=False)

    def functionals(self) -> list[Functional]:
        return [b.functional(self.quantity) for b in self.bands]

    def tolerances(self, estimates: np.ndarray | None, delta: float, margin: float = MARGIN) -> np.ndarray:
        return np.full(len(self.bands), self.tolerance)

    def values(self, estimates: np.ndarray, tolerances: np.ndarray) -> list[Value]:
        return _linear_values(self.functionals(), estimates, tolerances)

    def met(self, values: list[Value]) -> bool:
        return all(v.half_width <= self.tolerance * (1 + 1e-12) for v in values)

    def describe(self) -> str:
        return (f"{self.quantity} in band{'s' if len(self.bands) > 1 else ''} "
                f"{', '.join(f'{b.name} ({b.edges[0]:g}-{b.edges[1]:g} nm)' for b in self.bands)} to "
                f"+-{self.tolerance:g}")

    def as_dict(self) -> dict[str, Any]:
        return {"kind": self.kind, "bands": [b.name for b in self.bands], "tolerance": self.tolerance,
                "quantity": self.quantity}


@dataclass(frozen=True)
class FaparTarget(Target):
    """
    fAPAR: the share of the PAR photons (``low``–``high`` nm, every ``step`` nm) of
    ``illuminant`` (a name of ``colour.SDS_ILLUMINANTS``, default D65; photons ∝ E(λ)·λ)
    the specimen absorbs, to ±``tolerance``.
    """

    tolerance: float = 0.002
    illuminant: str = "D65"
    low: float = 400.0
    high: float = 700.0
    step: float = 1.0
    kind: str = field(default="fapar", init=False)

    def functionals(self) -> list[Functional]:
        import colour

        from virtspec_mi.applications.targets.bands import quadrature_weights

        if self.illuminant not in colour.SDS_ILLUMINANTS:
            raise ValueError(f"illuminant must be a name of colour.SDS_ILLUMINANTS, e.g. D65 (got {self.illuminant!r})")
        light = colour.SDS_ILLUMINANTS[self.illuminant]
        grid = make_band((self.low, self.high), step=self.step).wavelengths
        if grid[0] < light.wavelengths[0] or grid[-1] > light.wavelengths[-1]:
            raise ValueError(f"fAPAR range {self.low:g}-{self.high:g} nm lies outside illuminant {self.illuminant}'s "
                             f"data ({light.wavelengths[0]:g}-{light.wavelengths[-1]:g} nm)")
        photons = np.interp(grid, light.wavelengths, light.values) * grid * quadrature_weights(grid)
        return [Functional("fapar", grid, photons / photons.sum(), "absorptance", "1",
                           f"absorbed share of the {self.illuminant} PAR photons, {self.low:g}-{self.high:g} nm")]

    def tolerances(self, estimates: np.ndarray | None, delta: float, margin: float = MARGIN) -> np.ndarray:
        return np.array([self.tolerance])

    def values(self, estimates: np.ndarray, tolerances: np.ndarray) -> list[Value]:
        return _linear_values(self.functionals(), estimates, tolerances)

    def met(self, values: list[Value]) -> bool:
        return values[0].half_width <= self.tolerance * (1 + 1e-12)

    def describe(self) -> str:
        return f"fAPAR ({self.illuminant} photons, {self.low:g}-{self.high:g} nm) to +-{self.tolerance:g}"

    def as_dict(self) -> dict[str, Any]:
        return {"kind": self.kind, "tolerance": self.tolerance, "illuminant": self.illuminant, "low": self.low,
                "high": self.high, "step": self.step}


def _scaled(shape: np.ndarray, fits: Callable[[np.ndarray], bool],
            unmet: str = "no tolerance of the functionals meets the target at the pilot's point") -> np.ndarray:
    """About the largest s·``shape`` (bisection on s) for which ``fits`` holds; ``ValueError(unmet)`` if none does."""

    low, high = 0.0, 1.0
    while fits(high * shape) and high < 1e6:
        low, high = high, high * 2
    for _ in range(14):  # s within 2^-14 of the largest that fits (from below: it always fits)
        middle = (low + high) / 2
        if fits(middle * shape):
            low = middle
        else:
            high = middle
    if low == 0.0:
        raise ValueError(unmet)
    return low * shape


@dataclass(frozen=True)
class IndexTarget(Target):
    """A normalised-difference index (:mod:`.indices`) to ±``tolerance``, its two bands reported too."""

    index: Index = None  # type: ignore[assignment]
    tolerance: float = 0.005
    step: float = 1.0
    kind: str = field(default="index", init=False)

    @property
    def needs_pilot(self) -> bool:
        return True

    def _bands(self) -> tuple[Band, Band]:
        return make_band(self.index.plus, step=self.step), make_band(self.index.minus, step=self.step)

    def functionals(self) -> list[Functional]:
        return [b.functional("reflectance") for b in self._bands()]

    def tolerances(self, estimates: np.ndarray | None, delta: float, margin: float = MARGIN) -> np.ndarray:
        a, b = np.clip(np.asarray(estimates, dtype=np.float64), 1e-6, 1.0)
        gradient = np.abs(np.array(self.index.gradient(a, b))) + 1e-9
        shape = gradient ** (-1.0 / 3.0)  # least rays for a linear budget: t_j ∝ |g_j|^(-1/3)

        def fits(t: np.ndarray) -> bool:
            try:
                low, high = self.index.interval((a - t[0], a + t[0]), (b - t[1], b + t[1]))
            except ValueError:
                return False
            centre = self.index.value(a, b)
            return max(centre - low, high - centre) <= margin * self.tolerance

        pilot = np.asarray(estimates, dtype=np.float64)
        return _scaled(shape, fits, f"{self.index.name} cannot be certified to +-{self.tolerance:g} for this specimen: "
                                    f"its pilot reads the bands at {pilot[0]:.3g} and {pilot[1]:.3g}, and a normalised "
                                    "difference of bands this dark (a + b near 0) is undefined or moves by more than "
                                    "the tolerance within any interval the rays can give; measure the bands instead "
                                    f"({spoken('vm.band(...)', '--target band:...')}), or loosen tolerance")

    def values(self, estimates: np.ndarray, tolerances: np.ndarray) -> list[Value]:
        bands = _linear_values(self.functionals(), estimates, tolerances)
        low, high = self.index.interval((bands[0].lower, bands[0].upper), (bands[1].lower, bands[1].upper))
        value = self.index.value(*np.clip(estimates, 0.0, 1.0))
        return [Value(self.index.name, value, low, high, "1",
                      f"{self.index.long_name} ({self.index.reference})"), *bands]

    def met(self, values: list[Value]) -> bool:
        return values[0].half_width <= self.tolerance * (1 + 1e-12)

    def describe(self) -> str:
        a, b = self._bands()
        return (f"{self.index.name} = ({a.name} - {b.name})/({a.name} + {b.name}) to +-{self.tolerance:g}")

    def as_dict(self) -> dict[str, Any]:
        return {"kind": self.kind, "index": self.index.name, "plus": str(self.index.plus),
                "minus": str(self.index.minus), "tolerance": self.tolerance, "step": self.step}


@dataclass(frozen=True)
class ColourTarget(Target):
    """
    The colour of ``quantity`` under ``illuminant`` and ``observer`` with ΔE₀₀ ≤
    ``tolerance_dE00`` over the certified box, from readings every ``step`` nm over
    the observer's range (within the specimen's data: :mod:`~virtspec_mi.applications.targets.measure` clips it).
    """

    tolerance_dE00: float = 0.5
    illuminant: str = DEFAULT_ILLUMINANT
    observer: str = DEFAULT_OBSERVER
    quantity: str = "reflectance"
    step: float = 10.0
    low: float | None = None
    high: float | None = None
    kind: str = field(default="colour", init=False)

    @property
    def needs_pilot(self) -> bool:
        return True

    def grid(self) -> np.ndarray:
        import colour

        if self.observer not in colour.MSDS_CMFS:
            raise ValueError(f"observer must be a name of colour.MSDS_CMFS, e.g. {DEFAULT_OBSERVER!r} "
                             f"(got {self.observer!r})")
        if self.illuminant not in colour.SDS_ILLUMINANTS:
            raise ValueError(f"illuminant must be a name of colour.SDS_ILLUMINANTS, e.g. D65, A, D50 "
                             f"(got {self.illuminant!r})")
        shape = colour.MSDS_CMFS[self.observer].shape
        low = max(shape.start, self.low if self.low is not None else shape.start)
        high = min(shape.end, self.high if self.high is not None else shape.end)
        first = math.ceil(low / self.step) * self.step
        return np.arange(first, high + 1e-9, self.step)

    def functionals(self) -> list[Functional]:
        from virtspec_mi.colorimetry.certified import colour_functionals

        return colour_functionals(self.grid(), self.quantity, self.illuminant, self.observer)

    def tolerances(self, estimates: np.ndarray | None, delta: float, margin: float = MARGIN) -> np.ndarray:
        from virtspec_mi.colorimetry.delta_e import lab_box, radius

        functionals = self.functionals()
        XYZ = np.maximum(np.asarray(estimates, dtype=np.float64), 1e-3)
        estimate = colour_of(XYZ, functionals, self)
        white = _white(functionals)
        floor = np.maximum(np.array([f.weights[f.weights < 0].sum() for f in functionals]), 0.0)

        def radius_of(t: np.ndarray) -> float:  # the certificate's ΔE₀₀ radius for tolerances t (no sRGB)
            return radius(estimate.Lab, lab_box(np.maximum(XYZ - t, floor), XYZ + t, white))[0]

        probe = 1e-3 * XYZ.max()
        base = radius_of(np.full(3, 1e-12))
        slopes = np.array([(radius_of(np.where(np.arange(3) == j, probe, 1e-12)) - base) / probe for j in range(3)])
        shape = (np.abs(slopes) + 1e-9) ** (-1.0 / 3.0) * np.array([f.total_weight for f in functionals]) ** (2 / 3)
        return _scaled(shape / shape.max(), lambda t: radius_of(t) <= margin * self.tolerance_dE00)

    def values(self, estimates: np.ndarray, tolerances: np.ndarray) -> list[Value]:
        raise NotImplementedError("a colour target's values come with its CertifiedColour (see measure)")

    def met(self, values: list[Value]) -> bool:
        radius = next(v for v in values if v.name == "dE00_radius")
        return radius.value <= self.tolerance_dE00

    def describe(self) -> str:
        return (f"colour of the {self.quantity} ({self.illuminant}, {self.observer}) to dE00 <= "
                f"{self.tolerance_dE00:g}")

    def as_dict(self) -> dict[str, Any]:
        return {"kind": self.kind, "tolerance_dE00": self.tolerance_dE00, "illuminant": self.illuminant,
                "observer": self.observer, "quantity": self.quantity, "step": self.step}


def _white(functionals: list[Functional]) -> np.ndarray:
    """xy of the perfect diffuser through the functionals (X, Y, Z): the white point colorimetry uses."""

    import colour as cs

    return np.asarray(cs.XYZ_to_xy(np.array([f.weights.sum() for f in functionals]) / 100.0))


def colour_of(XYZ: np.ndarray, functionals: list[Functional], target: ColourTarget) -> Any:
    """The plain Colour of tristimulus values ``XYZ`` of ``functionals`` (as colorimetry gives it: white Σ w)."""

    import colour as cs

    from virtspec_mi.colorimetry.cie import Colour

    white = _white(functionals)
    Lab = np.asarray(cs.XYZ_to_Lab(np.asarray(XYZ) / 100.0, white), dtype=np.float64)
    sRGB = np.asarray(cs.XYZ_to_sRGB(np.asarray(XYZ) / 100.0, illuminant=white), dtype=np.float64)
    return Colour(np.asarray(XYZ), Lab, sRGB, target.illuminant, target.observer, functionals[0].wavelengths)


# -- the constructors (a row each of TARGETS: vm.colour, vm.band, vm.index, vm.fapar, vm.albedo) ----


def band(response: Any = "B04", /, *more: Any, tolerance: float = 0.002, quantity: str = "reflectance",
         step: float = 1.0) -> BandTarget:
    """
    A band target: ``response`` (and ``more`` bands) each a Sentinel-2 band name, edges
    ``(low, high)`` nm, a dict ``{nm: response}`` or a two-column file
    (:func:`~.bands.band`), certified together to ±``tolerance`` (absolute).
    """

    from virtspec_mi.budgets.functionals import QUANTITIES

    if quantity not in QUANTITIES:
        raise ValueError(f"quantity must be one of {', '.join(QUANTITIES)} (got {quantity!r})")
    bands = tuple(r if isinstance(r, Band) else make_band(r, step=step) for r in (response, *more))
    names = [b.name for b in bands]
    if len(set(names)) != len(names):
        raise ValueError(f"bands must have distinct names (got {names})")
    return BandTarget(bands, _check_tolerance("tolerance", tolerance, 1.0), quantity)


def fapar(tolerance: float = 0.002, illuminant: str = "D65", low: float = 400.0, high: float = 700.0,
          step: float = 1.0) -> FaparTarget:
    """fAPAR (absorbed share of PAR photons of ``illuminant``, ``low``–``high`` nm) to ±``tolerance``."""

    low, high = real("low", low), real("high", high)
    if not 0 < low < high:
        raise ValueError(f"low and high must satisfy 0 < low < high nm (got {low!r}, {high!r})")
    target = FaparTarget(_check_tolerance("tolerance", tolerance, 1.0), illuminant, float(low), float(high),
                         float(step))
    target.functionals()  # checks the illuminant and range now
    return target


def index(name: str = "NDVI", /, bands: dict[str, Any] | None = None, tolerance: float = 0.005,
          step: float = 1.0) -> IndexTarget:
    """A normalised-difference index (NDVI, GNDVI, NDRE, PRI; ``bands`` replaces its bands) to ±``tolerance``."""

    return IndexTarget(index_definition(name, bands), _check_tolerance("tolerance", tolerance, 2.0), float(step))


def colour(tolerance_dE00: float | None = None, illuminant: str = DEFAULT_ILLUMINANT,
           observer: str = DEFAULT_OBSERVER, quantity: str = "reflectance", step: float = 10.0, *,
           dE00: float | None = None) -> ColourTarget:
    """
    The colour (XYZ, L*a*b*, sRGB) certified to ΔE₀₀ ≤ ``tolerance_dE00`` (default 0.5) over
    its certified box. ``dE00`` is the same tolerance by its short name, the one a text
    writes (``--target colour,dE00=0.5``; a text takes ``tolerance_dE00=`` too): give one.
    """

    from virtspec_mi.budgets.functionals import QUANTITIES

    if tolerance_dE00 is not None and dE00 is not None:
        raise ValueError("tolerance_dE00 and dE00 are one tolerance (dE00 its short name): give one")
    tolerance_dE00 = 0.5 if tolerance_dE00 is None and dE00 is None else \
        tolerance_dE00 if tolerance_dE00 is not None else dE00

    if quantity not in QUANTITIES:
        raise ValueError(f"quantity must be one of {', '.join(QUANTITIES)} (got {quantity!r})")
    if step not in (1, 5, 10, 20):
        raise ValueError(f"step must be 1, 5, 10 or 20 nm (ASTM E308 weights) (got {step!r})")
    target = ColourTarget(_check_tolerance("tolerance_dE00", tolerance_dE00, 100.0), illuminant, observer, quantity,
                          float(step))
    target.grid()
    return target


def albedo(tolerance: float = 0.002, illuminant: str = "D65", low: float | None = None, high: float | None = None,
           quantity: str = "reflectance", step: float = 1.0) -> BandTarget:
    """
    An illuminant-weighted albedo: the mean ``quantity`` weighted by the spectral power of
    ``illuminant`` (a name of ``colour.SDS_ILLUMINANTS``; CIE D65 daylight by default, over
    its 300–780 nm unless ``low``/``high`` narrow it), to ±``tolerance``: a band whose
    response is the illuminant. A broadband solar albedo needs a solar spectrum (e.g. ASTM
    G173) given as a band's response: ``vm.band({wavelength: irradiance, ...})``.
    """

    import colour as cs

    if illuminant not in cs.SDS_ILLUMINANTS:
        raise ValueError(f"illuminant must be a name of colour.SDS_ILLUMINANTS, e.g. D65 (got {illuminant!r})")
    light = cs.SDS_ILLUMINANTS[illuminant]
    first, last = float(light.wavelengths[0]), float(light.wavelengths[-1])
    low, high = first if low is None else real("low", low), last if high is None else real("high", high)
    if not first <= low < high <= last:
        raise ValueError(f"low and high must satisfy {first:g} <= low < high <= {last:g} nm, the data of illuminant "
                         f"{illuminant} (got {low:g}, {high:g})")
    grid = make_band((low, high), step=step).wavelengths
    response = {float(w): float(v) for w, v in zip(grid, np.interp(grid, light.wavelengths, light.values))}
    weighted = make_band(response, name=f"albedo_{illuminant}")
    weighted = Band(weighted.name, weighted.wavelengths, weighted.response, f"weighted by illuminant {illuminant}")
    return band(weighted, tolerance=tolerance, quantity=quantity, step=step)


# -- the table of targets ---------------------------------------------------------------------------

_TEXT_TYPES: dict[Any, type] = {float: float, int: int, str: str, bool: bool}


@dataclass(frozen=True)
class TargetKind:
    """
    One row of :data:`TARGETS`: a target's constructor, and how a text names it. Its
    positional-only parameters and ``*args`` take the ``:`` arguments of a text
    (``band:B04:B08``); its other parameters of a plain type (``float``, ``int``, ``str``,
    ``bool``, or one of them or ``None``) are its options (``NAME=VALUE``, converted by
    their annotation); ``spellings`` are other names of the kind (``color``) and
    ``short`` the options' short names (``dE00`` for ``tolerance_dE00``).
    """

    make: Callable[..., Target]
    spellings: tuple[str, ...] = ()
    short: tuple[tuple[str, str], ...] = ()

    def _parameters(self) -> list[inspect.Parameter]:
        return list(inspect.signature(self.make).parameters.values())

    def arguments(self) -> tuple[int, int | None]:
        """How many ``:`` arguments it takes: (fewest, most; ``None``: any)."""

        positional = [p for p in self._parameters() if p.kind is p.POSITIONAL_ONLY]
        many = any(p.kind is p.VAR_POSITIONAL for p in self._parameters())
        return (1 if positional or many else 0), (None if many else len(positional))

    def options(self) -> dict[str, type]:
        """Each option as a text writes it (short names first) → the type its value is converted to."""

        hints = typing.get_type_hints(self.make)
        kinds = {}
        for parameter in self._parameters():
            if parameter.kind in (parameter.POSITIONAL_ONLY, parameter.VAR_POSITIONAL, parameter.VAR_KEYWORD):
                continue
            hint = hints.get(parameter.name, Any)
            plain = [t for t in typing.get_args(hint) if t is not type(None)] if typing.get_args(hint) else [hint]
            if len(plain) == 1 and plain[0] in _TEXT_TYPES:
                kinds[dict((long, short) for short, long in self.short).get(parameter.name, parameter.name)] = plain[0]
        return kinds

    def keyword(self, option: str) -> str:
        """The constructor's keyword of ``option`` as a text writes it."""

        return dict(self.short).get(option, option)

    def describe(self, name: str) -> str:
        """The row in words: ``band[:ARG...][,NAME=VALUE ...] (NAME: tolerance, quantity, step)``."""

        low, high = self.arguments()
        arguments = "" if high == 0 else ":ARG" if high == 1 else ":ARG..."
        return f"{name}{arguments} ({', '.join(self.options()) or 'no options'})"


TARGETS: dict[str, TargetKind] = {
    "colour": TargetKind(colour, spellings=("color",), short=(("dE00", "tolerance_dE00"),)),
    "band": TargetKind(band),
    "index": TargetKind(index),
    "fapar": TargetKind(fapar),
    "albedo": TargetKind(albedo),
}
"""
The targets by name → their row (:class:`TargetKind`: a constructor and how a text names
it). The parser (:func:`~.parse.parse_target`), ``vm.measure(target=...)``'s message, the
command line's ``--target`` help and the package's top-level names (``vm.colour`` …) read
it: a new target is one constructor and one row.
"""


def target_kind(word: str) -> tuple[str, TargetKind]:
    """The row of :data:`TARGETS` that ``word`` names (a name or a spelling, any case), or ``ValueError``."""

    folded = word.strip().lower()
    for name, kind in TARGETS.items():
        if folded == name.lower() or folded in (s.lower() for s in kind.spellings):
            return name, kind
    raise ValueError(f"the kind must be one of {', '.join(TARGETS)} (got {word!r})")
