"""
``virtspec klems SCENE`` and its alias ``virtspec gonio --klems FILE``, declared
==================================================================================

:data:`KLEMS` is the Klems application's :class:`~virtspec_mi.applications.base.Command`
(its flags :class:`KlemsCommandFlags`, :func:`respond`); :data:`GONIO_KLEMS` the
:class:`~virtspec_mi.applications.base.Extension` that keeps ``virtspec gonio --klems FILE``
as an alias of it: ``--klems-basis``, ``--isotropic``, and of ``gonio``'s flags only those
it :attr:`~virtspec_mi.applications.base.Extension.takes` (``--wavelengths``, ``--mu`` the
tolerance of every patch fraction, ``--delta``, ``--rays``, ``--seed``, ``--quiet``); the
command line refuses any other, in one message.

References
----------
Klems, J.H. (1994). ASHRAE Transactions 100(1), 1065–1072.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar

from virtspec_mi.applications.base import Command, Extension, Session
from virtspec_mi.base.checks import check_delta, check_rays, number, parse_wavelengths
from virtspec_mi.settings import Options, one_of, option, text, true_or_false, whole_number

__all__ = ["KLEMS", "GONIO_KLEMS", "KlemsCommandFlags", "KlemsFlags", "respond", "respond_gonio"]

_BASES = {"full": "145 patches", "half": "77 patches", "quarter": "41 patches"}



@dataclass(frozen=True)
class KlemsCommandFlags(Options):
    """The arguments and flags of ``virtspec klems`` (:func:`~virtspec_mi.applications.klems.measure.klems_measure`)."""

    title: ClassVar[str] = "Klems matrices"

    scene: str | None = option(None, text("scene", "a file path"), "Mitsuba XML scene with 'emitter' and 'specimen' disks, or a "
                               "shipped scene's name (virtspec scenes); its geometry does not matter (collimated beam)",
                               positional=True, metavar="SCENE")
    out: str | None = option(None, text("out", "a file path"), "the WINDOW 6 XML file to write, with its NetCDF sidecar FILE.nc "
                             "(its groups of readings kept in FILE.parts meanwhile: re-run to resume)", required=True,
                             metavar="FILE")
    basis: str = option("full", one_of("basis", _BASES), "Klems basis", _BASES)
    back: str | None = option(None, text("back", "a file path"), "a scene of the back side (e.g. a leaf with -D side=abaxial "
                              "written as its own file)", unset="the specimen turned over")
    wavelengths: tuple = option((551.0,), parse_wavelengths, "wavelengths in nm (numbers or start:stop:step)",
                                words=True)
    epsilon: float = option(0.01, lambda value: number("epsilon", value), "every patch fraction, R and T within "
                            "epsilon at once (0 < epsilon < 0.5)")
    delta: float = option(0.01, check_delta, "failure probability of the whole file")
    rays: int | None = option(None, check_rays, "rays per incidence (the certificate then states what they give)",
                              unset="sized by epsilon and delta")
    seed: int = option(0, whole_number("seed", 0, 2**32 - 1, "0 <= seed < 2**32"), "seed of the run")
    isotropic: bool = option(False, true_or_false("isotropic"), "one reading per ring, rotated onto its other patches "
                             "(rotation-invariant specimens)")
    name: str = option("virtspec-mi specimen", text("name", "a file path"), "the specimen's name in the file")
    overwrite: bool = option(False, true_or_false("overwrite"), "let the sidecar FILE.nc replace a file of that name "
                             "that is not a Klems sidecar")
    quiet: bool = option(False, true_or_false("quiet"), "no progress bar")


def _measured(scene: Any, out: str, quiet: bool, **keywords: Any) -> tuple[Any, str, str]:
    """The Klems matrices measured and written to ``out``, their statement and the files written, in words."""

    from virtspec_mi.applications.klems.matrices import sidecar_path
    from virtspec_mi.applications.klems.measure import klems_measure

    measured = klems_measure(scene, out=out, progress=False if quiet else None, **keywords)
    return measured, measured.statement(), f"{out} (certified bounds per patch: {sidecar_path(out)})"


def respond(session: Session) -> int:
    """``virtspec klems SCENE --out FILE``: the certified Klems matrices, written (WINDOW 6 XML and its sidecar)."""

    flags = session.flags
    measured, text, written = _measured(
        flags.scene, flags.out, flags.quiet, basis=flags.basis, back=flags.back, wavelengths=list(flags.wavelengths),
        epsilon=flags.epsilon, delta=flags.delta, rays=flags.rays, seed=flags.seed, isotropic=flags.isotropic,
        name=flags.name, overwrite=flags.overwrite)
    return session.report(measured, text, written=[written])


KLEMS = Command(
    "klems", "certified Klems BSDF matrices (WINDOW 6 XML) from the goniophotometer",
    "Measure the specimen of a scene on a Klems basis with the goniophotometer: one collimated reading per incident "
    "patch centre, front and back (the specimen turned over, or --back), every patch fraction of every matrix and "
    "every R and T within --epsilon at once with probability >= 1 - delta; writes the WINDOW 6 XML file and its "
    "NetCDF sidecar (the certified bounds per patch). Resumable: re-run the same command. virtspec gonio SCENE "
    "--klems FILE is an alias (--mu the tolerance).",
    ("virtspec klems soybean_abmb --out leaf.xml --basis quarter --epsilon 0.02 --isotropic",
     "virtspec klems diamond_collimated --out glass.xml --wavelengths 450,550,650"),
    KlemsCommandFlags, respond)
"""The Klems application's command (:class:`~virtspec_mi.applications.klems.KlemsApplication`)."""


@dataclass(frozen=True)
class KlemsFlags(Options):
    """
    ``virtspec gonio``'s flags of the alias ``--klems FILE`` (``virtspec klems SCENE --out
    FILE``): the Klems matrices instead of one reading.
    """

    title: ClassVar[str] = "Klems matrices (alias of virtspec klems)"

    klems: str | None = option(
        None, text("klems", "a file path"), "measure the Klems matrices instead (an alias of virtspec klems SCENE --out FILE; --mu "
                              "is the certified tolerance of every patch fraction) and write WINDOW 6 XML FILE with "
                              "its NetCDF sidecar FILE.nc")
    klems_basis: str = option("full", one_of("klems_basis", _BASES), "Klems basis of --klems", _BASES)
    isotropic: bool = option(False, true_or_false("isotropic"),
                             "--klems: one reading per ring, rotated onto its other patches (rotation-invariant "
                             "specimens)")


def respond_gonio(session: Any, flags: KlemsFlags) -> int:
    """``virtspec gonio SCENE --klems FILE``: :func:`respond`'s matrices, ``--mu`` their tolerance."""

    given = session.keywords
    measured, text, written = _measured(
        session.args.scene, flags.klems, session.args.quiet, basis=flags.klems_basis,
        wavelengths=given.get("wavelengths", 551.0), epsilon=float(given.get("mu", 0.01)),
        delta=float(given.get("delta", 0.01)), rays=None if "rays" not in given else int(given["rays"]),
        seed=int(given.get("seed", 0)), isotropic=flags.isotropic)
    return session.report(measured, f"{text}\nwritten: {written}")


GONIO_KLEMS = Extension(
    "gonio", KlemsFlags, respond_gonio, "klems", takes=("wavelengths", "mu", "delta", "rays", "seed", "quiet"),
    reason="it measures readings of its own (every patch centre, its own bins) and writes FILE and FILE.nc",
    example="--klems window.xml")
"""``virtspec gonio --klems FILE``: the documented alias of :data:`KLEMS`."""
