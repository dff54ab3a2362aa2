"""
Small pieces the exchange modules share: atomic file writes and derived seeds
=============================================================================

- :func:`atomic_write`: a file written through a temporary file beside it and renamed
  onto its name in one step, so a reader never sees half a file and an interrupted
  write leaves the old file (or none) — the rule every result file of the project
  follows (the manual, docs/guide/files.md).
- :func:`derived_seed`: the seed of one group of readings of a larger run (a table's
  group of cells, a Klems file's incidence azimuth), a hash of the run's seed and the
  group's label, so every group has its own random numbers and a resumed run traces the
  same rays.

References
----------
Baranoski, G.V.G., Rokne, J.G., Xu, G. (2001). The Visual Computer 17, 506–518 (the
instrument whose readings these files carry).
"""

from __future__ import annotations

import hashlib
import os
from pathlib import Path
from typing import Any, Callable

__all__ = ["atomic_write", "derived_seed"]


def atomic_write(path: str | os.PathLike, write: Callable[[str], Any]) -> Path:
    """Call ``write(temporary_path)``, then rename the temporary file onto ``path``."""

    path = Path(path)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    try:
        write(str(tmp))
        os.replace(tmp, path)
    finally:
        if tmp.exists():
            tmp.unlink()
    return path


def derived_seed(seed: int, label: str) -> int:
    """A 32-bit seed for the group ``label`` of a run seeded with ``seed`` (BLAKE2b of both)."""

    return int.from_bytes(hashlib.blake2b(f"{seed}:{label}".encode(), digest_size=4).digest(), "little")
