"""
Checks of measurement inputs: one message style, naming the parameter and its range
===================================================================================

The bottom of the package: every check that turns user input into a validated value
(:mod:`virtspec_mi.settings`, :mod:`virtspec_mi.budgets.bounds`, :mod:`virtspec_mi.geometry.disks`,
the specimen plugins, …) lives here, so each rule is written once. A bad value raises
``ValueError`` with a message such as
``theta_i must satisfy 0 <= theta_i <= 90 degrees (got 95)``; values are shown with
all the digits they were given (``399.99999999``, not ``400``).

Values are checked once, where they enter: the settings and options dataclasses, and
the few functions users call directly (:func:`validated` makes such an entry of a
function that trusts its arguments, and keeps the trusting function for the callers
below the boundary as ``.unchecked``).

Limits
------
Every cap of a call is a constant here, checked *before* anything of that size is
built (lists, kernels), so a request beyond them is refused in milliseconds:

- :data:`MAX_RAYS` rays per reading (rays are numbered with 32 bits within a
  reading), whether given (``rays``, ``pilot_rays``, ``spp``) or computed by a bound;
- :data:`MAX_VALUES` wavelengths and incidence angles per call, counted before a
  ``start:stop:step`` range is expanded;
- :data:`MAX_READINGS` readings (wavelength × θi) per call and :data:`MAX_TOTAL_RAYS`
  rays per call;
- :data:`WAVELENGTH_RANGE`: wavelengths the kernel's float32 arithmetic holds;
  :data:`NANOMETRE_FLOOR`: a set of wavelengths all below it looks like micrometres;
- :data:`MAX_CHUNK_SIZE` rays per kernel launch (memory).
"""

from __future__ import annotations

import functools
import inspect
import math
import re
import sys
from typing import Any, Callable, Iterable, TypeVar

import numpy as np

__all__ = [
    "MAX_RAYS",
    "MAX_VALUES",
    "parse_values",
    "value_tokens",
    "MAX_READINGS",
    "MAX_TOTAL_RAYS",
    "MAX_CHUNK_SIZE",
    "WAVELENGTH_RANGE",
    "FLOAT32_MIN_NORMAL",
    "FLOAT32_MAX",
    "shown_value",
    "number",
    "real",
    "check_mu",
    "check_delta",
    "check_rays",
    "check_rays_needed",
    "check_bins",
    "check_relative_tolerance",
    "check_brdf_floor",
    "validated",
    "check_readings",
    "check_theta_i",
    "check_positive",
    "check_float32",
    "parse_wavelengths",
    "parse_theta_i",
    "check_wavelength_range",
    "NANOMETRE_FLOOR",
    "check_nanometres",
]

MAX_RAYS: int = 2**32 - 1
"""Most rays one reading may use (its rays are numbered with 32 bits)."""

MAX_VALUES: int = 100_000
"""
Most wavelengths, and most incidence angles, one call takes. A spectrum at 0.1 nm over
400–2500 nm is 21,001 values and the paper's Fig. 5 is 91 angles; ``"400:700:1e-6"``
(3·10⁸ values) is refused before its list is built.
"""

MAX_READINGS: int = 1_000_000
"""
Most readings (wavelengths × angles) one call takes. The engine's bookkeeping costs
about 1.3–1.8 KB of host memory and 14 µs per reading (measured with 10⁶ one-ray
readings: +1.25 GiB, 14 s), so this bounds it near 1.5 GiB; a 2,101-wavelength ×
91-angle leaf survey is 191,191 readings.
"""

MAX_TOTAL_RAYS: int = 10**13
"""
Most rays one call traces (every reading, two-stage pilots included): about 16 hours
at the 175 Mray/s this project's 2-core machine reaches on its fastest specimen. A
request beyond is almost certainly a mistake (μ or δ off by orders of magnitude); a
sweep can be split into several calls.
"""

MAX_CHUNK_SIZE: int = 2**25
"""
Most rays per kernel launch (``chunk_size``). Peak memory grows linearly with the
chunk: measured 12 B/ray (``simple_dielectric``, ``diffuse``, ``abm_b``), 20 B/ray
(``turbid_slab``: two packed counts) and 41 B/ray (coloured ``plastic`` at 89°: weight
violations, the rare-event path) at 2²², 2²⁴, 2²⁵ and 2²⁶ rays
(``python tools/chunk_memory.py``) — so at most about 1.3 GiB above the process's
~120 MiB at 2²⁵ (11 GiB and more at 2³⁰). Throughput does not grow beyond 2²² (the
default).
"""

WAVELENGTH_RANGE: tuple[float, float] = (1e-3, 1e6)
"""
Wavelengths (nm) a reading may ask for, ends included: 1 pm to 1 mm. The kernel traces
float32 wavelengths; values far outside (``1e-300``, ``1e39``) would become 0 or inf.
"""

NANOMETRE_FLOOR: float = 100.0
"""
Wavelengths (nm) below which *every* wavelength of a call, or of a measured spectrum,
looks like micrometres (``0.4:0.7:0.1``: 400–700 nm typed in µm) rather than far-UV
nanometres: such a set is refused with the hint "micrometres? multiply by 1000"
(:func:`check_nanometres`, the one rule of the instruments and of
:mod:`virtspec_mi.applications.comparison`). A set that reaches :data:`NANOMETRE_FLOOR` nm or beyond
is read as nanometres.
"""

FLOAT32_MIN_NORMAL: float = 1.1754943508222875e-38
"""Smallest normal float32: the project's plugins refuse smaller nonzero parameters."""

FLOAT32_MAX: float = 3.4028234663852886e38
"""Largest finite float32."""

_FLOAT64_MIN_NORMAL: float = sys.float_info.min


def shown_value(value: Any) -> str:
    """
    ``value`` as a message shows it: every digit it was given (``399.99999999``),
    whole floats without ``.0`` (``95``), huge integers by their length.
    """

    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return repr(value)
    if isinstance(value, int):
        text = str(value)
        return text if len(text) <= 24 else f"an integer of {len(text.lstrip('-'))} digits"
    if math.isfinite(value) and value.is_integer() and abs(value) < 1e16:
        return str(int(value))
    return repr(float(value))


def _is_bool(value: Any) -> bool:
    return isinstance(value, (bool, np.bool_))


def number(name: str, value: Any) -> float:
    """
    ``value`` as a float that is not NaN; booleans, non-numbers and integers beyond the
    float range raise ``ValueError`` naming ``name``.
    """

    if _is_bool(value):
        raise ValueError(f"{name} must be a number (got {value!r})")
    try:
        result = float(value)
    except OverflowError:
        raise ValueError(f"{name} must be a number within the float range, |{name}| < 1.8e308 "
                         f"(got {shown_value(value)})") from None
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a number (got {value!r})") from None
    if math.isnan(result):
        raise ValueError(f"{name} must be a number (got NaN)")
    return result


def real(name: str, value: Any) -> float:
    """
    As :func:`number`, for a parameter of a Python call that takes a number and nothing
    else: a string (``"0.1"``) is refused too, naming ``name`` (a command line's text is
    turned into numbers by its parser, before the call).
    """

    if isinstance(value, (str, bytes)):
        raise ValueError(f"{name} must be a number, not text (got {value!r}); write {name}={_unquoted(value)}")
    return number(name, value)


def _unquoted(value: str | bytes) -> str:
    text = value.decode(errors="replace") if isinstance(value, bytes) else value
    try:
        float(text)
    except ValueError:
        return "a number"
    return text.strip()


def _normal(name: str, value: float, rule: str) -> float:
    if 0.0 < value < _FLOAT64_MIN_NORMAL:
        raise ValueError(f"{name} must satisfy {rule} and be at least {_FLOAT64_MIN_NORMAL:.3g}, the smallest "
                         f"normal float (got {shown_value(value)})")
    return value


def check_mu(mu: Any) -> float:
    """μ, the certified tolerance: 0 < μ < 0.5 (a normal float)."""

    mu = number("mu", mu)
    if not 0.0 < mu < 0.5:
        raise ValueError(f"mu must satisfy 0 < mu < 0.5 (got {shown_value(mu)})")
    return _normal("mu", mu, "0 < mu < 0.5")


def check_delta(delta: Any, name: str = "delta") -> float:
    """δ, the allowed failure probability: 0 < δ < 1 (a normal float)."""

    delta = number(name, delta)
    if not 0.0 < delta < 1.0:
        raise ValueError(f"{name} must satisfy 0 < {name} < 1 (got {shown_value(delta)})")
    return _normal(name, delta, f"0 < {name} < 1")


def check_rays(rays: Any, maximum: float = MAX_RAYS, name: str = "rays") -> int:
    """
    Rays per reading: a whole number, 1 ≤ rays ≤ ``maximum`` (2³² − 1 for a reading);
    ``name`` is the setting the value came from (``rays``, ``pilot_rays``, ``spp``).
    """

    if isinstance(rays, int) and not _is_bool(rays):
        whole = rays
    else:
        value = number(name, rays)
        if not value.is_integer():
            raise ValueError(f"{name} must be a whole number >= 1 (got {rays!r})")
        whole = int(value)
    if not 1 <= whole <= maximum:
        upper = f" <= {int(maximum)}" if math.isfinite(maximum) else ""
        raise ValueError(f"{name} must satisfy 1 <= {name}{upper} (got {shown_value(whole)})")
    return whole


def check_rays_needed(rays: int, rule: str) -> int:
    """
    Rays a budget computed for one reading (``rule`` says which, e.g. ``"the hoeffding
    bound for mu = 2.4e-05, delta = 0.01"``): at most :data:`MAX_RAYS`, else
    ``ValueError`` naming the rule and the limit. Every N, given or computed, passes here
    or :func:`check_rays` before anything is traced.
    """

    if not 1 <= rays <= MAX_RAYS:
        shown = f"{rays:,}" if rays < 10**21 else f"{float(rays):.3g}"
        raise ValueError(
            f"{rule} needs N = {shown} rays per reading, more than the {MAX_RAYS:,} (2**32 - 1) one reading may "
            "trace (its rays are numbered with 32 bits); raise mu or delta, or give rays")
    return int(rays)


def check_bins(bins: Any) -> int:
    """K, the number of bins of a goniophotometer reading: a whole number ≥ 1."""

    if isinstance(bins, bool) or not isinstance(bins, (int, np.integer)) or bins < 1:
        raise ValueError(f"bins must be a whole number of bins >= 1 (got {bins!r})")
    return int(bins)


def check_relative_tolerance(value: Any) -> float:
    """ε, the relative tolerance on a bin's BRDF value: 0 < ε ≤ 1."""

    tolerance = number("relative_tolerance", value)
    if not 0.0 < tolerance <= 1.0:
        raise ValueError(f"relative_tolerance must satisfy 0 < relative_tolerance <= 1 (got {shown_value(value)})")
    return tolerance


def check_brdf_floor(value: Any) -> float:
    """The BRDF/BTDF value (sr⁻¹) above which bins are held to a relative tolerance: finite and > 0."""

    floor = number("brdf_floor", value)
    if not (math.isfinite(floor) and floor > 0.0):
        raise ValueError(f"brdf_floor must be a finite BRDF value > 0 in 1/sr (got {shown_value(value)})")
    return floor


_Function = TypeVar("_Function", bound=Callable[..., Any])


def validated(**checks: Callable[[Any], Any]) -> Callable[[_Function], _Function]:
    """
    Make a function that trusts its arguments into a public entry that checks them once.

    ``@validated(mu=check_mu, delta=check_delta)`` puts each named argument, when given
    and not ``None``, through its check (which returns the value to use or raises
    ``ValueError`` naming the parameter), in the order of the signature, before the body
    runs. The body stays reachable as ``function.unchecked`` for callers below the
    boundary, which hold validated values already (the settings and options dataclasses
    validate on construction).
    """

    def decorate(function: _Function) -> _Function:
        signature = inspect.signature(function)
        unknown = sorted(set(checks) - set(signature.parameters))
        if unknown:
            raise TypeError(f"{function.__qualname__} has no parameter(s) {', '.join(unknown)} to check")
        order = [name for name in signature.parameters if name in checks]

        @functools.wraps(function)
        def checked(*args: Any, **kwargs: Any) -> Any:
            call = signature.bind(*args, **kwargs)
            for name in order:
                if call.arguments.get(name) is not None:
                    call.arguments[name] = checks[name](call.arguments[name])
            return function(*call.args, **call.kwargs)

        checked.unchecked = function  # type: ignore[attr-defined]
        return checked  # type: ignore[return-value]

    return decorate


def check_readings(readings: int, rays: int) -> None:
    """
    A call of ``readings`` readings tracing ``rays`` rays in all: at most
    :data:`MAX_READINGS` and :data:`MAX_TOTAL_RAYS` (``ValueError`` with the numbers).
    """

    if readings > MAX_READINGS:
        raise ValueError(f"a call takes at most {MAX_READINGS:,} readings (wavelengths x theta_i; got {readings:,}): "
                         "split it into several calls")
    if rays > MAX_TOTAL_RAYS:
        raise ValueError(f"a call traces at most {MAX_TOTAL_RAYS:.0e} rays (got {rays:,} = {readings:,} readings "
                         "x their rays): raise mu or delta, give fewer rays, or split it into several calls")


def check_theta_i(theta_i: Any) -> float:
    """Polar incidence angle in degrees: 0 ≤ θi ≤ 90."""

    theta_i = number("theta_i", theta_i)
    if not 0.0 <= theta_i <= 90.0:
        raise ValueError(f"theta_i must satisfy 0 <= theta_i <= 90 degrees (got {shown_value(theta_i)})")
    return theta_i


def check_positive(name: str, value: Any) -> float:
    """A length that must be finite and > 0 (radii, distance)."""

    value = number(name, value)
    if not (value > 0.0 and math.isfinite(value)):
        raise ValueError(f"{name} must be a finite number > 0 (got {shown_value(value)})")
    return value


def check_float32(name: str, value: Any, allowed: str, test: Any, allow_inf: bool = False) -> float:
    """
    A numeric parameter of a specimen plugin (``name`` as the message shows it, e.g.
    ``"simple_dielectric: 'eta'"``): a real number, not a boolean, that float32 holds —
    finite (or ``inf`` with ``allow_inf``), no larger than :data:`FLOAT32_MAX` and zero
    or at least :data:`FLOAT32_MIN_NORMAL` in magnitude (float32 would turn it into inf
    or a denormal/zero) — for which ``test(value)`` is true. ``allowed`` says that rule
    as the message's verb phrase: ``"be a number > 0"``, ``"satisfy -1 <= g <= 1"``.
    """

    def refuse(shown: str) -> ValueError:
        return ValueError(f"{name} must {allowed} (a float32: 0 or {FLOAT32_MIN_NORMAL:.3g} <= |value| <= "
                          f"{FLOAT32_MAX:.3g}{', or inf' if allow_inf else ''}) (got {shown})")

    if _is_bool(value) or not isinstance(value, (int, float)):
        raise refuse(repr(value))
    try:
        result = float(value)
    except OverflowError:
        raise refuse(shown_value(value)) from None
    magnitude = abs(result)
    representable = magnitude == 0.0 or FLOAT32_MIN_NORMAL <= magnitude <= FLOAT32_MAX or (
        allow_inf and result == math.inf)
    if math.isnan(result) or not representable or not test(result):
        raise refuse(shown_value(value))
    return result


def parse_wavelengths(wavelengths: Any) -> tuple[float, ...]:
    """
    Wavelengths in nm, each within :data:`WAVELENGTH_RANGE`, at least one and at most
    :data:`MAX_VALUES`.

    Accepts a number, a sequence, or a string of comma/space separated numbers and
    ``start:stop:step`` ranges (stop included), e.g. ``"400:700:10"`` or ``"465, 551"``.
    """

    values = _parse_numbers("wavelengths", wavelengths, "nm")
    if not values:
        raise ValueError("wavelengths must hold at least one wavelength (got none)")
    low, high = WAVELENGTH_RANGE
    for value in values:
        if not low <= value <= high:
            raise ValueError(f"wavelengths must be finite and > 0 nm, {low:g} <= wavelength <= {high:g} nm "
                             f"(got {shown_value(value)})")
    check_nanometres(values, "wavelengths")
    return tuple(values)


def check_nanometres(wavelengths: Iterable[float], what: str, where: str = "") -> None:
    """
    Refuse wavelengths that look like micrometres — every one below
    :data:`NANOMETRE_FLOOR` nm — with the hint to multiply by 1000. ``what`` names them in
    the message (``"wavelengths"``, ``"measured wavelengths"``), ``where`` says where they
    came from (a file), if anywhere.
    """

    values = [float(w) for w in wavelengths]
    if values and max(values) < NANOMETRE_FLOOR:
        low, high = min(values), max(values)
        shown = f"{low:g}-{high:g}" if low != high else f"{low:g}"
        raise ValueError(f"{what} must be in nm (got {shown}{f' in {where}' if where else ''}: all below "
                         f"{NANOMETRE_FLOOR:g} nm, micrometres? multiply by 1000)")


def check_wavelength_range(wavelengths: Iterable[float], span: tuple[float, float] | None, specimen: str) -> None:
    """
    Refuse wavelengths outside ``span`` = (lowest, highest) nm of a specimen that declares
    one (a BSDF attribute ``wavelength_range``, e.g. the ABM leaves' data range); ``None``
    accepts any.
    """

    if span is None:
        return
    low, high = (float(v) for v in span)
    outside = [w for w in wavelengths if not low <= w <= high]
    if outside:
        raise ValueError(
            f"wavelengths must satisfy {low:g} <= wavelength <= {high:g} nm for the specimen "
            f"{specimen} (got {', '.join(shown_value(w) for w in outside[:5])}{' ...' if len(outside) > 5 else ''})"
        )


def parse_theta_i(theta_i: Any) -> tuple[float, ...]:
    """
    Polar incidence angles of a sweep in degrees, each 0 ≤ θi ≤ 90, at least one and at
    most :data:`MAX_VALUES`.

    Same forms as :func:`parse_wavelengths`, e.g. ``"0:90:1"`` (91 angles) or ``[0, 45]``.
    """

    values = _parse_numbers("theta_i", theta_i, "degrees")
    if not values:
        raise ValueError("theta_i must hold at least one angle (got none)")
    return tuple(check_theta_i(value) for value in values)


def parse_values(name: str, values: Any) -> tuple[float, ...]:
    """
    Values of a swept specimen parameter ``name``: the forms of :func:`parse_wavelengths`
    (a number, a sequence, or a string of numbers and ``start:stop:step`` ranges, stop
    included when it lies on the grid within rounding), each finite, at least one and at
    most :data:`MAX_VALUES`. A range's values are rounded to 15 significant digits, so
    ``"0.1:0.3:0.1"`` gives 0.1, 0.2, 0.3 rather than 0.30000000000000004 (labels that
    ``Result.sel`` and files show as typed). Their range is the specimen's to check.
    """

    if isinstance(values, str) and ":" in values:
        numbers: list[float] = []
        for token in value_tokens(f"parameter {name!r}", values):
            numbers.extend([float(f"{v:.15g}") for v in _parse_range(token, name, MAX_VALUES - len(numbers))]
                           if ":" in token else [number(name, token)])
            _check_count(name, len(numbers))
    else:
        numbers = _parse_numbers(name, values, "the parameter's unit")
    if not numbers:
        raise ValueError(f"parameter {name!r} must hold at least one value (got none)")
    for value in numbers:
        if not math.isfinite(value):
            raise ValueError(f"parameter {name!r} must hold finite numbers (got {value!r})")
    return tuple(numbers)


def value_tokens(name: str, text: str) -> list[str]:
    """
    The items of a written list of values: separated by commas and/or spaces
    (``"400, 500 600"``); an empty item between commas (``"1,2,,3"``, a leading or
    trailing comma) is a ``ValueError`` naming ``name`` — a value was left out.
    """

    items = [item.strip() for item in text.split(",")]
    if len(items) > 1 and not all(items):
        raise ValueError(f"{name} must be values separated by commas or spaces, with no empty item between commas "
                         f"(got {text!r})")
    return [token for item in items for token in item.split()]


def _parse_numbers(name: str, value: Any, unit: str) -> list[float]:
    """
    Numbers from a number, a sequence or a string of numbers and start:stop:step ranges;
    more than :data:`MAX_VALUES` are refused before they are built.
    """

    if isinstance(value, str):
        values: list[float] = []
        for token in value_tokens(name, value):
            values.extend(_parse_range(token, name, MAX_VALUES - len(values)) if ":" in token
                          else [_token_number(name, token)])
            _check_count(name, len(values))
        return values
    if isinstance(value, (int, float)) and not _is_bool(value):
        return [number(name, value)]
    if isinstance(value, Iterable):
        if hasattr(value, "__len__"):
            _check_count(name, len(value))
        values = []
        for item in value:
            values.append(number(name, item))
            _check_count(name, len(values))
        return values
    raise ValueError(f"{name} must be numbers in {unit} (got {value!r})")


def _token_number(name: str, token: str) -> float:
    """
    One number of a string of numbers; a token that is not one is refused with the forms
    that are (a dash range, ``400-700``, with its ``start:stop:step`` spelling).
    """

    try:
        return number(name, token)
    except ValueError as error:
        dashed = re.fullmatch(r"(\d+(?:\.\d*)?)-(\d+(?:\.\d*)?)", token.strip())
        form = (f"a range is start:stop:step, e.g. {dashed[1]}:{dashed[2]}:10" if dashed else
                "write numbers separated by commas or spaces (450,550,650) or start:stop:step ranges (400:700:10)")
        raise ValueError(f"{error}; {form}") from None


def _check_count(name: str, count: float) -> None:
    if count > MAX_VALUES:
        shown = f"{count:,.0f}" if count < 1e21 else f"{count:.3g}"
        raise ValueError(f"{name} must hold at most {MAX_VALUES:,} values per call (got {shown})")


def _parse_range(token: str, name: str, room: int = MAX_VALUES) -> list[float]:
    """The values of ``start:stop:step`` (stop included), counted before the list is built."""

    parts = token.split(":")
    if len(parts) != 3:
        raise ValueError(f"{name} range must be start:stop:step (got {token!r})")
    start, stop, step = (number(name, p) for p in parts)
    if not all(math.isfinite(v) for v in (start, stop, step)):
        raise ValueError(f"{name} range {token!r} needs finite start, stop and step")
    if not step > 0 or stop < start:
        raise ValueError(f"{name} range {token!r} needs step > 0 and stop >= start")
    span = (stop - start) / step  # finite: both are finite and step > 0 (may overflow to inf)
    if not span + 1 <= room:
        shown = f"{span + 1:,.0f}" if span < 1e21 else f"{span + 1:.3g}"
        raise ValueError(f"{name} range {token!r} holds {shown} values; {name} must hold at most "
                         f"{MAX_VALUES:,} values per call")
    count = int(math.floor(span + 1e-9)) + 1
    return [start + i * step for i in range(count)]
