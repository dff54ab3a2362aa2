"""
Shipped scenes
==============

Ready instruments as Mitsuba XML scenes, shipped with the package (this folder): the
paper's diamond (conical and collimated), the soybean and corn leaves, the MCML slab and
two integrating spheres. Every API entry and ``virtspec`` subcommand that takes a scene
also takes a shipped scene's name (``virtspec measure soybean_abmb``,
``vm.measure("soybean_abmb")``); :func:`path` gives its file and :func:`catalogue` one
line of description per scene (``virtspec scenes``).

References
----------
Baranoski et al. (2001), Sect. 3.2 and Sect. 5.1 (the instrument: r1 = 8 mm,
r2 = 12.5 mm, D = 100 mm).
"""

from __future__ import annotations

import os
import re
from pathlib import Path
from typing import Any

__all__ = ["FOLDER", "names", "path", "describe", "catalogue", "resolve"]

FOLDER: Path = Path(__file__).resolve().parent
"""Where the shipped scenes are."""


def names() -> list[str]:
    """The shipped scenes' names (file names without ``.xml``), sorted."""

    return sorted(p.stem for p in FOLDER.glob("*.xml"))


def path(name: str) -> Path:
    """
    The file of the shipped scene ``name`` (``ValueError`` naming the shipped scenes when
    there is none of that name).
    """

    if not isinstance(name, str) or name not in names():
        raise ValueError(f"no shipped scene {name!r}; the shipped scenes are {', '.join(names())}")
    return FOLDER / f"{name}.xml"


def describe(name: str) -> str:
    """The scene's one-line summary: its file's first XML comment."""

    match = re.search(r"<!--(.*?)-->", path(name).read_text(encoding="utf-8"), re.S)
    return " ".join(match.group(1).split()) if match else ""


def catalogue() -> str:
    """One line per shipped scene: its name and what it holds."""

    width = max(len(n) for n in names())
    return "\n".join(f"{name:<{width}}  {describe(name)}" for name in names())


def resolve(scene: Any) -> Any:
    """
    ``scene`` as given, except a string that names no existing file but a shipped scene
    (``"soybean_abmb"``): that scene's path.
    """

    if isinstance(scene, (str, os.PathLike)) and not Path(scene).exists() and str(scene) in names():
        return path(str(scene))
    return scene
