"""
Spectral Evolution ``.sed`` files: a reader of the published layout
===================================================================

A ``.sed`` file (PSR, RS, SR spectroradiometers) is a header of ``Key: value`` lines, then
``Data:``, a row of tab-separated column names and one row per channel. A ratio column
named ``Reflect.`` holds reflectance, ``Trans.`` transmittance, ``Tgt./Ref.`` the quantity
of the header's ``Measurement:`` line (``REFLECTANCE``, ``TRANSMITTANCE``); ``%`` in its
name is a percentage, ``[1.0]`` a fraction. Without a ratio column the ``(Ref.)`` and
``(Target)`` columns are ratioed. A ratio column that contradicts ``Measurement:`` is
refused (a mislabelled file), and the header's ``Channels:`` count is checked (a
truncated file is refused).

No package reader is used: ``specdal`` (MIT) reads ``.sed`` but has had no release since
2018 and pulls pandas, SciPy and Matplotlib.

References
----------
Spectral Evolution, *DARWin SP Data Acquisition Software Manual* (the ``.sed`` file).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from virtspec_mi.exchange.measured.base import RawSpectra, number_rows, refuse, text_lines

__all__ = ["read_sed"]


_SED_QUANTITIES = {"reflectance": "reflectance", "transmittance": "transmittance"}


def _ratio_column(names: list[str]) -> tuple[int, str | None, str | None] | None:
    for k, name in enumerate(names):
        lower = name.lower()
        if lower.startswith(("reflect", "trans", "tgt./ref", "tgt/ref")):
            quantity = ("reflectance" if lower.startswith("reflect") else
                        "transmittance" if lower.startswith("trans") else None)
            scale = "percent" if "%" in name else "fraction" if "[1.0]" in name else None
            return k, quantity, scale
    return None


def read_sed(path: Path, splice: bool = False) -> RawSpectra:
    """A Spectral Evolution ``.sed`` file (see the module docstring)."""

    path = Path(path)
    lines = text_lines(path)
    header: dict[str, str] = {}
    start = None
    for k, line in enumerate(lines):
        if line.strip().lower() == "data:":
            start = k + 1
            break
        key, sep, value = line.partition(":")
        if sep:
            header[key.strip().lower()] = value.strip()
    if start is None or "version" not in header:
        raise refuse(path, "not a Spectral Evolution .sed file, or truncated before its data (no 'Version:' and "
                           "'Data:' lines)")
    if start >= len(lines):
        raise refuse(path, "truncated: nothing after 'Data:'")
    names = [name.strip() for name in lines[start].split("\t") if name.strip()]
    table = number_rows(path, [(k + 1, line) for k, line in enumerate(lines[start + 1:], start + 1)], len(names))
    channels = header.get("channels", "")
    if channels.isdigit() and int(channels) != len(table):
        raise refuse(path, f"truncated or damaged: its header says Channels: {channels}, it holds {len(table)} rows")
    measurement = header.get("measurement", "").strip().lower()
    told_quantity = _SED_QUANTITIES.get(measurement)
    label = Path(header.get("file name", path.name).replace("\\", "/")).stem or path.stem
    metadata = ({key: header[key] for key in ("instrument", "measurement", "date", "time", "units")
                 if key in header},)
    ratio = _ratio_column(names)
    if ratio is not None:
        k, quantity, scale = ratio
        if quantity and told_quantity and quantity != told_quantity:
            raise refuse(path, f"its column {names[k]!r} holds {quantity}, its header says Measurement: "
                               f"{header['measurement']}: a mislabelled file")
        quantity = quantity or told_quantity
        told = f"its column {names[k]!r}" if ratio[1] else f"its header's Measurement: {header.get('measurement')}"
        return RawSpectra(wavelengths=table[:, 0], labels=(label,), values=table[None, :, k], quantity=quantity,
                          scale=scale, unit="nm", told=told, metadata=metadata)
    reference = [k for k, name in enumerate(names) if "(ref" in name.lower()]
    target = [k for k, name in enumerate(names) if "(target" in name.lower() or "(tgt" in name.lower()]
    if not (reference and target):
        raise refuse(path, f"its columns ({', '.join(names)}) hold neither a ratio (Reflect., Trans., Tgt./Ref.) nor a "
                           "reference and target pair")
    return RawSpectra(wavelengths=table[:, 0], labels=(label,), target=table[None, :, target[0]],
                      reference=table[None, :, reference[0]], quantity=told_quantity, unit="nm",
                      told=f"its header's Measurement: {header.get('measurement', '(none)')}", metadata=metadata)
