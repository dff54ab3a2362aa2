"""
A target that survives interruption: every batch's counts kept on disk
======================================================================

``vm.measure(scene, target=..., checkpoint=PATH)`` (``virtspec measure SCENE --target
... --checkpoint PATH``) keeps the counts of every trace of the run — the pilot, each
batch of the betting route, Hoeffding's one batch — in the JSON file ``PATH``, written
atomically (:func:`virtspec_mi.base.files.atomic_write`) after each trace: a SIGKILL
leaves the file as it was after the last finished batch, or after the one before.

The same call again resumes: it runs the same deterministic computation, and each trace
whose counts the file holds — the same wavelengths, rays, first global ray indices and
seed, in the same order (:class:`TargetCheckpoint`) — is read back instead of traced.
Everything a batch decides (the stakes, the next batch's rays, whether to stop) is a
function of the seed and of the counts before it, so the resumed run takes the very
batches the uninterrupted one takes, and its result is **bit-identical** to it (every
count, interval, batch and reading; the wall time ``seconds`` excepted). The sequence
stays valid: the rays of the batches traced after the resume are the same fresh rays
(the same global indices) the uninterrupted run would have traced, and the stakes of
each batch were fixed before it, from the counts before it.

The file records what decides the counts (the scene's fingerprint, the settings, the
target, the bound, the version): a file of another run, or a trace the run does not
ask for at that place, raises :class:`~virtspec_mi.engine.checkpoint.CheckpointError`
and is left as it is. It is read as strictly as user input (whole counts, each within
its rays). One run at a time holds the file (:func:`virtspec_mi.engine.checkpoint.claim`);
the file is removed once the result is returned.
"""

from __future__ import annotations

import contextlib
import contextvars
import hashlib
import json
import math
from dataclasses import fields
from pathlib import Path
from typing import Any, Callable, Iterator

import numpy as np

from virtspec_mi.base.files import atomic_write
from virtspec_mi.base.version import __version__
from virtspec_mi.engine.checkpoint import CheckpointError, claim, remove
from virtspec_mi.engine.tally import Tally
from virtspec_mi.kernel.counts import Counts

__all__ = ["FORMAT", "TargetCheckpoint", "REPLAY", "replaying", "trace_key"]

FORMAT: str = "virtspec-mi target checkpoint 1"
"""The ``format`` of a target's checkpoint file."""

REPLAY: contextvars.ContextVar["TargetCheckpoint | None"] = contextvars.ContextVar("target_checkpoint", default=None)
"""The checkpoint of the target being measured in this context (``None``: no checkpoint)."""


def trace_key(grid: np.ndarray, rays: np.ndarray, seed: int, offsets: np.ndarray | None) -> str:
    """What decides one trace's counts besides the run's identity: a SHA-256 of its wavelengths, rays, offsets, seed."""

    digest = hashlib.sha256()
    for part in (np.asarray(grid, dtype=np.float64), np.asarray(rays, dtype=np.int64),
                 np.zeros(0) if offsets is None else np.asarray(offsets, dtype=np.int64)):
        digest.update(part.tobytes())
        digest.update(b"|")
    digest.update(str(int(seed)).encode())
    return digest.hexdigest()


def _counts_json(counts: Counts) -> dict[str, list]:
    out = {}
    for item in fields(counts):
        value = np.asarray(getattr(counts, item.name))
        if item.name == "largest_weight":
            out[item.name] = [None if not math.isfinite(v) else float(v) for v in value.tolist()]
        else:
            out[item.name] = [int(v) for v in value.tolist()]
    return out


def _whole(name: str, values: Any, length: int) -> np.ndarray:
    if not isinstance(values, list) or len(values) != length or \
            not all(isinstance(v, int) and not isinstance(v, bool) and v >= 0 for v in values):
        raise ValueError(f"{name} must be {length} whole numbers >= 0")
    return np.asarray(values, dtype=np.int64)


def _counts_from(data: Any, rays: np.ndarray) -> Counts:
    """The counts stored for a trace of ``rays`` (each > 0), checked as strictly as user input."""

    if not isinstance(data, dict) or set(data) != {item.name for item in fields(Counts)}:
        raise ValueError(f"counts must have exactly the fields {', '.join(item.name for item in fields(Counts))}")
    n = len(rays)
    values = {name: _whole(name, data[name], n) for name in data if name != "largest_weight"}
    weights = data["largest_weight"]
    if not isinstance(weights, list) or len(weights) != n or \
            not all(w is None or (isinstance(w, (int, float)) and math.isfinite(w)) for w in weights):
        raise ValueError(f"largest_weight must be {n} numbers or nulls")
    if not np.array_equal(values["rays"], rays):
        raise ValueError("rays differ from the trace's")
    fated = values["reflected"] + values["transmitted"] + values["capped"] + values["invalid_directions"]
    if np.any(fated > rays) or any(np.any(values[name] > rays) for name in values):
        raise ValueError("a count exceeds its rays")
    return Counts(**values, largest_weight=np.array([np.nan if w is None else float(w) for w in weights]))


class TargetCheckpoint:
    """
    The traces of one target run kept in ``path`` (module docstring): :meth:`trace` reads
    a trace back when the file holds it at that place, else traces it and saves the file.

    Attributes
    ----------
    path : Path
        The JSON file.
    identity : dict
        What decides the counts (scene fingerprint, settings, target, bound, version).
    reused : int
        Traces read back from the file in this run.
    """

    def __init__(self, path: str | Path, identity: dict[str, Any]) -> None:
        self.path, self.identity = Path(path), json.loads(json.dumps(identity, sort_keys=True, default=str))
        self.stored: list[dict[str, Any]] = []
        self.done: list[dict[str, Any]] = []
        self.reused = 0
        if self.path.exists():
            self._load()

    def _load(self) -> None:
        try:
            data = json.loads(self.path.read_text())
        except (OSError, ValueError) as error:
            raise CheckpointError(f"checkpoint {self.path}: not a target checkpoint ({error}); left as it is") from None
        if not isinstance(data, dict) or data.get("format") != FORMAT or not isinstance(data.get("traces"), list):
            raise CheckpointError(f"checkpoint {self.path}: not a target checkpoint (format {FORMAT!r}); left as it is")
        if data.get("identity") != self.identity:
            raise CheckpointError(f"checkpoint {self.path} belongs to another measurement (scene, settings, target or "
                                  "bound differ): give another checkpoint, or remove it to start again")
        self.stored = data["traces"]

    def trace(self, key: str, rays: np.ndarray, run: Callable[[], Tally]) -> Tally:
        """The tally of the next trace (``key``: :func:`trace_key`; ``rays`` > 0 of its readings): read back, or run."""

        position = len(self.done)
        rays = np.asarray(rays, dtype=np.int64)
        if position < len(self.stored):
            entry = self.stored[position]
            if not isinstance(entry, dict) or entry.get("key") != key:
                raise CheckpointError(f"checkpoint {self.path}: trace {position + 1} is not the one this run asks for "
                                      "there (another measurement's file?); left as it is")
            try:
                counts = _counts_from(entry.get("counts"), rays)
                seconds = float(entry.get("seconds"))
                if not math.isfinite(seconds) or seconds < 0:
                    raise ValueError("seconds must be a number >= 0")
            except (TypeError, ValueError) as error:
                raise CheckpointError(f"checkpoint {self.path}: trace {position + 1}: {error}; left as it is") from None
            self.done.append(entry)
            self.reused += 1
            return Tally(counts).with_seconds(seconds)
        tally = run()
        self.done.append({"key": key, "counts": _counts_json(tally.counts), "seconds": float(tally.seconds)})
        self._save()
        return tally

    def _save(self) -> None:
        text = json.dumps({"format": FORMAT, "identity": self.identity, "traces": self.done})
        atomic_write(self.path, lambda temporary: Path(temporary).write_text(text))


@contextlib.contextmanager
def replaying(path: str | Path | None, identity: dict[str, Any]) -> Iterator["TargetCheckpoint | None"]:
    """
    The block's traces kept in checkpoint ``path`` (held by this run; removed when the block
    ends without an error); ``None``: nothing kept.
    """

    if path is None:
        yield None
        return
    with claim(path):
        checkpoint = TargetCheckpoint(path, {**identity, "version": __version__})
        token = REPLAY.set(checkpoint)
        try:
            yield checkpoint
        finally:
            REPLAY.reset(token)
    remove(path)
