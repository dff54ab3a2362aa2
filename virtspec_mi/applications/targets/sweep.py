"""
A target certified at every θi of a sweep: ``vm.sweep(scene, target=...)``, ``virtspec sweep --target``
=======================================================================================================

:func:`target_sweep` resolves the angles of a sweep as the spectrophotometer's sweep does
(the scene's θi when none is given) and certifies the target at each, every angle at its
own δ (:func:`~.sequential.measure_targets`: one checkpoint for all the angles, or one
angle per Dask worker). The API's ``vm.sweep(target=...)`` and the command line's
``virtspec sweep --target`` both come here, so they give the same results, bit for bit.

References
----------
Spertus, Sridhar & Stark (2024), arXiv:2409.06680 (the certificate of each angle:
:mod:`virtspec_mi.budgets.betting`).
"""

from __future__ import annotations

from typing import Any

from virtspec_mi.applications.targets.measure import REFUSED_SETTINGS
from virtspec_mi.applications.targets.result import DerivedSweep
from virtspec_mi.applications.targets.sequential import measure_targets
from virtspec_mi.applications.targets.targets import Target
from virtspec_mi.runtime.reading import incidence_angles, scene_options
from virtspec_mi.runtime.scene import LoadedScene
from virtspec_mi.settings import Settings, resolve

__all__ = ["target_sweep"]


def target_sweep(scene: LoadedScene, target: Target, settings: dict[str, Any], theta_i: Any = None,
                 checkpoint: Any = None, workers: Any = None, progress: bool | None = None) -> DerivedSweep:
    """
    ``target`` certified at every angle of ``theta_i`` (as for ``vm.sweep``: a number, a
    sequence or ``"start:stop:step"``; ``None``: the scene's θi) with ``settings`` (those a
    target takes: :data:`~.measure.REFUSED_SETTINGS` are refused by each angle's
    measurement), its traces kept in ``checkpoint`` or traced on ``workers``.
    """

    resolved, = resolve("sweep", {k: v for k, v in settings.items() if k not in (*REFUSED_SETTINGS, "bound")},
                        scene_options(scene.bench, Settings))
    angles = tuple(float(t) for t in incidence_angles(resolved, theta_i, "a sweep"))
    return DerivedSweep(angles, measure_targets(scene, target, {**settings, "progress": progress}, angles, checkpoint,
                                                workers))
