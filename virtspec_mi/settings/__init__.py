"""
Options and measurement settings: defined once, validated once
==============================================================

The one-definition machinery of every instrument's options, and the common
:class:`Settings` of a measurement.

- :func:`option` declares a field: its default, its check (naming the parameter and its
  allowed range, e.g. from :mod:`virtspec_mi.base.checks`), its help text and, for a choice,
  its choices and what each means.
- :class:`Options` is the frozen-dataclass base of every set of options: on construction
  it validates each field with its check (``None`` means the field's default; a value
  may arrive as a string — XML, command line — and the check converts it: ``"5"`` is
  read as 5 everywhere, a boolean is never a number), then the rules between fields
  (:meth:`Options._check_together`). Everything else derives from the fields:
  :meth:`Options.describe`, :meth:`Options.names`, :meth:`Options.updated`,
  :meth:`Options.as_dict`, :meth:`Options.from_parameters` (the one reader of XML/dict
  integrator parameters) and :func:`keywords` (the one builder of the API's signatures);
  the command line makes one ``--flag`` per field (:mod:`virtspec_mi.cli`).
- :func:`resolve` takes an API call's keywords: each goes to the options that declare it
  (an unknown name is a ``TypeError`` listing the names), over the scene's values.

:class:`Settings` is the one definition of the 14 settings every instrument shares;
each instrument declares its own options beside them
(:class:`virtspec_mi.instruments.goniophotometer.GonioOptions`,
:class:`virtspec_mi.instruments.sphere.SphereOptions`). Validation happens once, when
the options are built: code below this boundary takes validated values. Defaults are
the paper's: μ = 0.005, δ = 0.01, the exponential Chebyshev bound (eq. 23), conical
beam, jittered sampling (eq. 4), λ = 551 nm, θi = φi = 0°.

References
----------
Baranoski et al. (2001), eqs. (3), (4), (23); Sect. 3.2.
"""

from __future__ import annotations

import inspect
import math
from dataclasses import dataclass, field, fields, replace
from typing import Any, Callable, ClassVar, Mapping, TypeVar

from virtspec_mi.budgets.betting import CERTIFICATES
from virtspec_mi.budgets.rules import BUDGETS, RayBudget
from virtspec_mi.base.checks import (
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

__all__ = [
    "option",
    "Options",
    "keywords",
    "resolve",
    "one_of",
    "text",
    "share",
    "true_or_false",
    "whole_number",
    "BEAMS",
    "SAMPLINGS",
    "Settings",
    "SETTING_NAMES",
    "shown",
    "help_text",
]

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


# --- checks shared by the options of every instrument -------------------------------------


def text(name: str, what: str = "a text") -> Callable[[Any], str]:
    """The check of a text that is not empty (a file path, a target's words): ``what`` it must be, in the message."""

    def check(value: Any) -> str:
        if not isinstance(value, str) or not value.strip():
            raise ValueError(f"{name} must be {what} (got {shown_value(value)})")
        return value
    return check


def one_of(name: str, choices: Mapping[str, Any], fold: Callable[[str], str] | None = None) -> Callable[[Any], str]:
    """The check of a choice: one of ``choices``' names (``fold``, e.g. ``str.upper``, applied to a string first)."""

    def check(value: Any) -> str:
        if isinstance(value, str) and fold is not None:
            value = fold(value)
        if not isinstance(value, str) or value not in choices:
            raise ValueError(f"{name} must be one of {', '.join(choices)} (got {value!r})")
        return value
    return check


def share(name: str) -> Callable[[Any], float]:
    """The check of a share of one: a number 0 < x ≤ 1 (a numeric string is read as the number)."""

    def check(value: Any) -> float:
        result = number(name, value)
        if not 0.0 < result <= 1.0:
            raise ValueError(f"{name} must satisfy 0 < {name} <= 1 (got {shown_value(value)})")
        return result
    return check


def true_or_false(name: str) -> Callable[[Any], bool]:
    """The check of a switch: ``True``/``False`` (or 1/0, ``"true"``/``"false"``)."""

    def check(value: Any) -> bool:
        if isinstance(value, str) and value.lower() in ("true", "false"):
            return value.lower() == "true"
        if not isinstance(value, (bool, int)) or value not in (0, 1):
            raise ValueError(f"{name} must be true or false (got {value!r})")
        return bool(value)
    return check


def whole_number(name: str, low: int, high: int, shown: str) -> Callable[[Any], int]:
    """
    The check of a whole number ``low`` ≤ n ≤ ``high`` (``shown``: that range as the
    message says it); a numeric string is read as the number, a boolean refused.
    """

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


# --- the machinery --------------------------------------------------------------------------


def option(default: Any, check: Callable[[Any], Any], help: str, choices: Mapping[str, Any] | None = None, *,
           words: bool = False, unset: str = "none", flag: bool = True, positional: bool = False,
           repeat: bool = False, spelled: str | None = None, metavar: str | None = None, required: bool = False,
           hidden: bool = False) -> Any:
    """
    A field of an :class:`Options` class: the one definition of one option.

    Parameters
    ----------
    default
        Its value when not given (``None``: unset).
    check
        Turns a value as given (a string too) into the validated value, or raises
        ``ValueError`` naming the option and its allowed range.
    help
        What it means, with its range (the CLI's help, :meth:`Options.describe`).
    choices
        For a choice: name → meaning (or an object with a ``description``).
    words
        The command line takes it as several words (``--wavelengths 400 500``), joined by spaces.
    unset
        What an unset ``None`` default means, in words (``"from the rule"``).
    flag
        ``False``: no command-line flag (a value no one types, e.g. a
        :class:`~virtspec_mi.instruments.sphere.geometry.Sphere`).
    positional, repeat, spelled, metavar, required, hidden
        How the command line writes it (an application's command): a positional argument; a flag
        given once per value (the check receives the tuple of values); a flag spelled
        otherwise than ``--name`` (``-D``, ``--from``); the word that stands for its value
        in the help; a flag that must be given; a flag left out of the help.
    """

    return field(default=default, metadata={"check": check, "help": help, "choices": choices, "words": words,
                                            "unset": unset, "flag": flag, "positional": positional, "repeat": repeat,
                                            "spelled": spelled, "metavar": metavar, "required": required,
                                            "hidden": hidden})


OptionsT = TypeVar("OptionsT", bound="Options")


class Options:
    """
    Base of a frozen dataclass of options declared with :func:`option` (see the module
    docstring): validated field by field on construction, then together.
    """

    title: ClassVar[str] = "options"
    """What these options are called in messages (``"the settings are …"``)."""

    def __post_init__(self) -> None:
        for item in fields(self):
            value = getattr(self, item.name)
            if value is None:
                value = item.default  # None means the default
            if value is not None:
                value = item.metadata["check"](value)
            object.__setattr__(self, item.name, value)
        self._check_together()

    def _check_together(self) -> None:
        """The rules between fields (each field is valid on its own by now); none by default."""

    @classmethod
    def names(cls) -> tuple[str, ...]:
        """The names of the options, in definition order."""

        return tuple(item.name for item in fields(cls))

    @classmethod
    def describe(cls) -> str:
        """One line per option: name, default, meaning and allowed values (the CLI's help says the same)."""

        return "\n".join(f"{item.name} = {shown(item.default)}: {help_text(item)}" for item in fields(cls))

    @classmethod
    def keyword_parameters(cls) -> list[inspect.Parameter]:
        """
        These options as keyword-only parameters of a signature (:func:`keywords`): each
        ``name=None`` (a value left ``None`` comes from the scene's integrator, else from
        the default).
        """

        return [inspect.Parameter(name, inspect.Parameter.KEYWORD_ONLY, default=None) for name in cls.names()]

    @classmethod
    def keywords(cls, function: Callable, exclude: tuple[str, ...] = ()) -> inspect.Signature:
        """``function``'s signature with these options as keywords (:func:`keywords`)."""

        return keywords(function, cls, exclude=exclude)

    @classmethod
    def from_parameters(cls: type[OptionsT], parameters: Any) -> OptionsT:
        """
        The options from an integrator's XML/dict parameters (a dict or ``mi.Properties``):
        each option named there, as given (strings are converted by the checks); the
        others take their default. The one reader of integrator parameters.
        """

        values = {name: parameters.get(name) for name in cls.names() if name in parameters}
        return cls(**{**values, **cls._gathered(parameters)})

    @classmethod
    def _gathered(cls, parameters: Any) -> dict[str, Any]:
        """Options made of several flat parameters (e.g. a sphere description), by name; none by default."""

        return {}

    @classmethod
    def parameters_in(cls, parameters: Any) -> list[str]:
        """The names in ``parameters`` (a dict or ``mi.Properties``) that these options read."""

        return [name for name in parameters.keys() if name in cls.names() or cls._gathers(name)]

    @classmethod
    def _gathers(cls, name: str) -> bool:
        """True for a flat parameter name that :meth:`_gathered` reads."""

        return False

    def updated(self: OptionsT, **changes: Any) -> OptionsT:
        """
        A copy with the given options replaced (``None`` values are ignored),
        re-validated; an unknown name raises ``TypeError`` listing the names.
        """

        unknown = sorted(set(changes) - set(self.names()))
        if unknown:
            raise TypeError(f"unexpected {self.title} {', '.join(unknown)}; the {self.title} are "
                            f"{', '.join(self.names())}")
        return replace(self, **{k: v for k, v in changes.items() if v is not None})

    def as_dict(self) -> dict[str, Any]:
        """Plain-data view (JSON, result files): every option, sequences as lists."""

        return {name: list(value) if isinstance(value, tuple) else value
                for name, value in ((n, getattr(self, n)) for n in self.names())}


def keywords(function: Callable, *kinds: type[Options], exclude: tuple[str, ...] = ()) -> inspect.Signature:
    """
    The one signature builder: ``function``'s signature with every option of ``kinds``
    (in order) appended as a keyword-only parameter (:meth:`Options.keyword_parameters`:
    ``name=None`` — a value left ``None`` comes from the scene's integrator, else from the
    default — or a kind's own, e.g. the API's run options with their defaults), except
    those ``function`` declares itself, those an earlier kind gave, and those in ``exclude``.
    """

    signature = inspect.signature(function)
    own = [p for p in signature.parameters.values() if p.kind is not p.VAR_KEYWORD]
    taken = {p.name for p in own} | set(exclude)
    extra = []
    for kind in kinds:
        for parameter in kind.keyword_parameters():
            if parameter.name not in taken:
                extra.append(parameter)
                taken.add(parameter.name)
    return signature.replace(parameters=[*own, *extra])


def resolve(caller: str, given: Mapping[str, Any], *bases: Options) -> tuple[Any, ...]:
    """
    Each of ``bases`` (the scene's options, or the defaults) with the keywords of
    ``given`` that it declares replaced (``None`` keeps the base value), validated; a
    name none of them declares raises ``TypeError`` listing every name.
    """

    unknown = sorted(set(given) - {name for base in bases for name in base.names()})
    if unknown:
        names = "; ".join(f"the {base.title} are {', '.join(base.names())}" for base in bases)
        raise TypeError(f"{caller}() got unexpected keyword argument(s) {', '.join(unknown)}; {names}")
    return tuple(base.updated(**{k: v for k, v in given.items() if k in base.names()}) for base in bases)


def shown(value: Any) -> str:
    """A default as a user writes it: ``551``, ``0``, ``hoeffding``, ``none``."""

    if value is None:
        return "none"
    if isinstance(value, tuple):
        return ", ".join(shown(v) for v in value)
    return f"{value:g}" if isinstance(value, float) else str(value)


def help_text(item: Any) -> str:
    """An option's help text with its choices and what each means."""

    choices = item.metadata["choices"]
    if not choices:
        return item.metadata["help"]
    meanings = "; ".join(f"{name}: {getattr(value, 'description', value)}" for name, value in choices.items())
    return f"{item.metadata['help']} ({meanings})"


# --- the common settings ----------------------------------------------------------------------


def _check_phi(value: Any) -> float:
    phi = number("phi_i", value)
    if not math.isfinite(phi):
        raise ValueError(f"phi_i must be a finite number of degrees (got {shown_value(phi)})")
    return phi


def _check_pilot_delta(value: Any) -> float:
    return number("pilot_delta", value)  # its range, 0 < pilot_delta < delta, needs delta: see _check_together


def _rays(name: str) -> Callable[[Any], int]:
    def check(value: Any) -> int:
        return check_rays(value, name=name)
    return check


_CHUNK_LOG2 = MAX_CHUNK_SIZE.bit_length() - 1  # MAX_CHUNK_SIZE is a power of two


@dataclass(frozen=True)
class Settings(Options):
    """
    Everything that defines a measurement besides the scene; validated on construction.

    Every field is listed with its default, allowed values and meaning in
    ``Settings.describe()`` (the same text the CLI's ``--help`` shows).
    """

    title: ClassVar[str] = "settings"

    theta_i: float = option(0.0, check_theta_i, "polar incidence angle, degrees in [0, 90]")
    phi_i: float = option(0.0, _check_phi, "azimuthal incidence angle from the specimen's x axis, degrees")
    wavelengths: tuple[float, ...] = option(
        (551.0,), parse_wavelengths,
        f"wavelengths in nm ({WAVELENGTH_RANGE[0]:g} ... {WAVELENGTH_RANGE[1]:g}): numbers and start:stop:step "
        "ranges, e.g. 400:700:10", words=True)
    mu: float = option(0.005, check_mu, "certified tolerance, 0 < mu < 0.5")
    delta: float = option(0.01, check_delta, "failure probability, 0 < delta < 1")
    rays: int | None = option(None, _rays("rays"), "rays per reading, 1 ... 2**32 - 1 (overrides the bound)",
                              unset="from the rule")
    bound: str = option("hoeffding", one_of("bound", {**BUDGETS, **CERTIFICATES}),
                        "ray budget rule (auto and betting: a target's certificate only)", {**BUDGETS, **CERTIFICATES})
    joint: bool = option(False, true_or_false("joint"),
                         "certify reflectance and transmittance together (each at delta/2)")
    pilot_rays: int | None = option(
        None, _rays("pilot_rays"), "two-stage pilot rays per reading, 1 ... 2**32 - 1 (default ceil(10/mu))",
        unset="from the rule")
    pilot_delta: float | None = option(
        None, _check_pilot_delta, "two-stage pilot failure probability, 0 < pilot_delta < delta (default delta/10)",
        unset="from the rule")
    beam: str = option("conical", one_of("beam", BEAMS), "beam geometry", BEAMS)
    sampling: str = option("jittered", one_of("sampling", SAMPLINGS), "disk sampling", SAMPLINGS)
    seed: int = option(0, whole_number("seed", 0, 2**32 - 1, "0 <= seed < 2**32"), "seed of the random numbers")
    chunk_size: int = option(
        1 << 22, whole_number("chunk_size", 1024, MAX_CHUNK_SIZE, f"1024 <= chunk_size <= 2**{_CHUNK_LOG2}"),
        f"rays per kernel launch, 1024 ... 2**{_CHUNK_LOG2} (bounds memory; results do not depend on it)")

    def _check_together(self) -> None:
        """
        0 < ``pilot_delta`` < δ; and the probabilities derived from δ (δ/2 with ``joint``;
        the two-stage δ₁ and δ − δ₁, halved with ``joint``) must be normal floats like δ:
        refused here, before tracing.
        """

        if self.bound not in BUDGETS:
            raise ValueError(f"bound {self.bound} certifies a target (give target=..., --target on the command line); "
                             f"a spectrum's ray budget rule is one of {', '.join(BUDGETS)}")
        if self.pilot_delta is not None and not 0.0 < self.pilot_delta < self.delta:
            raise ValueError(f"pilot_delta must satisfy 0 < pilot_delta < delta = {shown_value(self.delta)} "
                             f"(got {shown_value(self.pilot_delta)})")
        share = 2 if self.joint else 1
        derived = {"delta/2 (joint)": self.quantity_delta} if self.joint else {}
        if self.rays is None and self.budget.adaptive:
            pilot = self.pilot_delta_value
            derived[f"pilot_delta{'/2' if self.joint else ''}"] = pilot / share
            derived[f"(delta - pilot_delta){'/2' if self.joint else ''}"] = (self.delta - pilot) / share
        for name, value in derived.items():
            check_delta(value, name=name)

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
        if adaptive, or if N exceeds :data:`~virtspec_mi.base.checks.MAX_RAYS`).
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


SETTING_NAMES: tuple[str, ...] = Settings.names()
"""The names of every setting, in definition order."""
