"""
Targets written as text: ``virtspec measure --target ...``, ``virtspec sweep --target ...``
===========================================================================================

:func:`parse_target` reads a target from one string, ``KIND[:ARG]...[,NAME=VALUE]...``,
by the table :data:`~.targets.TARGETS`: ``KIND`` names a row (or one of its spellings,
``color``), the ``:`` arguments go to its constructor's positional-only parameters
(``band:B04:B08``, ``index:NDVI``), and each ``NAME=VALUE`` is one of the constructor's
options, converted by its annotation (a number, a word, true/false). An unknown kind or
option is refused naming the allowed ones, an option given twice is refused. The rows
today:

- ``colour`` (or ``color``) with ``dE00=0.5``, ``illuminant=D65``, ``observer=...``,
  ``quantity=``, ``step=10``;
- ``band:B04:B08`` (Sentinel-2 names, ``650-680`` edges in nm, or a two-column file) with
  ``tolerance=0.002``, ``quantity=``, ``step=1``;
- ``index:NDVI`` with ``tolerance=0.005``, ``step=1``;
- ``fapar`` with ``tolerance=0.002``, ``illuminant=D65``, ``low=400``, ``high=700``, ``step=1``;
- ``albedo`` (illuminant-weighted) with ``tolerance=0.002``, ``illuminant=D65``, ``low``, ``high``,
  ``quantity``, ``step``.

e.g. ``colour,dE00=0.5``, ``band:B04:B08,tolerance=0.002``, ``index:NDVI,tolerance=0.002``,
``fapar,tolerance=0.002``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable, ClassVar

from virtspec_mi.applications.targets.targets import TARGETS, Target, target_kind
from virtspec_mi.settings import Options, option, text

__all__ = ["parse_target", "kinds", "TargetFlags", "measure_target_command", "sweep_target_command", "respond",
           "respond_sweep", "target_help"]


def kinds() -> dict[str, tuple[str, ...]]:
    """Each kind of target of :data:`~.targets.TARGETS` and the options it takes, as a text writes them."""

    return {name: tuple(kind.options()) for name, kind in TARGETS.items()}


def _value(kind: str, name: str, text: str, to: type) -> Any:
    text = text.strip()
    if to is bool:
        if text.lower() not in ("true", "false"):
            raise ValueError(f"--target {kind}: {name} must be true or false (got {text!r})")
        return text.lower() == "true"
    try:
        return to(text)
    except ValueError:
        raise ValueError(f"--target {kind}: {name} must be {'a number' if to is float else 'a whole number'} "
                         f"(got {text!r})") from None


def parse_target(text: str) -> Target:
    """The :class:`~.targets.Target` written ``text`` (see the module docstring)."""

    head, *pairs = [part.strip() for part in str(text).split(",")]
    word, *arguments = [part.strip() for part in head.split(":")]
    try:
        kind, row = target_kind(word)
    except ValueError:
        raise ValueError(f"--target: the kind must be one of {', '.join(TARGETS)} (got {text!r}), e.g. "
                         "colour,dE00=0.5 or band:B04:B08,tolerance=0.002") from None
    allowed = row.options()
    accepted = {**allowed, **{long: allowed[short] for short, long in row.short if short in allowed}}
    options: dict[str, Any] = {}
    for pair in pairs:
        name, sep, value = pair.partition("=")
        name = name.strip()
        if not sep or name not in accepted:
            raise ValueError(f"--target {kind}: options are NAME=VALUE with NAME one of "
                             f"{', '.join(allowed) or '(none)'} (got {pair!r})")
        if row.keyword(name) in options:
            raise ValueError(f"--target {kind}: {name} given twice (got {text!r})")
        options[row.keyword(name)] = _value(kind, name, value, accepted[name])
    fewest, most = row.arguments()
    if most == 0 and arguments:
        raise ValueError(f"--target {kind} takes no ':' arguments (got {arguments})")
    if len(arguments) < fewest or (most is not None and len(arguments) > most):
        count = f"{fewest}" if most == fewest else f"at least {fewest}"
        raise ValueError(f"--target {kind} needs {count} ':' argument{'s' if most != 1 else ''}, "
                         f"e.g. {_example(kind)} (got {len(arguments)})")
    return row.make(*arguments, **options)


_EXAMPLES = {"band": "band:B04:B08 or band:650-680", "index": "index:NDVI"}


def _example(kind: str) -> str:
    return _EXAMPLES.get(kind, f"{kind}:ARG")


def target_help() -> str:
    """The ``--target`` help: an example, then each row of :data:`~.targets.TARGETS` with its options."""

    rows = "; ".join(kind.describe(name) for name, kind in TARGETS.items())
    return ("certify a derived quantity instead of a spectrum, KIND[:ARG...][,NAME=VALUE...], e.g. colour,dE00=0.5 | "
            f"band:B04:B08,tolerance=0.002 | index:NDVI,tolerance=0.002 | fapar,tolerance=0.002; the kinds: {rows} "
            "(the instrument picks the wavelengths and the rays of each)")



@dataclass(frozen=True)
class TargetFlags(Options):
    """``virtspec measure``'s and ``sweep``'s own flags: a derived quantity certified instead of the spectrum."""

    title: ClassVar[str] = "derived quantity"

    target: str | None = option(None, text("target", "a text such as colour,dE00=0.5"), target_help())
    checkpoint: str | None = option(None, text("checkpoint", "a file path"),
                                    "keep the target's traced batches in this JSON file, saved after each: the same "
                                    "command resumes from it after an interruption, to the same result (removed once "
                                    "the result is printed)")


def measure_target_command(args: Any, keywords: dict[str, Any], report: Callable[..., int]) -> int:
    """
    ``virtspec measure SCENE --target TARGET``: the target measured (``vm.measure(scene,
    target=...)``) and printed by ``report`` (its summary, or with ``--json`` its file: ``as_dict()`` sealed).
    The flags it does not take were refused by the command line
    (:attr:`~virtspec_mi.applications.base.Extension.takes`).
    """

    from virtspec_mi.applications.targets.sequential import measure_target
    from virtspec_mi.runtime.scene import loaded

    settings = {k: v for k, v in keywords.items()
                if k not in ("out", "workers", "task_readings", "points", "parameters", "defines")}
    if getattr(args, "checkpoint", None):
        settings["checkpoint"] = args.checkpoint
    result = measure_target(loaded(args.scene, keywords.get("defines") or None), None, _parsed(args.target), settings)
    return report(args, result, result.summary())  # --json: its file (sealed JSON, read by vm.read_result)


def sweep_target_command(args: Any, keywords: dict[str, Any], report: Callable[..., int]) -> int:
    """
    ``virtspec sweep SCENE --target TARGET``: the target certified at every θi of
    ``--theta-i`` (:func:`~.sweep.target_sweep`, as ``vm.sweep(scene, target=…)``), kept
    in ``--checkpoint`` or traced on ``--workers``, printed by ``report``.
    """

    from virtspec_mi.applications.targets.sweep import target_sweep
    from virtspec_mi.runtime.reading import RunOptions
    from virtspec_mi.runtime.scene import loaded

    settings = {k: v for k, v in keywords.items() if k not in RunOptions.names()}
    result = target_sweep(loaded(args.scene, keywords.get("defines") or None), _parsed(args.target), settings,
                          keywords.get("theta_i"), getattr(args, "checkpoint", None), keywords.get("workers"),
                          keywords.get("progress"))
    return report(args, result, result.summary())


def _parsed(text: str) -> Target:
    """The target of ``--target``; a refusal names the flag."""

    try:
        return parse_target(text)
    except ValueError as error:
        message = str(error)
        raise ValueError(message if message.startswith("--target") else f"--target: {message}") from None


def _reporting(session: Any) -> Callable[..., int]:
    return lambda _, result, text, data=None: session.report(result, text, data=data)


def respond(session: Any, flags: TargetFlags) -> int:
    """``virtspec measure --target``: the derived quantity certified (:func:`measure_target_command`)."""

    return measure_target_command(session.args, session.keywords, _reporting(session))


def respond_sweep(session: Any, flags: TargetFlags) -> int:
    """``virtspec sweep --target``: the derived quantity certified at every θi (:func:`sweep_target_command`)."""

    return sweep_target_command(session.args, session.keywords, _reporting(session))
