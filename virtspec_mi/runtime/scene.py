"""
Scenes: loading, building and fingerprinting instrument scenes
==============================================================

- :func:`load_scene` accepts an XML path, a shipped scene's name
  (:mod:`virtspec_mi.scenes`; an XML file may include a shipped scene by its file
  name), a scene dict or a loaded ``mi.Scene`` and
  turns Mitsuba's loader errors into messages that name the problem; an XML scene's
  parameters (``$name`` with a ``<default name="name" value="…"/>``) are set by
  ``defines`` (name → value), as Mitsuba's ``mitsuba -D name=value`` and
  ``mi.load_file(path, name=value)`` do;
- :func:`find_bench` loads a scene and reads its bench (the emitter and specimen disks)
  (:func:`virtspec_mi.engine.bench.read_bench`);
- :func:`instrument_scene` builds the paper's instrument (r₁ = 8, r₂ = 12.5, D = 100, in
  mm) around any BSDF dict;
- :func:`scene_fingerprint` identifies a scene in result files and checkpoints;
  :func:`scene_source` names it for people (the scene file or shipped scene, the
  ``-D`` defines), in files and figure titles.

References
----------
Baranoski et al. (2001), Sect. 5.1 (the instrument's dimensions).
"""

from __future__ import annotations

import difflib
import hashlib
import os
import re
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from virtspec_mi.geometry.disks import (
    PAPER_DISTANCE,
    PAPER_EMITTER_RADIUS,
    PAPER_SPECIMEN_RADIUS,
    InstrumentGeometry,
)
from virtspec_mi.engine.bench import EMITTER_ID, SPECIMEN_ID, Bench, SceneError, read_bench
import virtspec_mi.base.interrupts as interrupts
from virtspec_mi.base.files import check_name_length
from virtspec_mi import scenes
from virtspec_mi.runtime import mitsuba
from virtspec_mi.settings import SETTING_NAMES

__all__ = [
    "LoadedScene",
    "loaded",
    "load_scene", "check_defines", "find_bench", "instrument_scene", "placeholder_sensor", "scene_fingerprint",
    "scene_source", "tabulated_bsdf",
]


def load_scene(scene: Any, defines: dict[str, Any] | None = None) -> Any:
    """
    A loaded ``mi.Scene`` from an XML path, a scene dict or an ``mi.Scene``; ``defines``
    (name → value) sets the XML file's ``$name`` parameters (only for an XML path).
    """

    mi = mitsuba()
    check_name_length("scene", scene)  # a 5,000-character name: refused, shortened, before the file system sees it
    scene = scenes.resolve(scene)
    defines = check_defines(defines, scene)
    if isinstance(scene, mi.Scene):
        return scene
    try:
        if isinstance(scene, (str, os.PathLike)):
            path = Path(scene)
            if path.is_dir():
                raise SceneError(f"scene {path} is a directory; give a Mitsuba XML scene file")
            if not path.is_file():
                raise SceneError(f"scene file not found: {path}{scenes.hint(path)}")
            _check_defined(path, defines)
            scenes.include_folder(mi.file_resolver())  # <include filename="diamond_conical.xml"/> finds it
            with interrupts.deferred():  # a Ctrl-C in a plugin's Python would come out as Mitsuba's RuntimeError
                return mi.load_file(str(path), **defines)
        if isinstance(scene, dict):
            _check_dict(scene)
            with interrupts.deferred():
                return mi.load_dict(scene)
    except SceneError:
        raise
    except Exception as error:  # Mitsuba raises RuntimeError/ValueError with its parser text
        raise SceneError(f"could not load scene {_describe(scene)}: {_clean(error)}{_suggestion(error)}") from error
    raise SceneError(f"scene must be an XML path, a dict or a mitsuba Scene (got {type(scene).__name__})")


def check_defines(defines: dict[str, Any] | None, scene: Any = None) -> dict[str, str]:
    """
    ``defines`` as XML parameter strings: names are identifiers, values numbers or
    strings; ``ValueError`` naming the problem, also when given for a scene that is not
    an XML path (a dict or a loaded scene has no ``$name`` to set).
    """

    if not defines:
        return {}
    if not isinstance(defines, dict):
        raise ValueError(f"defines must be a dict of name -> value (got {type(defines).__name__})")
    if scene is not None and not isinstance(scene, (str, os.PathLike)):
        raise ValueError("defines (-D name=value) set the $name parameters of an XML scene file; the scene given "
                         f"is a {type(scene).__name__}")
    checked = {}
    for name, value in defines.items():
        if not isinstance(name, str) or not name.isidentifier() or name in _LOAD_FILE_ARGUMENTS:
            raise ValueError(f"a scene parameter name (-D NAME=value) must be an identifier other than "
                             f"{', '.join(_LOAD_FILE_ARGUMENTS)} (got {name!r})")
        if isinstance(value, bool) or not isinstance(value, (str, int, float)):
            raise ValueError(f"scene parameter {name!r} must be a number or a string (got {value!r})")
        checked[name] = value if isinstance(value, str) else repr(value)
    return checked


def _check_defined(path: Path, defines: dict[str, str]) -> None:
    """Each name of ``defines`` must be a ``$name`` the XML file uses (``ValueError`` with its names)."""

    if not defines:
        return
    used = sorted(set(re.findall(r"\$([A-Za-z_]\w*)", re.sub(r"<!--.*?-->", "", path.read_text(errors="replace"),
                                                             flags=re.S))))
    for name in defines:
        if name not in used:
            close = difflib.get_close_matches(name, used, n=1, cutoff=0.6)
            hint = f"; did you mean {close[0]!r}?" if close else ""
            raise SceneError(f"scene parameter {name!r} (-D) is not used by {path} (its parameters: "
                             f"{', '.join(used) or 'none'}){hint}")


_LOAD_FILE_ARGUMENTS = ("path", "update_scene", "parallel")  # mi.load_file's own keywords


def _check_dict(scene: dict, path: str = "") -> None:
    """Refuse what Mitsuba 3.9.1's ``load_dict`` crashes on (a ``None`` value: a segmentation fault)."""

    for key, value in scene.items():
        where = f"{path}.{key}" if path else str(key)
        if value is None:
            raise SceneError(f"could not load scene (dict): [{where}] has no value (None)")
        if isinstance(value, dict):
            _check_dict(value, where)


_NO_BSDF = (f"the specimen disk (shape id '{SPECIMEN_ID}') has no BSDF: Mitsuba would give it a default diffuse "
            "BSDF of reflectance 0.5 and measure that; give the specimen's BSDF ")


def _check_specimen_xml(path: Path) -> None:
    """
    Refuse an XML scene whose ``specimen`` shape holds no ``<bsdf>`` (nor a ``<ref>`` to
    one): Mitsuba gives such a shape a default diffuse BSDF. A file Python's XML parser
    cannot read, or whose specimen is not written out in it, Mitsuba has loaded already.
    """

    from xml.etree import ElementTree

    try:
        root = ElementTree.parse(path).getroot()
    except (ElementTree.ParseError, OSError):
        return
    for shape in root.iter("shape"):
        if shape.get("id") == SPECIMEN_ID and not any(child.tag in ("bsdf", "ref") for child in shape):
            raise SceneError(f"{_NO_BSDF}inside it (<bsdf type=\"...\">) in {path}")


def _check_specimen_dict(scene: dict) -> None:
    """
    Refuse a scene dict whose ``specimen`` entry holds no BSDF (a dict of a BSDF plugin,
    a ``ref``, or a loaded ``mi.BSDF``): Mitsuba gives such a shape a default diffuse BSDF.
    """

    from virtspec_mi.plugins import specimen_rows
    from virtspec_mi.runtime import PLUGINS

    mi = mitsuba()
    project = {**{name: "bsdf" for name in specimen_rows()}, **{name: row[0] for name, row in PLUGINS.items()}}
    specimen = scene.get(SPECIMEN_ID)
    if not isinstance(specimen, dict):
        return  # not an instrument scene: read_bench names what is missing

    def is_bsdf(value: Any) -> bool:  # or may be one: a plugin registered from Python is of no known type
        if isinstance(value, mi.BSDF):
            return True
        if not isinstance(value, dict) or not isinstance(value.get("type"), str):
            return False
        kind = value["type"]
        if kind in project:
            return project[kind] == "bsdf"
        return kind == "ref" or mi.PluginManager.instance().plugin_type(kind) in (mi.ObjectType.BSDF,
                                                                                mi.ObjectType.Unknown)

    if not any(is_bsdf(value) for key, value in specimen.items() if key != "type"):
        raise SceneError(f"{_NO_BSDF}in its dict entry (e.g. 'bsdf': {{'type': 'diffuse'}})")


def find_bench(scene: Any, defines: dict[str, Any] | None = None) -> Bench:
    """
    Load ``scene`` (XML path, dict or ``mi.Scene``; ``defines`` for an XML file) and read
    its bench (the disks); a specimen disk given no BSDF is refused (Mitsuba would give it
    its default diffuse BSDF).
    """

    bench = read_bench(load_scene(scene, defines))
    scene = scenes.resolve(scene)
    if isinstance(scene, (str, os.PathLike)):
        _check_specimen_xml(Path(scene))
    elif isinstance(scene, dict):
        _check_specimen_dict(scene)
    return bench


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


def scene_fingerprint(scene: Any, bench: Bench, defines: dict[str, Any] | None = None) -> str:
    """
    A short fingerprint of a scene for result files and checkpoints: SHA-256 over the
    XML file's bytes (or the dict's ``repr``), the XML parameters set (``defines``, when
    any), the specimen BSDF's description, the specimen frame and the geometry.
    """

    digest = hashlib.sha256()
    scene = scenes.resolve(scene)
    if isinstance(scene, (str, os.PathLike)):
        digest.update(Path(scene).read_bytes())
        if defines:
            digest.update(repr(sorted(check_defines(defines).items())).encode())
    elif isinstance(scene, dict):
        try:
            text = repr(sorted(scene.items(), key=lambda item: str(item[0])))
        except RuntimeError:  # a loaded Python plugin inside (Mitsuba's trampoline raises for its missing to_string)
            text = _dict_text(scene)
        digest.update(text.encode())
    digest.update(_described(bench.bsdf).encode())
    digest.update(np.asarray(bench.to_world, dtype=np.float64).round(9).tobytes())
    digest.update(repr(asdict(bench.geometry)).encode())
    return f"sha256:{digest.hexdigest()[:16]}"


def _dict_text(value: Any) -> str:
    """A scene dict as text, each loaded Mitsuba object in it :func:`_described` (for a dict ``repr`` cannot write)."""

    if isinstance(value, dict):
        return "{" + ", ".join(f"{key!r}: {_dict_text(item)}" for key, item in sorted(value.items(),
                                                                                    key=lambda i: str(i[0]))) + "}"
    try:
        return repr(value)
    except RuntimeError:
        return _described(value)


def _described(bsdf: Any) -> str:
    """
    ``str(bsdf)``; for a Python plugin without ``to_string`` (Mitsuba's trampoline raises),
    its class and its ``mi.traverse`` parameters.
    """

    try:
        return str(bsdf)
    except RuntimeError:
        params = mitsuba().traverse(bsdf)
        return f"{type(bsdf).__module__}.{type(bsdf).__qualname__}" + repr([(k, str(params[k])) for k in params.keys()])


def scene_source(scene: Any, bench: Bench, defines: dict[str, Any] | None = None) -> dict[str, Any]:
    """
    What a result records of the scene it measured, for people: ``{"scene": name,
    "defines": {name: value}}``. The name is a shipped scene's name (``"soybean_abmb"``),
    an XML file's name (``"my_leaf.xml"``), else what was given and the specimen's BSDF
    by the name a scene gives its plugin (``"scene dict, specimen prospect_d"``; Mitsuba's own
    BSDFs: their class, ``RoughConductor``); ``defines`` are the XML parameters set
    (``-D``), as strings.
    """

    scene = scenes.resolve(scene)
    if isinstance(scene, (str, os.PathLike)):
        path = Path(scene).resolve()
        name = path.stem if path.parent == scenes.FOLDER else path.name
    else:
        bsdf = type(bench.bsdf).__name__  # a Python plugin's class; Mitsuba's own: the class behind mi.BSDF
        bsdf = bench.bsdf.class_name() if bsdf == "BSDF" and hasattr(bench.bsdf, "class_name") else bsdf
        bsdf = getattr(bench.bsdf, "PLUGIN", "") or bsdf  # a specimen's registered name, as a scene writes it
        name = f"{'scene dict' if isinstance(scene, dict) else 'mi.Scene'}, specimen {bsdf}"
    return {"scene": name, "defines": check_defines(defines)}


def _describe(scene: Any) -> str:
    return f"'{scene}'" if isinstance(scene, (str, os.PathLike)) else f"({type(scene).__name__})"


def _clean(error: Exception) -> str:
    text = str(error).strip()
    return text.splitlines()[-1] if text else type(error).__name__


def _suggestion(error: Exception) -> str:
    """
    "; did you mean 'theta_i'?" when Mitsuba's message quotes a parameter name that is a
    near miss of a setting or of an instrument's option (Mitsuba reports an unused ``<float name="thetai" …>`` as
    ``float "thetai": 45``).
    """

    names = re.findall(r'"(\w+)"', str(error))
    from virtspec_mi.instruments import INSTRUMENTS

    known = {*SETTING_NAMES, *(n for i in INSTRUMENTS.values() if i.options is not None for n in i.options.names())}
    close = {name: difflib.get_close_matches(name, sorted(known), n=1, cutoff=0.75) for name in names}
    hints = [f"'{name}' is not a setting: did you mean '{match[0]}'?" for name, match in close.items()
             if match and match[0] != name]
    return f" ({'; '.join(hints)})" if hints else ""


def tabulated_bsdf(source: Any) -> dict:
    """
    The dict-scene entry of a ``tabulated`` BSDF holding ``source`` — a goniophotometer
    dataset (``xarray.Dataset``), an object with ``to_dataset()``, a NetCDF path or a
    :class:`virtspec_mi.plugins.bsdfs.bsdf_table.BSDFTable`. Mitsuba properties hold Dr.Jit arrays but
    no Python objects, so the table travels as flat ``Float64`` arrays (``fraction`` in C
    order over wavelength, theta_i, theta_o, phi_o);
    ``vm.instrument_scene(vm.tabulated_bsdf(dataset))`` measures it.
    """

    from virtspec_mi.plugins.bsdfs.bsdf_table import BSDFTable, read_table

    mi = mitsuba()
    table = source if isinstance(source, BSDFTable) else read_table(source)
    entry: dict[str, Any] = {"type": "tabulated"}
    for name, value in table.properties().items():
        if isinstance(value, np.ndarray):
            entry[name] = mi.Float64(np.ascontiguousarray(value, dtype=np.float64).ravel())
        else:
            entry[name] = value
    return entry


@dataclass(frozen=True)
class LoadedScene:
    """
    A scene resolved once, where it enters the API: what was given (a shipped scene's name
    resolved to its path, an XML path, a scene dict or a loaded ``mi.Scene``), the XML
    parameters set (``defines``), its bench (:func:`find_bench`), its fingerprint
    (:func:`scene_fingerprint`: checkpoints and results) and its source
    (:func:`scene_source`: what a result records for people). Made by :func:`loaded`;
    a Dask worker receives ``given`` and ``defines`` and loads its own bench.
    """

    given: Any
    """The scene as given, a shipped name resolved to its path."""
    defines: dict[str, Any] | None
    """The values of an XML scene's ``$name`` parameters (``mitsuba -D``), or ``None``."""
    bench: Bench
    """The emitter and specimen disks of the loaded scene."""
    fingerprint: str
    """:func:`scene_fingerprint` of the scene."""
    source: dict[str, Any]
    """:func:`scene_source` of the scene."""


def loaded(scene: Any, defines: dict[str, Any] | None = None) -> LoadedScene:
    """
    ``scene`` (XML path, shipped name, dict or ``mi.Scene``; ``defines`` for an XML file)
    loaded and described once (:class:`LoadedScene`); a :class:`LoadedScene` is returned
    as it is (``defines`` must then be left out).
    """

    if isinstance(scene, LoadedScene):
        if defines:
            raise ValueError("defines: give them when the scene is loaded (vm.scene.loaded(scene, defines)), "
                             "not with a loaded scene")
        return scene
    bench = find_bench(scene, defines)
    return LoadedScene(scenes.resolve(scene), defines, bench, scene_fingerprint(scene, bench, defines),
                       scene_source(scene, bench, defines))
