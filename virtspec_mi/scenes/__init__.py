"""
Shipped scenes
==============

Ready instruments as Mitsuba XML scenes, shipped with the package (this folder): the
paper's diamond (conical and collimated), the soybean and corn leaves, the MCML slab and
two integrating spheres. Every API entry and ``virtspec`` subcommand that takes a scene
also takes a shipped scene's name (``virtspec measure soybean_abmb``,
``vm.measure("soybean_abmb")``); :func:`path` gives its file and :func:`catalogue` one
line of description per scene (``virtspec scenes``), :func:`copy` a copy to edit
(``virtspec scenes --copy NAME``).

A name is resolved once, where it enters (:func:`resolve`): an existing file of that
name wins, else the shipped scene's path, which Dask workers then load whatever their
working directory. A shipped scene is also found by its file name from a scene's
``<include filename="NAME.xml"/>`` (:func:`include_folder`), and a misspelt name or a
``scenes/NAME.xml`` path outside the checkout gets the name to use (:func:`hint`).

References
----------
Baranoski et al. (2001), Sect. 3.2 and Sect. 5.1 (the instrument: r1 = 8 mm,
r2 = 12.5 mm, D = 100 mm).
"""

from __future__ import annotations

import difflib
import os
import re
from pathlib import Path
from typing import Any

__all__ = [
    "FOLDER", "names", "path", "describe", "catalogue", "listing", "resolve", "hint", "copy", "include_folder",
    "answer",
]

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
        close = difflib.get_close_matches(str(name), names(), n=1, cutoff=0.6)
        guess = f"; did you mean {close[0]!r}?" if close else ""
        raise ValueError(f"no shipped scene {name!r}; the shipped scenes are {', '.join(names())}{guess}")
    return FOLDER / f"{name}.xml"


def describe(name: str) -> str:
    """The scene's one-line summary: its file's first XML comment."""

    match = re.search(r"<!--(.*?)-->", path(name).read_text(encoding="utf-8"), re.S)
    return " ".join(match.group(1).split()) if match else ""


def catalogue() -> str:
    """One line per shipped scene: its name and what it holds."""

    width = max(len(n) for n in names())
    return "\n".join(f"{name:<{width}}  {describe(name)}" for name in names())


def listing() -> str:
    """One line per shipped scene: its name, its file and what it holds (``virtspec scenes``)."""

    width = max(len(n) for n in names())
    return "\n".join(f"{name:<{width}}  {describe(name)}\n{'':<{width}}  {path(name)}"
                     for name in names())


def resolve(scene: Any) -> Any:
    """
    ``scene`` as given, except a string (or path) that names no existing file but a
    shipped scene (``"soybean_abmb"``): that scene's path. A folder of the scene's name
    in the working directory does not hide the shipped scene.
    """

    if isinstance(scene, (str, os.PathLike)) and not Path(scene).is_file() and os.fspath(scene) in names():
        return path(os.fspath(scene))
    return scene


def hint(scene: Any) -> str:
    """
    What to say after "scene file not found: SCENE": the shipped scene's name when
    ``scene`` is a path to a shipped scene's file that is not there (``scenes/X.xml``
    outside the checkout), else the nearest shipped name ("did you mean …?"), else how to
    list them; ``""`` for what is not a string or path.
    """

    if not isinstance(scene, (str, os.PathLike)):
        return ""
    given = Path(scene)
    stem = given.stem if given.suffix.lower() == ".xml" else given.name
    if stem in names():
        return f"; the shipped scene {stem!r} is given by its name alone (e.g. virtspec measure {stem})"
    close = difflib.get_close_matches(stem, names(), n=1, cutoff=0.6)
    if close:
        return f"; did you mean the shipped scene {close[0]!r}?"
    return "; a shipped scene is given by its name (virtspec scenes lists them)"


def copy(name: str, destination: str | os.PathLike | None = None) -> Path:
    """
    Copy the shipped scene ``name`` to ``destination`` (a file, or a folder that gets
    ``NAME.xml``; default ``NAME.xml`` in the working directory) as a template to edit,
    and return the copy's path. An existing file is never replaced (``FileExistsError``
    naming it); a missing folder is an ``OSError`` naming it.
    """

    source = path(name)
    target = Path(f"{name}.xml") if destination is None else Path(destination)
    if target.is_dir():
        target = target / source.name
    if not target.parent.is_dir():
        raise FileNotFoundError(f"cannot copy scene {name!r} to {target}: folder {target.parent} does not exist")
    try:
        with open(target, "x", encoding="utf-8") as copied:  # "x": never replaces a file
            copied.write(source.read_text(encoding="utf-8"))
    except FileExistsError:
        raise FileExistsError(f"cannot copy scene {name!r}: {target} exists (it is kept; give another "
                              "destination)") from None
    return target


def include_folder(resolver: Any) -> None:
    """
    Add the shipped scenes' folder to Mitsuba's file resolver ``resolver``
    (``mi.file_resolver()``), last, once: a scene file's ``<include filename="NAME.xml"/>``
    then finds a shipped scene when no file of that name is beside the scene.
    """

    folder = str(FOLDER)
    if folder not in (str(resolver[i]) for i in range(len(resolver))):
        resolver.append(folder)


def answer(path_of: str | None = None, copy_of: str | None = None, destination: str | None = None) -> str:
    """
    What ``virtspec scenes`` prints: the listing (:func:`listing`); with ``path_of`` the
    scene's file; with ``copy_of`` the path of its copy at ``destination``
    (:func:`copy`). ``ValueError`` for a destination without a scene to copy.
    """

    if destination is not None and copy_of is None:
        raise ValueError(f"DEST ({destination}) is where --copy NAME puts its copy: give --copy NAME DEST")
    if path_of is not None:
        return str(path(path_of))
    if copy_of is not None:
        return str(copy(copy_of, destination))
    return listing()
