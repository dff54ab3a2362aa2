"""
Measurement settings and the one place that validates them
==========================================================

Every user-facing entry point (the integrator's XML/dict parameters, :func:`measure`,
the CLI) builds a :class:`Settings`; its checks name the parameter and the allowed
range, so bad input never reaches a kernel as a crash or a NaN.

Defaults are the paper's: μ = 0.005, δ = 0.01, the exponential Chebyshev bound,
conical beam, jittered sampling, λ = 551 nm, θi = φi = 0°.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any, Iterable

__all__ = [
    "BEAMS",
    "SAMPLINGS",
    "MAX_RAYS",
    "Settings",
    "check_mu",
    "check_delta",
    "check_rays",
    "check_theta_i",
    "check_positive",
    "parse_wavelengths",
    "parse_theta_i",
    "check_wavelength_range",
]

BEAMS: tuple[str, ...] = ("conical", "collimated", "diffuse")
"""``conical``: conical-hemispherical (disk to disk); ``collimated``: directional-hemispherical;
``diffuse``: hemispherical-hemispherical (cosine-distributed incidence, θi and φi unused)."""

SAMPLINGS: tuple[str, ...] = ("jittered", "random", "concentric")
"""Disk sampling strategies: eq. (4) stratified polar warp, eq. (3) square + rejection, Shirley–Chiu."""

MAX_RAYS: int = 2**32 - 1
"""Most rays one reading may use (its rays are numbered with 32 bits)."""


def _number(name: str, value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
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

    mu = _number("mu", mu)
    if not 0.0 < mu < 0.5:
        raise ValueError(f"mu must satisfy 0 < mu < 0.5 (got {mu:g})")
    return mu


def check_delta(delta: Any) -> float:
    """δ, the allowed failure probability: 0 < δ < 1."""

    delta = _number("delta", delta)
    if not 0.0 < delta < 1.0:
        raise ValueError(f"delta must satisfy 0 < delta < 1 (got {delta:g})")
    return delta


def check_rays(rays: Any, maximum: float = MAX_RAYS) -> int:
    """Rays per reading: a whole number, 1 ≤ rays ≤ ``maximum`` (2³² − 1 for a reading)."""

    if isinstance(rays, bool) or not float(_number("rays", rays)).is_integer():
        raise ValueError(f"rays must be a whole number >= 1 (got {rays!r})")
    rays = int(float(rays))
    if not 1 <= rays <= maximum:
        upper = f" <= {int(maximum)}" if math.isfinite(maximum) else ""
        raise ValueError(f"rays must satisfy 1 <= rays{upper} (got {rays})")
    return rays


def check_theta_i(theta_i: Any) -> float:
    """Polar incidence angle in degrees: 0 ≤ θi ≤ 90."""

    theta_i = _number("theta_i", theta_i)
    if not 0.0 <= theta_i <= 90.0:
        raise ValueError(f"theta_i must satisfy 0 <= theta_i <= 90 degrees (got {theta_i:g})")
    return theta_i


def check_positive(name: str, value: Any) -> float:
    """A length that must be finite and > 0 (radii, distance)."""

    value = _number(name, value)
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
            values.extend(_parse_range(token, name) if ":" in token else [_number(name, token)])
        return values
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        return [float(value)]
    if isinstance(value, Iterable):
        return [_number(name, v) for v in value]
    raise ValueError(f"{name} must be numbers in {unit} (got {value!r})")


def _parse_range(token: str, name: str = "wavelengths") -> list[float]:
    parts = token.split(":")
    if len(parts) != 3:
        raise ValueError(f"{name} range must be start:stop:step (got {token!r})")
    start, stop, step = (_number(name, p) for p in parts)
    if not step > 0 or stop < start:
        raise ValueError(f"{name} range {token!r} needs step > 0 and stop >= start")
    count = int(math.floor((stop - start) / step + 1e-9)) + 1
    return [start + i * step for i in range(count)]


@dataclass(frozen=True)
class Settings:
    """
    Everything that defines a reading besides the scene; validated on construction.

    Parameters
    ----------
    theta_i, phi_i
        Incidence angles in degrees (θi ∈ [0, 90]; φi any finite value).
    wavelengths
        Wavelengths in nm (one reading per wavelength).
    mu, delta
        Certified tolerance and failure probability of each reading.
    rays
        Rays per reading; ``None`` takes them from ``bound`` with μ and δ.
    bound
        Ray-budget rule of :data:`virtspec_mi.bounds.BOUND_NAMES`: ``"hoeffding"`` (eq. 23,
        default), ``"chebyshev"`` (eq. 15), ``"exact"`` or ``"two-stage"``.
    pilot_rays, pilot_delta
        Two-stage pilot size n₁ (default ⌈10/μ⌉) and its failure probability δ₁
        (default δ/10), 0 < δ₁ < δ; see :mod:`virtspec_mi.twostage`.
    joint
        Certify reflectance and transmittance jointly (each at δ/2, Bonferroni) instead
        of each on its own at δ.
    beam, sampling
        One of :data:`BEAMS` and :data:`SAMPLINGS`.
    seed
        Seed of the counter-based random numbers, 0 ≤ seed < 2³².
    chunk_size
        Rays per kernel launch (memory bound), ≥ 1024.
    """

    theta_i: float = 0.0
    phi_i: float = 0.0
    wavelengths: tuple[float, ...] = (551.0,)
    mu: float = 0.005
    delta: float = 0.01
    rays: int | None = None
    bound: str = "hoeffding"
    beam: str = "conical"
    sampling: str = "jittered"
    seed: int = 0
    chunk_size: int = 1 << 22
    pilot_rays: int | None = None
    pilot_delta: float | None = None
    joint: bool = False

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        set_(self, "theta_i", check_theta_i(self.theta_i))
        phi = _number("phi_i", self.phi_i)
        if not math.isfinite(phi):
            raise ValueError(f"phi_i must be a finite number of degrees (got {phi:g})")
        set_(self, "phi_i", phi)
        set_(self, "wavelengths", parse_wavelengths(self.wavelengths))
        set_(self, "mu", check_mu(self.mu))
        set_(self, "delta", check_delta(self.delta))
        if self.rays is not None:
            set_(self, "rays", check_rays(self.rays))
        from virtspec_mi.bounds import BOUND_NAMES

        if self.bound not in BOUND_NAMES:
            raise ValueError(f"bound must be one of {', '.join(BOUND_NAMES)} (got {self.bound!r})")
        if self.pilot_rays is not None:
            set_(self, "pilot_rays", check_rays(self.pilot_rays))
        if self.pilot_delta is not None:
            pilot_delta = _number("pilot_delta", self.pilot_delta)
            if not 0.0 < pilot_delta < self.delta:
                raise ValueError(
                    f"pilot_delta must satisfy 0 < pilot_delta < delta = {self.delta:g} (got {pilot_delta:g})"
                )
            set_(self, "pilot_delta", pilot_delta)
        if not isinstance(self.joint, (bool, int)) or self.joint not in (0, 1):
            raise ValueError(f"joint must be true or false (got {self.joint!r})")
        set_(self, "joint", bool(self.joint))
        if self.beam not in BEAMS:
            raise ValueError(f"beam must be one of {', '.join(BEAMS)} (got {self.beam!r})")
        if self.sampling not in SAMPLINGS:
            raise ValueError(f"sampling must be one of {', '.join(SAMPLINGS)} (got {self.sampling!r})")
        seed = _number("seed", self.seed)
        if not (seed.is_integer() and 0 <= seed < 2**32):
            raise ValueError(f"seed must be a whole number with 0 <= seed < 2**32 (got {self.seed!r})")
        set_(self, "seed", int(seed))
        chunk = _number("chunk_size", self.chunk_size)
        if not (chunk.is_integer() and 1024 <= chunk <= 2**30):
            raise ValueError(f"chunk_size must be a whole number in [1024, 2**30] (got {self.chunk_size!r})")
        set_(self, "chunk_size", int(chunk))

    @property
    def rays_per_reading(self) -> int:
        """
        ``rays`` if given, else the fixed bound's N for μ and the quantity δ (eq. 23 by
        default); ``ValueError`` for ``"two-stage"``, which sizes each reading itself.
        """

        if self.rays is not None:
            return self.rays
        from virtspec_mi.bounds import rays_for_bound

        return rays_for_bound(self.bound, self.mu, self.quantity_delta)

    @property
    def adaptive(self) -> bool:
        """True when each reading is sized by a pilot batch (``two-stage`` without ``rays``)."""

        return self.rays is None and self.bound == "two-stage"

    @property
    def quantity_delta(self) -> float:
        """δ of each certified quantity: δ, or δ/2 with ``joint`` (R and T together at δ)."""

        return self.delta / 2 if self.joint else self.delta

    @property
    def pilot_rays_per_reading(self) -> int:
        """Two-stage pilot size n₁: ``pilot_rays`` or ⌈10/μ⌉."""

        from virtspec_mi.twostage import default_pilot_rays

        return self.pilot_rays if self.pilot_rays is not None else default_pilot_rays(self.mu)

    @property
    def pilot_delta_value(self) -> float:
        """Two-stage pilot failure probability δ₁: ``pilot_delta`` or δ/10."""

        from virtspec_mi.twostage import default_pilot_delta

        return self.pilot_delta if self.pilot_delta is not None else default_pilot_delta(self.delta)

    def updated(self, **changes: Any) -> "Settings":
        """A copy with the given fields replaced (``None`` values are ignored), re-validated."""

        return replace(self, **{k: v for k, v in changes.items() if v is not None})

    def as_dict(self) -> dict[str, Any]:
        """Plain-data view (for JSON and result files)."""

        return {
            "theta_i": self.theta_i,
            "phi_i": self.phi_i,
            "wavelengths": list(self.wavelengths),
            "mu": self.mu,
            "delta": self.delta,
            "rays": None if self.adaptive else self.rays_per_reading,
            "bound": self.bound,
            "joint": self.joint,
            **({"pilot_rays": self.pilot_rays_per_reading, "pilot_delta": self.pilot_delta_value}
               if self.adaptive else {}),
            "beam": self.beam,
            "sampling": self.sampling,
            "seed": self.seed,
        }

