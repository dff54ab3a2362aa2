"""
Measurement settings: defined once, validated once
==================================================

:class:`Settings` is the one definition of the 14 settings of a measurement. Each
field carries its default, its check (from :mod:`virtspec_mi.checks`, naming the
parameter and its allowed range) and its help text; everything else is derived from
these fields:

- :func:`virtspec_mi.measure` and :func:`virtspec_mi.sweep` take them as keywords
  (:func:`settings_keywords` gives their signatures);
- the ``spectrophotometer`` integrator reads them as XML/dict parameters;
- the command line makes one ``--flag`` per field (choices, defaults and help from
  the field).

Validation happens once, when a :class:`Settings` is built: code below this boundary
takes validated values. Values may arrive as strings (XML, command line): the checks
convert them. Defaults are the paper's: μ = 0.005, δ = 0.01, the exponential Chebyshev
bound (eq. 23), conical beam, jittered sampling (eq. 4), λ = 551 nm, θi = φi = 0°.

References
----------
Baranoski et al. (2001), eqs. (3), (4), (23); Sect. 3.2.
"""

from __future__ import annotations

import inspect
import math
from dataclasses import dataclass, field, fields, replace
from typing import Any, Callable

from virtspec_mi.budgets.rules import BUDGETS, RayBudget
from virtspec_mi.checks import (
    MAX_CHUNK_SIZE,
    WAVELENGTH_RANGE,
    check_delta,
    check_mu,
    check_rays,
    check_rays_needed,
    check_theta_i,
    number,
    parse_wavelengths,
    shown_value,
)

__all__ = ["BEAMS", "SAMPLINGS", "Settings", "SETTING_NAMES", "settings_keywords", "with_settings", "shown", "help_text"]

BEAMS: dict[str, str] = {
    "conical": "conical-hemispherical: disk to disk",
    "collimated": "directional-hemispherical: every ray along the incidence direction",
    "diffuse": "hemispherical-hemispherical: cosine-distributed incidence, theta_i and phi_i unused",
}
"""Beam geometries and what each measures."""

SAMPLINGS: dict[str, str] = {
    "jittered": "stratified polar warp, eq. (4)",
    "random": "square and rejection, eq. (3)",
    "concentric": "Shirley-Chiu concentric map",
}
"""Disk sampling strategies."""


def _choice(name: str, choices: dict[str, Any]) -> Callable[[Any], str]:
    def check(value: Any) -> str:
        if not isinstance(value, str) or value not in choices:
            raise ValueError(f"{name} must be one of {', '.join(choices)} (got {value!r})")
        return value
    return check


def _check_phi(value: Any) -> float:
    phi = number("phi_i", value)
    if not math.isfinite(phi):
        raise ValueError(f"phi_i must be a finite number of degrees (got {shown_value(phi)})")
    return phi


def _check_joint(value: Any) -> bool:
    if isinstance(value, str) and value.lower() in ("true", "false"):
        return value.lower() == "true"
    if not isinstance(value, (bool, int)) or value not in (0, 1):
        raise ValueError(f"joint must be true or false (got {value!r})")
    return bool(value)


def _check_pilot_delta(value: Any) -> float:
    return number("pilot_delta", value)  # its range, 0 < pilot_delta < delta, needs delta: see __post_init__


def _rays(name: str) -> Callable[[Any], int]:
    def check(value: Any) -> int:
        return check_rays(value, name=name)
    return check


def _whole(name: str, low: int, high: int, shown: str) -> Callable[[Any], int]:
    def check(value: Any) -> int:
        if isinstance(value, int) and not isinstance(value, bool):
            whole = value  # any size: never through a float
        else:
            as_float = None if isinstance(value, bool) else number(name, value)
            whole = int(as_float) if as_float is not None and as_float.is_integer() else None
        if whole is None or not low <= whole <= high:
            raise ValueError(f"{name} must be a whole number with {shown} (got {shown_value(value)})")
        return whole
    return check


_CHUNK_LOG2 = MAX_CHUNK_SIZE.bit_length() - 1  # MAX_CHUNK_SIZE is a power of two


def _setting(default: Any, check: Callable[[Any], Any], help: str, choices: dict | None = None) -> Any:
    """A :class:`Settings` field: default, check and help text (the one definition)."""

    return field(default=default, metadata={"check": check, "help": help, "choices": choices})


@dataclass(frozen=True)
class Settings:
    """
    Everything that defines a measurement besides the scene; validated on construction.

    Every field is listed with its default, allowed values and meaning in
    ``Settings.describe()`` (the same text the CLI's ``--help`` shows).
    """

    theta_i: float = _setting(0.0, check_theta_i, "polar incidence angle, degrees in [0, 90]")
    phi_i: float = _setting(0.0, _check_phi, "azimuthal incidence angle from the specimen's x axis, degrees")
    wavelengths: tuple[float, ...] = _setting(
        (551.0,), parse_wavelengths,
        f"wavelengths in nm ({WAVELENGTH_RANGE[0]:g} ... {WAVELENGTH_RANGE[1]:g}): numbers and start:stop:step "
        "ranges, e.g. 400:700:10")
    mu: float = _setting(0.005, check_mu, "certified tolerance, 0 < mu < 0.5")
    delta: float = _setting(0.01, check_delta, "failure probability, 0 < delta < 1")
    rays: int | None = _setting(None, _rays("rays"), "rays per reading, 1 ... 2**32 - 1 (overrides the bound)")
    bound: str = _setting("hoeffding", _choice("bound", BUDGETS), "ray budget rule", BUDGETS)
    joint: bool = _setting(False, _check_joint, "certify reflectance and transmittance together (each at delta/2)")
    pilot_rays: int | None = _setting(
        None, _rays("pilot_rays"), "two-stage pilot rays per reading, 1 ... 2**32 - 1 (default ceil(10/mu))")
    pilot_delta: float | None = _setting(
        None, _check_pilot_delta, "two-stage pilot failure probability, 0 < pilot_delta < delta (default delta/10)")
    beam: str = _setting("conical", _choice("beam", BEAMS), "beam geometry", BEAMS)
    sampling: str = _setting("jittered", _choice("sampling", SAMPLINGS), "disk sampling", SAMPLINGS)
    seed: int = _setting(0, _whole("seed", 0, 2**32 - 1, "0 <= seed < 2**32"), "seed of the random numbers")
    chunk_size: int = _setting(
        1 << 22, _whole("chunk_size", 1024, MAX_CHUNK_SIZE, f"1024 <= chunk_size <= 2**{_CHUNK_LOG2}"),
        f"rays per kernel launch, 1024 ... 2**{_CHUNK_LOG2} (bounds memory; results do not depend on it)")

    def __post_init__(self) -> None:
        for item in fields(self):
            value = getattr(self, item.name)
            if value is not None:
                object.__setattr__(self, item.name, item.metadata["check"](value))
        if self.pilot_delta is not None and not 0.0 < self.pilot_delta < self.delta:
            raise ValueError(f"pilot_delta must satisfy 0 < pilot_delta < delta = {shown_value(self.delta)} "
                             f"(got {shown_value(self.pilot_delta)})")
        self._check_derived_deltas()

    def _check_derived_deltas(self) -> None:
        """
        The probabilities derived from δ (δ/2 with ``joint``; the two-stage δ₁ and δ − δ₁,
        halved with ``joint``) must be normal floats like δ: refused here, before tracing.
        """

        share = 2 if self.joint else 1
        derived = {"delta/2 (joint)": self.quantity_delta} if self.joint else {}
        if self.rays is None and self.budget.adaptive:
            pilot = self.pilot_delta_value
            derived[f"pilot_delta{'/2' if self.joint else ''}"] = pilot / share
            derived[f"(delta - pilot_delta){'/2' if self.joint else ''}"] = (self.delta - pilot) / share
        for name, value in derived.items():
            check_delta(value, name=name)

    @classmethod
    def describe(cls) -> str:
        """One line per setting: name, default, meaning and allowed values (the CLI's help says the same)."""

        return "\n".join(f"{item.name} = {shown(item.default)}: {help_text(item)}" for item in fields(cls))

    @property
    def budget(self) -> RayBudget:
        """The ray-budget rule object of :data:`virtspec_mi.budgets.rules.BUDGETS` named by ``bound``."""

        return BUDGETS[self.bound]

    @property
    def adaptive(self) -> bool:
        """True when each reading is sized by its own pilot (an adaptive rule without ``rays``)."""

        return self.rays is None and self.budget.adaptive

    @property
    def quantity_delta(self) -> float:
        """δ of each certified quantity: δ, or δ/2 with ``joint`` (R and T together at δ)."""

        return self.delta / 2 if self.joint else self.delta

    @property
    def rays_per_reading(self) -> int:
        """
        ``rays`` if given, else the fixed rule's N at μ and the quantity δ (``ValueError``
        if adaptive, or if N exceeds :data:`~virtspec_mi.checks.MAX_RAYS`).
        """

        if self.rays is not None:
            return self.rays
        return check_rays_needed(self.budget.rays(self.mu, self.quantity_delta), self._rule())

    @property
    def most_rays_per_reading(self) -> int:
        """The most rays one reading may trace in one batch (its key range in a sweep), ≤ 2³² − 1."""

        if self.rays is not None:
            return self.rays
        return check_rays_needed(self.budget.most_rays(self), self._rule())

    @property
    def most_rays_spent_per_reading(self) -> int:
        """The most rays one reading traces in all, the two-stage pilot included (the per-call budget)."""

        if not self.adaptive:
            return self.rays_per_reading
        return self.pilot_rays_per_reading + self.most_rays_per_reading

    @property
    def pilot_rays_per_reading(self) -> int:
        """Two-stage pilot size n₁: ``pilot_rays`` or the rule's default ⌈10/μ⌉ (≤ 2³² − 1)."""

        if self.pilot_rays is not None:
            return self.pilot_rays
        return check_rays_needed(self.budget.default_pilot_rays(self.mu),
                                 f"the default two-stage pilot ceil(10/mu) for mu = {shown_value(self.mu)}")

    def _rule(self) -> str:
        """The ray budget in words, for messages: rule, μ and δ."""

        joint = " (each quantity at delta/2: joint)" if self.joint else ""
        return f"the {self.bound} bound for mu = {shown_value(self.mu)}, delta = {shown_value(self.delta)}{joint}"

    @property
    def pilot_delta_value(self) -> float:
        """Two-stage pilot failure probability δ₁: ``pilot_delta`` or the rule's default δ/10."""

        return self.pilot_delta if self.pilot_delta is not None else self.budget.default_pilot_delta(self.delta)

    def updated(self, **changes: Any) -> "Settings":
        """A copy with the given fields replaced (``None`` values are ignored), re-validated."""

        return replace(self, **{k: v for k, v in changes.items() if v is not None})

    def as_dict(self) -> dict[str, Any]:
        """Plain-data view (for JSON and result files): every field, rays and pilot sizes resolved."""

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


def shown(value: Any) -> str:
    """A default as a user writes it: ``551``, ``0``, ``hoeffding``, ``none``."""

    if value is None:
        return "none"
    if isinstance(value, tuple):
        return ", ".join(shown(v) for v in value)
    return f"{value:g}" if isinstance(value, float) else str(value)


def help_text(item: Any) -> str:
    """A setting's help text with its choices and what each means."""

    choices = item.metadata["choices"]
    if not choices:
        return item.metadata["help"]
    meanings = "; ".join(f"{name}: {getattr(value, 'description', value)}" for name, value in choices.items())
    return f"{item.metadata['help']} ({meanings})"


SETTING_NAMES: tuple[str, ...] = tuple(item.name for item in fields(Settings))
"""The names of every setting, in definition order."""


def settings_keywords(function: Callable, exclude: tuple[str, ...] = ()) -> inspect.Signature:
    """
    ``function``'s signature with every setting appended as a keyword-only ``name=None``
    (a setting left ``None`` comes from the scene's integrator, else from the default).
    """

    own = [p for p in inspect.signature(function).parameters.values() if p.kind is not p.VAR_KEYWORD]
    names = {p.name for p in own}
    extra = [inspect.Parameter(name, inspect.Parameter.KEYWORD_ONLY, default=None)
             for name in SETTING_NAMES if name not in names and name not in exclude]
    return inspect.signature(function).replace(parameters=[*own, *extra])


def with_settings(base: Settings, overrides: dict[str, Any], caller: str) -> Settings:
    """
    ``base`` with the settings named in ``overrides`` replaced (``None`` keeps the base
    value); an unknown name raises ``TypeError`` listing the settings.
    """

    unknown = sorted(set(overrides) - set(SETTING_NAMES))
    if unknown:
        raise TypeError(f"{caller}() got unexpected keyword argument(s) {', '.join(unknown)}; "
                        f"the settings are {', '.join(SETTING_NAMES)}")
    return base.updated(**overrides)
