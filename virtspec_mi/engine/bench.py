"""
The bench inside a loaded scene: its emitter and specimen disks
===============================================================

A virtspec-mi scene is an ordinary Mitsuba scene holding two ``disk`` shapes with ids
``emitter`` and ``specimen`` (the specimen carries the BSDF under test), and optionally
a ``spectrophotometer`` integrator with the measurement settings.
:func:`read_bench` reads the geometry from the two disks of a *loaded* scene: r₁
and r₂ are their radii, D the distance between their centres; the specimen's
``to_world`` defines the measurement frame (normal = upper hemisphere, its local x
axis = φi = 0). The emitter's own position only sets D: each reading rotates it to
(θi, φi) about the specimen centre. Loading scenes from XML or dicts is
:mod:`virtspec_mi.runtime.scene`'s job.

References
----------
Baranoski et al. (2001), Fig. 1 and Sect. 3.2.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from virtspec_mi.geometry.disks import InstrumentGeometry

__all__ = ["EMITTER_ID", "SPECIMEN_ID", "SceneError", "Bench", "read_bench"]

EMITTER_ID: str = "emitter"
SPECIMEN_ID: str = "specimen"


class SceneError(ValueError):
    """The scene cannot be loaded or does not describe an instrument."""


@dataclass
class Bench:
    """The parts of a loaded scene that a measurement uses."""

    scene: Any
    specimen: Any
    bsdf: Any
    to_world: np.ndarray
    """4×4 matrix from the specimen's measurement frame (unit radius removed) to world."""
    geometry: InstrumentGeometry

    @property
    def integrator(self) -> Any:
        """The scene's ``spectrophotometer`` integrator, or ``None``."""

        integrator = self.scene.integrator()
        return integrator if hasattr(integrator, "settings") else None


def read_bench(scene: Any) -> Bench:
    """Locate the emitter and specimen disks of a loaded ``mi.Scene`` and read the geometry."""

    import mitsuba as mi

    shapes = {shape.id(): shape for shape in scene.shapes()}
    missing = [name for name in (EMITTER_ID, SPECIMEN_ID) if name not in shapes]
    if missing:
        raise SceneError(
            f"the scene has no shape with id {' or '.join(repr(m) for m in missing)}; an instrument "
            f"needs a disk with id '{EMITTER_ID}' and a disk with id '{SPECIMEN_ID}' "
            f"(found ids: {sorted(shapes) or 'none'})"
        )
    others = sorted(set(shapes) - {EMITTER_ID, SPECIMEN_ID})
    if others:
        raise SceneError(
            f"the instrument traces only the '{EMITTER_ID}' and '{SPECIMEN_ID}' disks; remove the "
            f"other shapes {others} (they would be silently ignored)"
        )
    params = mi.traverse(scene)
    emitter_matrix = _disk_matrix(params, shapes[EMITTER_ID], EMITTER_ID)
    specimen_matrix = _disk_matrix(params, shapes[SPECIMEN_ID], SPECIMEN_ID)
    r1, _ = _disk_radius_and_frame(emitter_matrix, EMITTER_ID)
    r2, frame = _disk_radius_and_frame(specimen_matrix, SPECIMEN_ID)
    distance = float(np.linalg.norm(emitter_matrix[:3, 3] - specimen_matrix[:3, 3]))
    if not distance > 0:
        raise SceneError("the emitter and specimen disks share their centre: distance D must be > 0")
    bsdf = shapes[SPECIMEN_ID].bsdf()
    return Bench(scene, shapes[SPECIMEN_ID], bsdf, frame, InstrumentGeometry(r1, r2, distance))


def _disk_matrix(params: Any, shape: Any, name: str) -> np.ndarray:
    if shape.class_name() != "Disk" and "Disk" not in str(shape):
        raise SceneError(f"shape '{name}' must be a Mitsuba 'disk' (got {shape.class_name()})")
    key = f"{name}.to_world"
    if key not in params.keys():
        raise SceneError(f"shape '{name}' must be a Mitsuba 'disk' with a to_world transform")
    matrix = np.array(params[key].matrix, dtype=np.float64).reshape(4, 4)
    return matrix


def _disk_radius_and_frame(matrix: np.ndarray, name: str) -> tuple[float, np.ndarray]:
    """Radius of a disk's to_world and its orthonormal frame (x, y, normal, centre)."""

    a, b = matrix[:3, 0], matrix[:3, 1]
    ra, rb = float(np.linalg.norm(a)), float(np.linalg.norm(b))
    if not (ra > 0 and rb > 0):
        raise SceneError(f"disk '{name}' has zero radius: its to_world must scale it by a radius > 0")
    if not math.isclose(ra, rb, rel_tol=1e-5) or abs(float(a @ b)) > 1e-5 * ra * rb:
        raise SceneError(
            f"disk '{name}' is not circular (to_world scales x by {ra:g} and y by {rb:g}); "
            "use a uniform scale"
        )
    x = a / ra
    normal = np.cross(a, b)
    normal /= np.linalg.norm(normal)
    frame = np.eye(4)
    frame[:3, 0], frame[:3, 1], frame[:3, 2], frame[:3, 3] = x, np.cross(normal, x), normal, matrix[:3, 3]
    return ra, frame
