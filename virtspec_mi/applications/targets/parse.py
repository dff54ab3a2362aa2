"""
Targets written as text: ``virtspec measure --target ...``
==========================================================

:func:`parse_target` reads a target from one string, ``KIND[:ARG]...[,NAME=VALUE]...``:

- ``colour`` (or ``color``) with ``dE00=0.5``, ``illuminant=D65``, ``observer=...``,
  ``quantity=``, ``step=10``;
- ``band:B04:B08`` (Sentinel-2 names, ``650-680`` edges in nm, or a two-column file) with
  ``tolerance=0.002``, ``quantity=``, ``step=1``;
- ``index:NDVI`` with ``tolerance=0.005``, ``step=1``;
- ``fapar`` with ``tolerance=0.002``, ``illuminant=D65``, ``low=400``, ``high=700``, ``step=1``;
- ``albedo`` (illuminant-weighted) with ``tolerance=0.002``, ``illuminant=D65``, ``low``, ``high``,
  ``quantity``, ``step``.

e.g. ``colour,dE00=0.5``, ``band:B04:B08,tolerance=0.002``, ``index:NDVI,tolerance=0.002``,
``fapar,tolerance=0.002``. An unknown kind or name is refused with the allowed ones.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable, ClassVar

import virtspec_mi.applications.targets.targets as targets
from virtspec_mi.applications.targets.targets import Target
from virtspec_mi.settings import Options, option

__all__ = ["parse_target", "KINDS", "TargetFlags", "measure_target_command", "respond"]

KINDS: dict[str, tuple[str, ...]] = {
    "colour": ("dE00", "illuminant", "observer", "quantity", "step"),
    "band": ("tolerance", "quantity", "step"),
    "index": ("tolerance", "step"),
    "fapar": ("tolerance", "illuminant", "low", "high", "step"),
    "albedo": ("tolerance", "illuminant", "low", "high", "quantity", "step"),
}
"""Each kind of target and the names it takes."""

_NUMBERS = {"dE00", "tolerance", "step", "low", "high"}


def _band_argument(text: str) -> Any:
    low, sep, high = text.partition("-")
    if sep:
        try:
            return float(low), float(high)
        except ValueError:
            pass
    return text


def parse_target(text: str) -> Target:
    """The :class:`~.targets.Target` written ``text`` (see the module docstring)."""

    head, *pairs = [part.strip() for part in str(text).split(",")]
    kind, *arguments = [part.strip() for part in head.split(":")]
    kind = "colour" if kind.lower() == "color" else kind.lower()
    if kind not in KINDS:
        raise ValueError(f"--target: the kind must be one of {', '.join(KINDS)} (got {text!r}), e.g. "
                         "colour,dE00=0.5 or band:B04:B08,tolerance=0.002")
    options: dict[str, Any] = {}
    for pair in pairs:
        name, sep, value = pair.partition("=")
        if not sep or name.strip() not in KINDS[kind]:
            raise ValueError(f"--target {kind}: options are NAME=VALUE with NAME one of {', '.join(KINDS[kind])} "
                             f"(got {pair!r})")
        name = name.strip()
        try:
            options[name] = float(value) if name in _NUMBERS else value.strip()
        except ValueError:
            raise ValueError(f"--target {kind}: {name} must be a number (got {value!r})") from None
    if kind == "colour":
        if arguments:
            raise ValueError(f"--target colour takes no ':' arguments (got {arguments})")
        if "dE00" in options:
            options["tolerance_dE00"] = options.pop("dE00")
        return targets.colour(**options)
    if kind == "band":
        if not arguments:
            raise ValueError("--target band needs at least one band, e.g. band:B04 or band:650-680")
        return targets.band(*[_band_argument(a) for a in arguments], **options)
    if kind == "index":
        if len(arguments) != 1:
            raise ValueError("--target index needs one index name, e.g. index:NDVI")
        return targets.index(arguments[0], **options)
    if arguments:
        raise ValueError(f"--target {kind} takes no ':' arguments (got {arguments})")
    return targets.albedo(**options) if kind == "albedo" else targets.fapar(**options)


def _check_target(value: Any) -> str:
    if not isinstance(value, str) or not value.strip():
        raise ValueError(f"target must be a text such as colour,dE00=0.5 (got {value!r})")
    return value


@dataclass(frozen=True)
class TargetFlags(Options):
    """``virtspec measure``'s own flag: a derived quantity certified instead of the spectrum."""

    title: ClassVar[str] = "derived quantity"

    target: str | None = option(
        None, _check_target, "certify a derived quantity instead of a spectrum, e.g. colour,dE00=0.5 | "
        "band:B04:B08,tolerance=0.002 | index:NDVI,tolerance=0.002 | fapar,tolerance=0.002 (the instrument picks "
        "the wavelengths and the rays of each)")


def measure_target_command(args: Any, keywords: dict[str, Any], report: Callable[..., int]) -> int:
    """
    ``virtspec measure SCENE --target TARGET``: the target measured (``vm.measure(scene,
    target=...)``) and printed by ``report`` (its summary, or with ``--json`` its ``as_dict()``).
    The flags it does not take were refused by the command line
    (:attr:`~virtspec_mi.applications.base.Extension.takes`).
    """

    from virtspec_mi.applications.targets.measure import measure_target
    from virtspec_mi.runtime.scene import loaded

    try:
        target = parse_target(args.target)
    except ValueError as error:
        message = str(error)
        raise ValueError(message if message.startswith("--target") else f"--target: {message}") from None
    settings = {k: v for k, v in keywords.items()
                if k not in ("out", "workers", "task_readings", "points", "parameters", "defines", "progress")}
    result = measure_target(loaded(args.scene, keywords.get("defines") or None), None, target, settings)
    return report(args, result, result.summary(), data=result.as_dict())


def respond(session: Any, flags: TargetFlags) -> int:
    """``virtspec measure --target``: the derived quantity certified (:func:`measure_target_command`)."""

    return measure_target_command(session.args, session.keywords,
                                  lambda _, result, text, data=None: session.report(result, text, data=data))
