"""
Small pieces the exchange modules share: companion files and derived seeds
===========================================================================

Their files are written as every file of the project is
(:func:`virtspec_mi.base.files.atomic_write`).

- :func:`check_companions`: a companion file an output brings with it (a sidecar of
  another suffix, an average beside a table) never replaces a file of that name that
  the format did not write, unless told to (``overwrite``), and never an input.
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
from typing import Callable, Iterable

from virtspec_mi.base.files import same_file

__all__ = ["check_companions", "derived_seed"]


def check_companions(output: str | os.PathLike, companions: Iterable[str | os.PathLike], ours: Callable[[Path], bool],
                     overwrite: bool = False, inputs: Iterable[str | os.PathLike] = (),
                     flag: str = "overwrite=True") -> None:
    """
    Refuse (``ValueError``, before anything is measured or written) a companion of
    ``output`` whose name is an input of the run (``inputs``: a scene file), the output
    itself, or an existing file that ``ours(path)`` does not recognise as written by
    this format — unless ``overwrite`` (its name in ``flag``).
    """

    output = Path(output)
    taken = [path for path in inputs if isinstance(path, (str, os.PathLike)) and Path(path).exists()]
    for companion in map(Path, companions):
        an_input = any(same_file(companion, path) for path in taken)
        if an_input or same_file(companion, output):
            raise ValueError(f"{output}: its companion file {companion} would replace "
                             f"{'an input of this run' if an_input else 'the output itself'}; choose another "
                             "output name")
        if companion.is_dir() or (companion.exists() and not overwrite and not ours(companion)):
            raise ValueError(f"{output}: its companion file {companion} already exists and was not written by "
                             f"virtspec-mi for this output; move it, choose another output name, or pass {flag}")


def derived_seed(seed: int, label: str) -> int:
    """A 32-bit seed for the group ``label`` of a run seeded with ``seed`` (BLAKE2b of both)."""

    return int.from_bytes(hashlib.blake2b(f"{seed}:{label}".encode(), digest_size=4).digest(), "little")
