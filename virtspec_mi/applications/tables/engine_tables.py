"""
Each engine's tables certified with its own model, in the engine's own files
============================================================================

A renderer's energy-compensation table is the albedo of *its* model on *its* grid; a
certified table can replace it only when both match (the models:
:mod:`virtspec_mi.exchange.engine_models`). :func:`engine_tables` certifies every
channel of an engine's table:

``cycles`` — Blender Cycles, ``intern/cycles/app/cycles_precompute.cpp``
    GGX with the height-correlated Smith G₂ (Heitz 2014, eq. 99), F = 1: ``table_ggx_E``
    (32 × 32) and ``table_ggx_Eavg`` (32), a C header (:mod:`virtspec_mi.exchange.header`).
``filament`` — Google Filament, ``libs/ibl/src/CubemapIBL.cpp`` (``DFV_Multiscatter``)
    GGX, height-correlated Smith visibility; the build runs ``cmgen --ibl-dfg-multiscatter``,
    so the texture holds DFG.x = ∫ F_c f cos and DFG.y = ∫ f cos (F_c = (1 − v·h)⁵; the
    shader's E = mix(DFG.x, DFG.y, f₀)), 128 × 128, as half floats in ``dfg.inc``
    (``tools/cmgen/src/cmgen.cpp``, ``iblLutDfg``: ``0x%04x`` per channel, rows in "GL
    order", i.e. the image's last row first). Filament's build adds a third, cloth
    channel (``--ibl-dfg-cloth``), which is another model (Charlie sheen) and is not
    certified here: :func:`write_filament_inc` writes the two GGX channels, or three
    with the cloth channel copied, uncertified, from a given array.
``unreal`` — Unreal Engine 4, ``SystemTextures.cpp`` (``PreintegratedGF``)
    GGX with ``Vis_SmithJointApprox`` (the ``unreal`` shadowing of the plugin):
    A = ∫ (1 − F_c) f cos and B = ∫ F_c f cos, 128 μ × 32 roughness, G16R16 unorm
    (round(65535·clamp(v)), A then B per texel, roughness rows ascending).
    :func:`write_unreal` writes that raw texture (``.raw``) or a 16-bit RGB PNG (R = A,
    G = B, B = 0; the provenance in a ``tEXt`` chunk).

Filament's and Unreal's two channels are the two halves of the split sum, counted on the
same rays (the plugin's ``fresnel="split"``): one table certifies E_R = ∫ F_c f cos,
E_T = ∫ (1 − F_c) f cos and E together (:class:`EngineTables`), every cell of every
channel at once with probability ≥ 1 − δ.

References
----------
Heitz, E. (2014). Understanding the masking-shadowing function in microfacet-based
BRDFs. JCGT 3(2): eq. (99).
Karis, B. (2013). Real shading in Unreal Engine 4. SIGGRAPH course *Physically Based
Shading in Theory and Practice* (the split sum, the (μ, roughness) texture).
Kulla, C., Conty, A. (2017). Revisiting physically based shading at Imageworks.
SIGGRAPH course (E, E_avg).
"""

from __future__ import annotations

import json
import os
import struct
import zlib
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from virtspec_mi.base.files import atomic_write
from virtspec_mi.base.surface import spoken
from virtspec_mi.exchange.common import check_companions
from virtspec_mi.exchange.engine_models import ENGINE_CHANNELS

_ENGINE_FILES = {"cycles": "Cycles' C header (.h)", "filament": "Filament's dfg.inc (half floats)",
                 "unreal": "Unreal's G16R16 texture (.raw) or a 16-bit PNG (.png)"}


__all__ = ["EngineTables", "engine_tables", "check_engine_sidecar", "held",
           "write_filament_inc", "read_filament_inc", "write_unreal", "read_unreal", "read_engine_file",
           "engine_layout"]

# ----------------------------------------------------------------------------- tables

@dataclass(frozen=True, eq=False)
class EngineTables:
    """
    An engine's table: one :class:`~virtspec_mi.applications.tables.table.AlbedoTable` of the
    engine's model on its grid whose certified quantities hold the engine's channels
    (:data:`~virtspec_mi.exchange.engine_models.ENGINE_CHANNELS`): every cell of every
    channel within its tolerance at once with probability ≥ 1 − δ.
    """

    engine: str
    table: Any
    channels: dict[str, str]

    @classmethod
    def from_table(cls, table: Any) -> "EngineTables":
        """
        An :class:`~virtspec_mi.applications.tables.table.AlbedoTable` read back (``.nc``) as the
        engine's table it was made as (``ValueError`` when it is not one: another grid,
        model or Fresnel mode).
        """

        fresnel, channels = ENGINE_CHANNELS.get(getattr(table, "engine", ""), (None, {}))
        if fresnel is None or table.model != "conductor" or table.bsdf.get("fresnel") != fresnel \
                or any(q not in table.quantities for q in channels.values()):
            raise ValueError(f"the table (engine {getattr(table, 'engine', None)!r}, fresnel "
                             f"{getattr(table, 'bsdf', {}).get('fresnel')!r}) is not an engine table made by "
                             "engine_tables (cycles: fresnel 'one'; filament, unreal: 'split' with parts)")
        return cls(table.engine, table, dict(channels))

    @property
    def delta(self) -> float:
        return self.table.delta

    @property
    def epsilon(self) -> float:
        return self.table.epsilon

    @property
    def rays(self) -> int:
        return self.table.rays

    @property
    def seconds(self) -> float:
        return float(self.table.provenance.get("seconds_wall", 0.0))

    def values(self, channel: str, average: bool = False) -> np.ndarray:
        """A channel's certified values in the engine's memory order (``average``: its E_avg)."""

        if channel not in self.channels:
            raise ValueError(f"channel must be one of {', '.join(self.channels)} (got {channel!r})")
        values = self.table.quantity(self.channels[channel], average)
        return values if average else self.table.layout(values)

    def tolerance(self, channel: str, average: bool = False) -> np.ndarray:
        """A channel's certified tolerance ε′ per cell (the table's: every quantity of a cell shares it)."""

        if channel not in self.channels:
            raise ValueError(f"channel must be one of {', '.join(self.channels)} (got {channel!r})")
        tolerance = self.table.certified_epsilon(average)
        return tolerance if average else self.table.layout(tolerance)

    def statement(self) -> str:
        """The joint certificate in one sentence."""

        return f"{self.engine} ({held(self.channels)}): {self.table.statement()}"

    def description(self) -> dict[str, Any]:
        """Provenance and certificate (the sidecar of a drop-in file)."""

        return {"engine": self.engine, "channels": self.channels, "certificate": self.statement(),
                "file": _ENGINE_FILES[self.engine], "table": self.table.description()}

    def write(self, path: str | os.PathLike, cloth: np.ndarray | None = None, overwrite: bool = False) -> Path:
        """
        The drop-in file by the engine: ``cycles`` ``.h``/``.hpp``; ``filament`` ``.inc``
        (``cloth``: a 128 × 128 third channel to carry along, uncertified); ``unreal``
        ``.raw`` or ``.png``. A ``PATH.json`` sidecar holds the provenance and certificate
        (the header, the ``.inc`` comments and the PNG's text chunk hold them too); it
        replaces a ``PATH.json`` only when that is such a sidecar, or with ``overwrite``
        (else ``ValueError``, before anything is written). ``.nc``: the certified table
        itself, every count (:meth:`from_table` reads it back).
        """

        path = Path(path)
        if path.suffix.lower() != ".nc":
            check_engine_sidecar(path, overwrite)
        suffix = path.suffix.lower()
        allowed = {"cycles": (".h", ".hpp"), "filament": (".inc",), "unreal": (".raw", ".png")}[self.engine]
        if suffix == ".nc":  # the certified table itself (read it back with EngineTables.from_table)
            return self.table.write(path)
        if suffix not in allowed:
            raise ValueError(f"path for engine {self.engine!r} must end in {' or '.join(allowed)}, or .nc for the "
                             f"certified table (got {path.name!r})")
        if self.engine == "cycles":
            self.table.write(path)
        elif self.engine == "filament":
            write_filament_inc(path, self.values("DFG.x"), self.values("DFG.y"), self._comment(), cloth)
        else:
            write_unreal(path, self.values("A"), self.values("B"), self._comment())
        sidecar = path.with_name(path.name + ".json")
        atomic_write(sidecar, lambda tmp: Path(tmp).write_text(json.dumps(self.description(), indent=1)))
        return path

    def _comment(self) -> list[str]:
        prov = self.table.provenance
        return [f"Certified by virtspec-mi {prov.get('virtspec_mi')} (Mitsuba {prov.get('mitsuba')}, "
                f"{prov.get('variant')}), {prov.get('created')}, seed {prov.get('seed')}",
                f"model: {prov.get('bsdf_model')}",
                "channels: " + held(self.channels)
                + " (E_R: reflected rays = int Fc f cos; E_T: rays sent below = int (1 - Fc) f cos; E = both)",
                f"every value within {np.nanmax(self.table.certified_epsilon()):.4g}, jointly with probability "
                f">= {1 - self.delta:g}; rays {self.rays:,}"]


def held(channels: dict[str, str]) -> str:
    """
    The channels and the quantity each holds, for people: ``DFG.x = E_R, DFG.y = E``; a
    channel named as its quantity is named once (``E``, not ``E = E``).
    """

    return ", ".join(name if name == quantity else f"{name} = {quantity}" for name, quantity in channels.items())


def check_engine_sidecar(path: str | os.PathLike, overwrite: bool = False, inputs: Any = ()) -> None:
    """
    Refuse (``ValueError``) a drop-in file whose ``PATH.json`` sidecar would replace an
    input (``inputs``), or a file of that name that is not such a sidecar, unless
    ``overwrite`` (``virtspec albedo-table --overwrite``).
    """

    path = Path(path)
    check_companions(path, [path.with_name(path.name + ".json")], _is_engine_sidecar, overwrite, inputs=inputs,
                     flag=spoken("overwrite=True", "--overwrite"))


def _is_engine_sidecar(path: Path) -> bool:
    """Whether ``path`` is the provenance sidecar of an engine's drop-in file (:meth:`EngineTables.description`)."""

    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return False
    return isinstance(data, dict) and {"engine", "channels", "certificate", "table"} <= set(data)


def engine_tables(engine: str, *, epsilon: float = 1e-3, delta: float = 0.01, seed: int = 0,
                  bound: str = "two-stage", average: bool | None = None, progress: bool | None = None,
                  checkpoint: str | os.PathLike | None = None, chunk_size: int | None = None) -> EngineTables:
    """
    Certify every channel of ``engine``'s table with its own model on its grid (module
    docstring), in one table: Cycles E (and E_avg, ``average`` default ``True``);
    Filament DFG.x and DFG.y, Unreal A and B on the same rays (``fresnel="split"``,
    ``parts=True``). ``checkpoint``: a directory keeping finished groups (resume).
    """

    from virtspec_mi.applications.tables.albedo import albedo_table

    if engine not in ENGINE_CHANNELS:
        raise ValueError(f"engine must be one of {', '.join(ENGINE_CHANNELS)} (got {engine!r})")
    fresnel, channels = ENGINE_CHANNELS[engine]
    if average is None:
        average = engine == "cycles"
    table = albedo_table("conductor", distribution="ggx", engine=engine, fresnel=fresnel, parts=fresnel == "split",
                         epsilon=epsilon, delta=delta, bound=bound, average=average, seed=seed, progress=progress,
                         checkpoint=checkpoint, chunk_size=chunk_size)
    return EngineTables(engine, table, dict(channels))


def engine_layout(engine: str) -> dict[str, tuple[int, ...]]:
    """The shape of each channel in the engine's memory order (``E_avg`` for Cycles' average)."""

    if engine == "cycles":
        return {"E": (32, 32), "E_avg": (32,)}
    if engine == "filament":
        return {"DFG.x": (128, 128), "DFG.y": (128, 128)}
    if engine == "unreal":
        return {"A": (32, 128), "B": (32, 128)}
    raise ValueError(f"engine must be one of cycles, filament, unreal (got {engine!r})")


# ----------------------------------------------------------------------------- Filament

def write_filament_inc(path: str | os.PathLike, x: np.ndarray, y: np.ndarray, comment: list[str] | None = None,
                       cloth: np.ndarray | None = None) -> Path:
    """
    ``dfg.inc`` as ``cmgen`` writes it: half floats (``0x%04x,`` per channel value), four texels
    a line, rows in GL order (the last row of the [roughness][μ] table first). ``x``,
    ``y`` (and ``cloth``) are 128 × 128 in the table's order (roughest row first).
    """

    arrays = [np.asarray(a, dtype=np.float64) for a in (x, y) + (() if cloth is None else (cloth,))]
    if any(a.ndim != 2 or a.shape != arrays[0].shape for a in arrays):
        raise ValueError("x, y (and cloth) must be 2-D arrays of one shape")
    texels = np.stack([a[::-1] for a in arrays], axis=-1).astype(np.float16).view(np.uint16)  # GL order
    lines = ["// generated with: virtspec-mi (certified; cmgen --ibl-dfg-multiscatter layout)",
             "// DFG LUT stored as an RG16F texture, in GL order"
             + ("" if cloth is None else " (third channel: cloth, copied, NOT certified)")]
    lines += [f"// {text}" for text in (comment or [])]
    size = texels.shape[1]
    body = []
    for row in texels:
        for start in range(0, size, 4):
            body.append("    " + "".join(f"0x{v:04x}, " for texel in row[start:start + 4] for v in texel))
    text = "\n".join(lines) + "\n" + "\n".join(body) + "\n"
    return atomic_write(path, lambda tmp: Path(tmp).write_text(text))


def read_filament_inc(path: str | os.PathLike, size: int = 128) -> dict[str, np.ndarray]:
    """
    The channels of a ``dfg.inc`` (two, or three with cloth) as float64 ``size × size``
    arrays in the table's order (roughest row first): ``DFG.x``, ``DFG.y`` (, ``cloth``).
    """

    import re

    text = re.sub(r"//[^\n]*", " ", Path(path).read_text())
    words = np.array([int(h, 16) for h in re.findall(r"0x([0-9a-fA-F]{1,4})", text)], dtype=np.uint16)
    for channels in (2, 3):
        if words.size == size * size * channels:
            break
    else:
        raise ValueError(f"{path}: {words.size} half floats, not a {size} x {size} texture of 2 or 3 channels")
    values = words.view(np.float16).astype(np.float64).reshape(size, size, channels)[::-1]
    names = ("DFG.x", "DFG.y", "cloth")[:channels]
    return {name: np.ascontiguousarray(values[..., k]) for k, name in enumerate(names)}


# ----------------------------------------------------------------------------- Unreal

def _unorm16(values: np.ndarray) -> np.ndarray:
    return (np.clip(values, 0.0, 1.0) * 65535.0 + 0.5).astype(np.uint16)  # SystemTextures.cpp's rounding


def _chunk(kind: bytes, data: bytes) -> bytes:
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)


def write_unreal(path: str | os.PathLike, a: np.ndarray, b: np.ndarray, comment: list[str] | None = None) -> Path:
    """
    Unreal's ``PreintegratedGF`` texture: ``.raw`` G16R16 (per texel A then B, uint16
    little-endian, rows = roughness ascending) or ``.png`` (16-bit RGB, R = A, G = B, B = 0,
    big-endian as PNG stores it; ``comment`` in a ``tEXt`` chunk). ``a``, ``b``: 32 × 128.
    """

    a16, b16 = _unorm16(np.asarray(a, dtype=np.float64)), _unorm16(np.asarray(b, dtype=np.float64))
    if a16.shape != b16.shape or a16.ndim != 2:
        raise ValueError("a and b must be 2-D arrays of one shape")
    path = Path(path)
    if path.suffix.lower() == ".raw":
        data = np.stack([a16, b16], axis=-1).astype("<u2").tobytes()
        return atomic_write(path, lambda tmp: Path(tmp).write_bytes(data))
    height, width = a16.shape
    rgb = np.stack([a16, b16, np.zeros_like(a16)], axis=-1).astype(">u2")
    raw = b"".join(b"\x00" + rgb[row].tobytes() for row in range(height))  # filter 0 per row
    text = "\n".join(comment or []).encode("latin-1", "replace")
    png = (b"\x89PNG\r\n\x1a\n" + _chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 16, 2, 0, 0, 0))
           + _chunk(b"tEXt", b"Description\x00" + text) + _chunk(b"IDAT", zlib.compress(raw, 9))
           + _chunk(b"IEND", b""))
    return atomic_write(path, lambda tmp: Path(tmp).write_bytes(png))


def _unfilter(data: bytes, height: int, stride: int, pixel: int) -> np.ndarray:
    rows = np.zeros((height, stride), dtype=np.int64)
    previous = np.zeros(stride, dtype=np.int64)
    position = 0
    for r in range(height):
        kind = data[position]
        line = np.frombuffer(data, dtype=np.uint8, count=stride, offset=position + 1).astype(np.int64)
        position += stride + 1
        out = line.copy()
        if kind == 2:
            out = (line + previous) & 0xFF
        elif kind in (1, 3, 4):
            for i in range(stride):
                left = out[i - pixel] if i >= pixel else 0
                up, corner = previous[i], previous[i - pixel] if i >= pixel else 0
                if kind == 1:
                    guess = left
                elif kind == 3:
                    guess = (left + up) // 2
                else:
                    p = left + up - corner
                    pa, pb, pc = abs(p - left), abs(p - up), abs(p - corner)
                    guess = left if pa <= pb and pa <= pc else up if pb <= pc else corner
                out[i] = (line[i] + guess) & 0xFF
        elif kind != 0:
            raise ValueError(f"PNG filter type {kind} is not one of 0-4")
        rows[r] = out
        previous = out
    return rows.astype(np.uint8)


def read_unreal(path: str | os.PathLike, width: int = 128, height: int = 32) -> dict[str, np.ndarray]:
    """
    A and B (float64, ``height × width``, roughness rows ascending) from a ``.raw`` G16R16
    texture or a 16-bit PNG (R = A, G = B; grey-alpha, RGB or RGBA, non-interlaced).
    """

    path = Path(path)
    data = path.read_bytes()
    if path.suffix.lower() == ".raw":
        if len(data) != width * height * 4:
            raise ValueError(f"{path}: {len(data)} bytes, not a {width} x {height} G16R16 texture "
                             f"({width * height * 4} bytes)")
        texels = np.frombuffer(data, dtype="<u2").reshape(height, width, 2).astype(np.float64) / 65535.0
        return {"A": texels[..., 0].copy(), "B": texels[..., 1].copy()}
    if not data.startswith(b"\x89PNG\r\n\x1a\n"):
        raise ValueError(f"{path}: not a .raw texture or a PNG file")
    position, header, idat = 8, None, b""
    while position < len(data):
        length, kind = struct.unpack(">I4s", data[position:position + 8])
        body = data[position + 8:position + 8 + length]
        if kind == b"IHDR":
            header = struct.unpack(">IIBBBBB", body)
        elif kind == b"IDAT":
            idat += body
        position += 12 + length
    if header is None:
        raise ValueError(f"{path}: PNG without IHDR")
    w, h, depth, colour, _, _, interlace = header
    channels = {4: 2, 2: 3, 6: 4}.get(colour)
    if depth != 16 or channels is None or interlace != 0:
        raise ValueError(f"{path}: a 16-bit grey-alpha, RGB or RGBA non-interlaced PNG is needed "
                         f"(got depth {depth}, colour type {colour}, interlace {interlace})")
    if (w, h) != (width, height):
        raise ValueError(f"{path}: {w} x {h} pixels, Unreal's PreintegratedGF is {width} x {height}")
    rows = _unfilter(zlib.decompress(idat), h, w * channels * 2, channels * 2)
    texels = rows.view(">u2").reshape(h, w, channels).astype(np.float64) / 65535.0
    return {"A": texels[..., 0].copy(), "B": texels[..., 1].copy()}


def _declares(path: Path, array: str) -> bool:
    """Whether the C header ``path`` names the array ``array`` at all."""

    import re

    text = path.read_text(encoding="utf-8", errors="replace")
    return re.search(rf"\b{re.escape(array)}\s*\[", text) is not None


def read_engine_file(path: str | os.PathLike, engine: str) -> dict[str, np.ndarray]:
    """
    A published table in the engine's native layout, by channel, in the engine's memory
    order: Cycles ``E`` (``table_ggx_E``) and ``E_avg`` (``table_ggx_Eavg``, when present)
    from a C header; Filament ``DFG.x``, ``DFG.y`` from ``dfg.inc``; Unreal ``A``, ``B``
    from ``.raw`` or ``.png``.
    """

    from virtspec_mi.exchange.header import read_table_values

    path = Path(path)
    if not path.exists():
        raise ValueError(f"the published table {path} does not exist")
    shapes = engine_layout(engine)
    if engine == "cycles":
        found = {"E": read_table_values(path, array="table_ggx_E", expected=1024).reshape(shapes["E"])}
        if _declares(path, "table_ggx_Eavg"):  # present: read whole or refused (31 values are not an E_avg)
            try:
                found["E_avg"] = read_table_values(path, array="table_ggx_Eavg", expected=32)
            except ValueError as error:
                raise ValueError(f"{path}: table_ggx_Eavg (Cycles' E_avg, 32 values): {error}") from None
        return found
    if engine == "filament":
        return read_filament_inc(path)
    return read_unreal(path)
