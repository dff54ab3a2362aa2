"""
Checks of measurement inputs: one message style, naming the parameter and its range
===================================================================================

The bottom of the package: every check that turns user input into a validated value
(:mod:`virtspec_mi.settings`, :mod:`virtspec_mi.bounds`, :mod:`virtspec_mi.geometry`,
…) lives here, so each rule is written once. A bad value raises ``ValueError`` with a
message such as ``theta_i must satisfy 0 <= theta_i <= 90 degrees (got 95)``.
"""

from __future__ import annotations

import math
from typing import Any, Iterable

__all__ = [
    "MAX_RAYS",
    "number",
    "check_mu",
    "check_delta",
    "check_rays",
    "check_theta_i",
    "check_positive",
    "parse_wavelengths",
    "parse_theta_i",
    "check_wavelength_range",
]

MAX_RAYS: int = 2**32 - 1
"""Most rays one reading may use (its rays are numbered with 32 bits)."""


def number(name: str, value: Any) -> float:
    """``value`` as a float that is not NaN; booleans and non-numbers raise ``ValueError`` naming ``name``."""

    if isinstance(value, bool):
        raise ValueError(f"{name} must be a number (got {value!r})")
    if not isinstance(value, (int, float)):
        try:
            value = float(value)
        except (TypeError, ValueError):
            raise ValueError(f"{name} must be a number (got {value!r})") from None
    value = float(value)
    if math.isnan(value):
        raise ValueError(f"{name} must be a number (got NaN)")
    return value


def check_mu(mu: Any) -> float:
    """μ, the certified tolerance: 0 < μ < 0.5."""

    mu = number("mu", mu)
    if not 0.0 < mu < 0.5:
        raise ValueError(f"mu must satisfy 0 < mu < 0.5 (got {mu:g})")
    return mu


def check_delta(delta: Any) -> float:
    """δ, the allowed failure probability: 0 < δ < 1."""

    delta = number("delta", delta)
    if not 0.0 < delta < 1.0:
        raise ValueError(f"delta must satisfy 0 < delta < 1 (got {delta:g})")
    return delta


def check_rays(rays: Any, maximum: float = MAX_RAYS) -> int:
    """Rays per reading: a whole number, 1 ≤ rays ≤ ``maximum`` (2³² − 1 for a reading)."""

    if isinstance(rays, bool) or not float(number("rays", rays)).is_integer():
        raise ValueError(f"rays must be a whole number >= 1 (got {rays!r})")
    rays = int(float(rays))
    if not 1 <= rays <= maximum:
        upper = f" <= {int(maximum)}" if math.isfinite(maximum) else ""
        raise ValueError(f"rays must satisfy 1 <= rays{upper} (got {rays})")
    return rays


def check_theta_i(theta_i: Any) -> float:
    """Polar incidence angle in degrees: 0 ≤ θi ≤ 90."""

    theta_i = number("theta_i", theta_i)
    if not 0.0 <= theta_i <= 90.0:
        raise ValueError(f"theta_i must satisfy 0 <= theta_i <= 90 degrees (got {theta_i:g})")
    return theta_i


def check_positive(name: str, value: Any) -> float:
    """A length that must be finite and > 0 (radii, distance)."""

    value = number(name, value)
    if not (value > 0.0 and math.isfinite(value)):
        raise ValueError(f"{name} must be a finite number > 0 (got {value:g})")
    return value


def parse_wavelengths(wavelengths: Any) -> tuple[float, ...]:
    """
    Wavelengths in nm, each finite and > 0, at least one.

    Accepts a number, a sequence, or a string of comma/space separated numbers and
    ``start:stop:step`` ranges (stop included), e.g. ``"400:700:10"`` or ``"465, 551"``.
    """

    values = _parse_numbers("wavelengths", wavelengths, "nm")
    if not values:
        raise ValueError("wavelengths must hold at least one wavelength (got none)")
    for value in values:
        if not (value > 0.0 and math.isfinite(value)):
            raise ValueError(f"wavelengths must be finite and > 0 nm (got {value:g})")
    return tuple(values)


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
            f"{specimen} (got {', '.join(f'{w:g}' for w in outside[:5])}{' ...' if len(outside) > 5 else ''})"
        )


def parse_theta_i(theta_i: Any) -> tuple[float, ...]:
    """
    Polar incidence angles of a sweep in degrees, each 0 ≤ θi ≤ 90, at least one.

    Same forms as :func:`parse_wavelengths`, e.g. ``"0:90:1"`` (91 angles) or ``[0, 45]``.
    """

    values = _parse_numbers("theta_i", theta_i, "degrees")
    if not values:
        raise ValueError("theta_i must hold at least one angle (got none)")
    return tuple(check_theta_i(value) for value in values)


def _parse_numbers(name: str, value: Any, unit: str) -> list[float]:
    """Numbers from a number, a sequence or a string of numbers and start:stop:step ranges."""

    if isinstance(value, str):
        values: list[float] = []
        for token in value.replace(",", " ").split():
            values.extend(_parse_range(token, name) if ":" in token else [number(name, token)])
        return values
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        return [float(value)]
    if isinstance(value, Iterable):
        return [number(name, v) for v in value]
    raise ValueError(f"{name} must be numbers in {unit} (got {value!r})")


def _parse_range(token: str, name: str = "wavelengths") -> list[float]:
    parts = token.split(":")
    if len(parts) != 3:
        raise ValueError(f"{name} range must be start:stop:step (got {token!r})")
    start, stop, step = (number(name, p) for p in parts)
    if not step > 0 or stop < start:
        raise ValueError(f"{name} range {token!r} needs step > 0 and stop >= start")
    count = int(math.floor((stop - start) / step + 1e-9)) + 1
    return [start + i * step for i in range(count)]
