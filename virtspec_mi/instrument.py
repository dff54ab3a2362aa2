"""
Scene ↔ instrument
==================

A virtspec-mi scene is an ordinary Mitsuba scene holding two ``disk`` shapes with
ids ``emitter`` and ``specimen`` (the specimen carries the BSDF under test), and
optionally a ``spectrophotometer`` integrator with the measurement settings and a
placeholder sensor (``mi.render`` needs one; the instrument ignores it).

- :func:`load_scene` accepts an XML path, a scene dict or a loaded ``mi.Scene`` and
  turns Mitsuba's loader errors into messages that name the problem.
- :func:`find_instrument` reads the geometry from the two disks: r₁ and r₂ are their
  radii, D the distance between their centres; the specimen's ``to_world`` defines
  the measurement frame (normal = upper hemisphere, its local x axis = φi = 0). The
  emitter's own position only sets D: each reading rotates it to (θi, φi) about the
  specimen centre.
- :func:`instrument_scene` builds the paper's instrument (r₁ = 8, r₂ = 12.5,
  D = 100, in mm) around any BSDF dict.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from virtspec_mi.geometry import (
    PAPER_DISTANCE,
    PAPER_EMITTER_RADIUS,
    PAPER_SPECIMEN_RADIUS,
    InstrumentGeometry,
)
from virtspec_mi.runtime import mitsuba

__all__ = [
    "EMITTER_ID",
    "SPECIMEN_ID",
    "SceneError",
    "Instrument",
    "load_scene",
    "find_instrument",
    "instrument_scene",
    "placeholder_sensor",
]

EMITTER_ID: str = "emitter"
SPECIMEN_ID: str = "specimen"


class SceneError(ValueError):
    """The scene cannot be loaded or does not describe an instrument."""


@dataclass
class Instrument:
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


def load_scene(scene: Any) -> Any:
    """A loaded ``mi.Scene`` from an XML path, a scene dict or an ``mi.Scene``."""

    mi = mitsuba()
    if isinstance(scene, mi.Scene):
        return scene
    try:
        if isinstance(scene, (str, os.PathLike)):
            path = Path(scene)
            if not path.is_file():
                raise SceneError(f"scene file not found: {path}")
            return mi.load_file(str(path))
        if isinstance(scene, dict):
            return mi.load_dict(scene)
    except SceneError:
        raise
    except Exception as error:  # Mitsuba raises RuntimeError/ValueError with its parser text
        raise SceneError(f"could not load scene {_describe(scene)}: {_clean(error)}") from error
    raise SceneError(f"scene must be an XML path, a dict or a mitsuba Scene (got {type(scene).__name__})")


def find_instrument(scene: Any) -> Instrument:
    """Locate the emitter and specimen disks of ``scene`` and read the geometry."""

    scene = load_scene(scene)
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
    params = mitsuba().traverse(scene)
    emitter_matrix = _disk_matrix(params, shapes[EMITTER_ID], EMITTER_ID)
    specimen_matrix = _disk_matrix(params, shapes[SPECIMEN_ID], SPECIMEN_ID)
    r1, _ = _disk_radius_and_frame(emitter_matrix, EMITTER_ID)
    r2, frame = _disk_radius_and_frame(specimen_matrix, SPECIMEN_ID)
    distance = float(np.linalg.norm(emitter_matrix[:3, 3] - specimen_matrix[:3, 3]))
    if not distance > 0:
        raise SceneError("the emitter and specimen disks share their centre: distance D must be > 0")
    bsdf = shapes[SPECIMEN_ID].bsdf()
    return Instrument(scene, shapes[SPECIMEN_ID], bsdf, frame, InstrumentGeometry(r1, r2, distance))


def instrument_scene(
    bsdf: dict,
    *,
    emitter_radius: float = PAPER_EMITTER_RADIUS,
    specimen_radius: float = PAPER_SPECIMEN_RADIUS,
    distance: float = PAPER_DISTANCE,
    integrator: dict | None = None,
) -> dict:
    """
    A scene dict of the paper's instrument around ``bsdf`` (a Mitsuba BSDF dict).

    The specimen disk lies in z = 0 with normal +z; the emitter disk faces it from
    (0, 0, D). ``integrator`` (a dict of ``spectrophotometer`` parameters) is added
    when given.
    """

    geometry = InstrumentGeometry(emitter_radius, specimen_radius, distance)
    mi = mitsuba()
    scene: dict[str, Any] = {
        "type": "scene",
        EMITTER_ID: {
            "type": "disk",
            "to_world": mi.ScalarTransform4f().translate([0.0, 0.0, geometry.distance])
            @ mi.ScalarTransform4f().scale(geometry.emitter_radius)
            @ mi.ScalarTransform4f().rotate([1.0, 0.0, 0.0], 180.0),
        },
        SPECIMEN_ID: {
            "type": "disk",
            "to_world": mi.ScalarTransform4f().scale(geometry.specimen_radius),
            "bsdf": bsdf,
        },
        "readout": placeholder_sensor(),
    }
    if integrator is not None:
        scene["integrator"] = {"type": "spectrophotometer", **integrator}
    return scene


def placeholder_sensor() -> dict:
    """A 1×1 sensor: ``mi.render`` insists on one; the spectrophotometer ignores it."""

    return {"type": "perspective", "film": {"type": "hdrfilm", "width": 1, "height": 1}}


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


def _describe(scene: Any) -> str:
    return f"'{scene}'" if isinstance(scene, (str, os.PathLike)) else f"({type(scene).__name__})"


def _clean(error: Exception) -> str:
    text = str(error).strip()
    return text.splitlines()[-1] if text else type(error).__name__
