"""
Certified derived quantities: colour, sensor bands, indices, fAPAR
==================================================================

A question in the user's own units — a colour and its ΔE₀₀, a band's reflectance, an
index, the absorbed share of PAR — is a *target* the instrument sizes its rays for: a
linear functional of the spectrum costs the rays of one reading at its tolerance
(Hoeffding 1963 with Nₖ ∝ |wₖ|), nonlinear maps get intervals by propagating the
certified box. Modules, one job each:

- :mod:`.functionals` — linear functionals, their Hoeffding tolerance and allocation;
- :mod:`.delta_e` — L*a*b* boxes, exact ΔE*ab and a rigorous ΔE₀₀ enclosure;
- :mod:`.colour` — certified XYZ, L*a*b*, sRGB (``Result.colour()``);
- :mod:`.bands`, :mod:`.indices` — response functions, Sentinel-2 bands, indices;
- :mod:`.targets` — ``vm.colour``, ``vm.band``, ``vm.fapar``, ``vm.index``;
- :mod:`~virtspec_mi.applications.targets.measure` — a target's rays traced through the engine (Hoeffding, one batch);
  :mod:`.sequential` — batches until a betting confidence sequence certifies it (a colour's
  and an index's default); :mod:`.pooled` — a linear target's wavelengths pooled into one
  proportion, the exact two-stage rule (a band's and fAPAR's default); :mod:`.result` — its result;
- :mod:`.difference` — ``vm.colour_difference``; :mod:`.parse` — ``--target`` strings.

The application's row (:class:`TargetsApplication`) extends ``virtspec measure`` and
``virtspec sweep`` with ``--target`` and ``--checkpoint`` (:class:`~.parse.TargetFlags`;
:mod:`.sweep` certifies a target at every θi): it takes the settings a target does not pick
itself (:data:`~.measure.REFUSED_SETTINGS`, the one list, which ``vm.measure(target=...)``
and ``vm.sweep(target=...)`` read too) and the command line refuses every other flag.
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np

from virtspec_mi.applications.base import Application, Extension
from virtspec_mi.applications.targets.measure import REFUSED_SETTINGS
from virtspec_mi.applications.targets.parse import TargetFlags, respond, respond_sweep
from virtspec_mi.applications.targets.result import DerivedResult, DerivedSweep
from virtspec_mi.settings import Settings

__all__ = ["TargetsApplication"]


def _api(folder: Any) -> Any:
    """The example's target through Python: ``measure_target`` (``vm.measure(scene, target=...)``)."""

    from virtspec_mi.applications.targets.sequential import measure_target
    from virtspec_mi.applications.targets.targets import band
    from virtspec_mi.runtime.scene import loaded

    return measure_target(loaded("diamond_collimated"), None, band("B04", tolerance=0.05), {"seed": 1})


_REASON = ("a target picks its own wavelengths and rays (give it its tolerance, e.g. --target colour,dE00=0.5 or "
           "--target band:B04,tolerance=0.002) and is measured at the scene's own specimen parameters; "
           "its result is printed (--json prints it as JSON, its per-wavelength readings included)")
_TAKES = (*(name for name in Settings.names() if name not in REFUSED_SETTINGS), "defines", "json", "quiet")


class TargetsApplication(Application):
    """
    Certified derived quantities: ``vm.measure(scene, target=...)``, ``vm.sweep(scene,
    target=...)``, ``virtspec measure --target`` and ``virtspec sweep --target``.
    """

    name: ClassVar[str] = "targets"
    summary: ClassVar[str] = "certified derived quantities: colour, bands, indices, fAPAR, albedo"
    extensions: ClassVar[tuple[Extension, ...]] = (
        Extension("measure", TargetFlags, respond, "target", takes=_TAKES, reason=_REASON,
                  example="--target colour,dE00=0.5"),
        Extension("sweep", TargetFlags, respond_sweep, "target", takes=(*_TAKES, "workers", "scheduler"),
                  reason=_REASON + "; --workers traces each angle on a Dask worker",
                  example="--target colour,dE00=0.5"))
    results: ClassVar[tuple[type, ...]] = (DerivedResult, DerivedSweep)
    example: ClassVar[dict[str, Any]] = {
        "argv": ("measure", "diamond_collimated", "--target", "band:B04,tolerance=0.05", "--seed", "1", "--json"),
        "api": _api,
        "counts": lambda result: np.array([v.value for v in result.values] + [result.rays, result.pilot_rays]),
        "printed": lambda data: np.array([v["value"] for v in data["values"].values()]
                                         + [data["rays"], data["pilot_rays"]])}
