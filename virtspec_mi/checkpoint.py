"""
Checkpoints: finished readings of a long run, kept on disk
==========================================================

A run keyed on reading indices (:func:`virtspec_mi.engine.run`, e.g. a sweep) records
every finished batch in a JSON file, atomically (an interruption leaves the old or the
new file); a later run of the same measurement picks the finished readings up and
traces only the rest, ending with exactly the counts of an uninterrupted run. The file
records what decides the counts (settings, grids, geometry, scene fingerprint): a
mismatch or a corrupt file raises :class:`CheckpointError` (a ``ValueError``) rather
than mixing results. Every count is kept by name, the pilot's too.
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

import numpy as np

from virtspec_mi import __version__
from virtspec_mi.counts import Counts

__all__ = ["CheckpointError", "Checkpoint"]

_FORMAT = "virtspec-mi sweep checkpoint 2"


class CheckpointError(ValueError):
    """A checkpoint file is corrupt or belongs to another measurement."""


class Checkpoint:
    """Finished readings of a run (``done``, ``counts``, ``pilot``, ``seconds``), optionally mirrored in a file."""

    def __init__(self, path: Path | None, identity: dict[str, Any], size: int) -> None:
        self.path, self.identity = path, identity
        self.done = np.zeros(size, dtype=bool)
        self.counts, self.pilot = Counts.zeros(size), Counts.zeros(size)
        self.seconds = 0.0

    @classmethod
    def open(cls, path: str | os.PathLike | None, identity: dict[str, Any], size: int) -> "Checkpoint":
        """The state of a run of ``size`` readings, resumed from ``path`` when it exists."""

        state = cls(Path(path) if path is not None else None, identity, size)
        if state.path is not None and state.path.exists():
            state._load()
        return state

    def record(self, batch: np.ndarray, counts: Counts, pilot: Counts | None, seconds: float) -> None:
        """Keep the counts of readings ``batch`` (and save the file)."""

        self.counts.put(batch, counts)
        if pilot is not None:
            self.pilot.put(batch, pilot)
        self.done[batch] = True
        self.seconds += seconds
        if self.path is not None:
            self._save()

    def finish(self) -> None:
        """The run is complete: remove the file."""

        if self.path is not None and self.path.exists():
            self.path.unlink()

    def _load(self) -> None:
        path = self.path
        try:
            data = json.loads(path.read_text())
            if not isinstance(data, dict) or data.get("format") != _FORMAT:
                raise CheckpointError(f"checkpoint {path} is not a virtspec-mi sweep checkpoint of this version "
                                      f"({_FORMAT!r}); delete it to start the sweep over")
            done = np.array(data["done"], dtype=np.int64)
            counts = {name: np.array(data["counts"][name], dtype=np.float64 if name == "largest_weight" else np.int64)
                      for name in Counts.names()}
            pilot = {name: np.array(data["pilot"][name], dtype=np.float64 if name == "largest_weight" else np.int64)
                     for name in Counts.names()}
            seconds = float(data["seconds"])
            stored = data["identity"]
        except CheckpointError:
            raise
        except (OSError, ValueError, KeyError, TypeError) as error:
            raise CheckpointError(
                f"checkpoint {path} is corrupt ({type(error).__name__}: {error}); delete it to start the sweep over"
            ) from None
        expected = json.loads(json.dumps(self.identity))
        if stored != expected:
            keys = sorted(k for k in set(stored) | set(expected) if stored.get(k) != expected.get(k))
            raise CheckpointError(
                f"checkpoint {path} belongs to a different sweep (differs in: {', '.join(keys)}); "
                "re-run with the same scene and settings, or delete it to start over"
            )
        size = self.done.size
        shapes = {v.shape for v in (*counts.values(), *pilot.values())}
        if shapes != {(len(done),)} or (len(done) and (done.min() < 0 or done.max() >= size)):
            raise CheckpointError(f"checkpoint {path} is corrupt (counts do not match the sweep); delete it")
        self.done[done] = True
        self.counts.put(done, Counts(**counts))
        self.pilot.put(done, Counts(**pilot))
        self.seconds = seconds

    def _save(self) -> None:
        done = np.flatnonzero(self.done)

        def plain(counts: Counts) -> dict[str, list]:
            return {name: [None if np.isnan(v) else v for v in getattr(counts, name)[done].tolist()]
                    if name == "largest_weight" else getattr(counts, name)[done].tolist() for name in Counts.names()}

        data = {
            "format": _FORMAT,
            "version": __version__,
            "identity": self.identity,
            "seconds": self.seconds,
            "done": done.tolist(),
            "counts": plain(self.counts),
            "pilot": plain(self.pilot),
        }
        temporary = self.path.with_name(self.path.name + ".tmp")
        temporary.write_text(json.dumps(data))
        os.replace(temporary, self.path)  # atomic: an interruption leaves the old or the new file
