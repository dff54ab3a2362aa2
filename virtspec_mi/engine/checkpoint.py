"""
Checkpoints: finished readings of a long run, kept on disk
==========================================================

A run keyed on reading indices (:func:`virtspec_mi.engine.readings.run`: a sweep, a
goniophotometer or a sphere reading) records every finished batch in a JSON file,
atomically (:func:`virtspec_mi.base.files.atomic_file`: an interruption leaves the old or the
new file, and only a temporary of its own is ever removed; saves are spaced out when they
would take more than about a tenth of the run, and what is left is saved at the end and
on an interruption). A save that fails (a full disk) does not stop the run: it is warned
about once, retried at the next save, and :func:`kept_in` says afterwards where the
readings are (the file, or memory only); a later run of the
same measurement picks the finished readings up and traces only the rest, ending with
exactly the counts of an uninterrupted run. The file
records what decides the counts (settings, grids, geometry, scene fingerprint): a
mismatch or a corrupt file raises :class:`CheckpointError` (a ``ValueError``) rather
than mixing results. Every count is kept by name, the pilot's too, and so are the kernel
hook's bins and per-reading sums of an instrument that has them (a goniophotometer's bin
counts, a sphere's fate histogram and wall reflections). A file of format 3 (before bins
and sums were kept) is read for a run without them — a hemispherical sweep resumes from
it — and refused, with the reason, for one with them.

A checkpoint is read as strictly as user input: counts are whole numbers with
0 ≤ count ≤ rays and reflected + transmitted + capped ≤ rays, each reading's rays are
those its settings give, ``done`` holds distinct reading indices in range, ``seconds``
is finite and ≥ 0, bins are whole numbers ≥ 0 adding up to at most the reading's rays,
sums whole numbers ≥ 0, and readings traced together (a wavelength-independent specimen's
wavelengths) are done together with equal counts. A file that breaks any of these is
refused with the reason and left as it is: nothing here ever deletes a checkpoint that
was not completed.

One run at a time: :func:`claim` checks, before any tracing, that the checkpoint can be
written where it is, and holds an OS lock (``fcntl.flock`` on ``PATH.lock``) for the
whole run; a second run on the same file is refused ("… is in use by another run (pid
…)"). Removing the file is the caller's decision (:func:`remove`), taken once the work
is safe elsewhere: :func:`virtspec_mi.api.sweep` removes it when it returns the result,
or, with ``out=``, once the output file is written and flushed to disk.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import re
import time
import warnings
from contextlib import contextmanager
from pathlib import Path
from typing import Any, Iterator

import numpy as np

from virtspec_mi.base.version import __version__
from virtspec_mi.base.files import IN_MEMORY, WriteError, atomic_file, atomic_write
from virtspec_mi.engine.tally import Tally
from virtspec_mi.kernel.counts import Counts

try:
    import fcntl
except ImportError:  # not a POSIX system: checkpoints are not locked
    fcntl = None  # type: ignore[assignment]

__all__ = ["CheckpointError", "Checkpoint", "checkpoint_for", "claim", "remove", "kept_in", "locked", "ResultStore"]

_FORMAT = "virtspec-mi sweep checkpoint 4"  # 3: invalid_directions counted; 4: bins and sums kept
_FORMAT_WITHOUT_BINS = "virtspec-mi sweep checkpoint 3"  # read for runs without bins or sums
_SAVE_EVERY = 10.0  # save again once the time since the last save is this many times what it took
_SUFFIX = ".partial.json"
_LOCK_SUFFIX = ".lock"


class CheckpointError(ValueError):
    """A checkpoint file is corrupt, belongs to another measurement, cannot be written or is in use."""


_UNSAVED: dict[Path, str] = {}  # checkpoints whose last save failed in this process, with the cause


def kept_in(path: str | os.PathLike) -> str:
    """
    Where the finished readings of a run with checkpoint ``path`` are, in words, for a
    message after a failure: in the checkpoint, or — when its last save failed — in
    memory only (the error's ``result``).
    """

    path = Path(path)
    cause = _UNSAVED.get(path)
    if cause is None:
        return f"every finished reading is kept in {path}: re-run the same sweep to write it"
    return f"the checkpoint {path} could not be saved either ({cause}); {IN_MEMORY}"


def checkpoint_for(out: str | os.PathLike) -> Path:
    """The checkpoint of a run written to ``out``: ``OUT.partial.json`` beside it."""

    out = Path(out)
    return out.with_name(out.name + _SUFFIX)


@contextmanager
def claim(path: str | os.PathLike) -> Iterator[Path]:
    """
    Hold checkpoint ``path`` for one run: check that it can be written there and take
    an exclusive OS lock on ``PATH.lock`` until the block ends (the lock file is then
    removed; the lock of a killed process ends with it). ``CheckpointError`` naming the
    path when it cannot be written, or when another run holds it (with that run's pid).
    """

    path = Path(path)
    _check_writable(path)
    handle = _lock(path)
    try:
        yield path
    finally:
        _unlock(path, handle)


@contextmanager
def locked(path: str | os.PathLike) -> Iterator[Path]:
    """
    An exclusive OS lock on ``PATH.lock`` (beside ``path``: a checkpoint file or folder)
    until the block ends, as :func:`claim` takes it: ``CheckpointError`` naming the
    path and the pid when another run holds it (a second run on one output refuses,
    never touching the first's files).
    """

    path = Path(path)
    handle = _lock(path)
    try:
        yield path
    finally:
        _unlock(path, handle)


def remove(path: str | os.PathLike) -> None:
    """Remove checkpoint ``path`` (if it exists): call only once its readings are safe elsewhere."""

    Path(path).unlink(missing_ok=True)


def _check_writable(path: Path) -> None:
    """``CheckpointError`` unless a file ``path`` can be created or replaced."""

    parent = path.parent
    if path.is_dir():
        raise CheckpointError(f"checkpoint {path} is a directory; give a file path")
    if not parent.exists():
        raise CheckpointError(f"checkpoint {path} cannot be written: directory {parent} does not exist")
    if not parent.is_dir():
        raise CheckpointError(f"checkpoint {path} cannot be written: {parent} is not a directory")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise CheckpointError(f"checkpoint {path} cannot be written: no permission to write in {parent}")


def _lock(path: Path) -> int:
    """An open descriptor of ``PATH.lock`` holding its exclusive lock, with this process's pid in it."""

    lock = path.with_name(path.name + _LOCK_SUFFIX)
    while True:
        try:
            handle = os.open(lock, os.O_RDWR | os.O_CREAT, 0o644)
        except OSError as error:
            raise CheckpointError(f"checkpoint {path} cannot be written: {error.strerror} ({lock})") from None
        if fcntl is None:
            return handle
        try:
            fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            owner = os.pread(handle, 32, 0).decode("ascii", "replace").strip()
            os.close(handle)
            raise CheckpointError(
                f"checkpoint {path} is in use by another run (pid {owner if owner.isdigit() else 'unknown'}); "
                "wait for it to end, or write to another file") from None
        except OSError as error:
            os.close(handle)
            raise CheckpointError(f"checkpoint {path} cannot be locked: {error.strerror} ({lock})") from None
        if _same_file(handle, lock):
            os.ftruncate(handle, 0)
            os.pwrite(handle, f"{os.getpid()}\n".encode("ascii"), 0)
            return handle
        os.close(handle)  # its last holder removed the file meanwhile: lock the one at the path now


def _same_file(handle: int, path: Path) -> bool:
    """Whether the open ``handle`` is still the file at ``path``."""

    try:
        here, there = os.fstat(handle), os.stat(path)
    except FileNotFoundError:
        return False
    return (here.st_dev, here.st_ino) == (there.st_dev, there.st_ino)


def _unlock(path: Path, handle: int) -> None:
    """Remove the lock file (still locked, so no other run holds it) and release the lock."""

    try:
        path.with_name(path.name + _LOCK_SUFFIX).unlink(missing_ok=True)
    finally:
        os.close(handle)


class _Corrupt(Exception):
    """What is wrong with a checkpoint's content (becomes a :class:`CheckpointError`)."""


class Checkpoint:
    """
    Finished readings of a run (``done``, ``counts``, ``pilot``, ``bins``, ``sums``,
    ``seconds``), optionally mirrored in a file.
    """

    def __init__(self, path: Path | None, identity: dict[str, Any], size: int, bins: int | None = None,
                 sums: tuple[str, ...] = ()) -> None:
        self.path, self.identity = path, identity
        self.done = np.zeros(size, dtype=bool)
        self.counts, self.pilot = Counts.zeros(size), Counts.zeros(size)
        self.bins = None if bins is None else np.zeros((size, bins), dtype=np.int64)
        self.sums = {name: np.zeros(size, dtype=np.int64) for name in sums}
        self.seconds = 0.0
        self._unsaved, self._saved_at, self._save_seconds = False, time.perf_counter(), 0.0

    @classmethod
    def open(
        cls,
        path: str | os.PathLike | None,
        identity: dict[str, Any],
        size: int,
        *,
        rays: tuple[int, int],
        pilot_rays: tuple[int, int] = (0, 0),
        group: int = 1,
        bins: int | None = None,
        sums: tuple[str, ...] = (),
    ) -> "Checkpoint":
        """
        The state of a run of ``size`` readings, resumed from ``path`` when it exists.

        A finished reading has between ``rays[0]`` and ``rays[1]`` rays (its pilot
        ``pilot_rays``), ``bins`` bin counts (or none) and the per-reading ``sums``;
        readings ``k·group`` to ``(k + 1)·group − 1`` are traced together (done together,
        equal tallies). A file that breaks these, or any rule of the module docstring,
        raises :class:`CheckpointError` and is left as it is.
        """

        state = cls(Path(path) if path is not None else None, identity, size, bins, sums)
        if state.path is not None and state.path.exists():
            state._load(rays, pilot_rays, group)
        return state

    @property
    def reused(self) -> int:
        """How many readings are done (after :meth:`open`: how many were resumed)."""

        return int(self.done.sum())

    def tally(self, pilot: bool) -> Tally:
        """Every reading's tallies (finished or not), with the pilot's counts when ``pilot``, and the seconds."""

        return Tally(self.counts, self.pilot if pilot else None, self.bins, self.sums, self.seconds)

    def record(self, batch: np.ndarray, tally: Tally) -> None:
        """
        Keep the tallies of readings ``batch`` and save the file — unless saving is slow
        next to the batches (a file of many thousand readings): it is then saved once
        the time since the last save is ten times what that save took, so saving never
        costs more than about a tenth of the run. :meth:`flush` saves what is left.
        """

        self.counts.put(batch, tally.counts)
        if tally.pilot is not None:
            self.pilot.put(batch, tally.pilot)
        if self.bins is not None:
            self.bins[batch] = tally.bins
        for name, value in self.sums.items():
            value[batch] = tally.sums[name]
        self.done[batch] = True
        self.seconds += tally.seconds
        self._unsaved = self.path is not None
        if self._unsaved and time.perf_counter() - self._saved_at >= _SAVE_EVERY * self._save_seconds:
            self.flush()

    def flush(self) -> None:
        """
        Save every finished reading not saved yet (at the end of a run, or when it is
        interrupted). A save that fails (a full disk, a file size limit …) does not stop
        the run: the old file stays whole, the failure is warned about once
        (``RuntimeWarning`` naming the file and the cause), the readings stay in memory —
        the run returns them — and the next save tries again (:func:`kept_in` says where
        they are, for a later message).
        """

        if self._unsaved:
            start = time.perf_counter()
            try:
                self._save()
            except WriteError as error:
                if self.path not in _UNSAVED:
                    warnings.warn(f"checkpoint {self.path} could not be saved ({error.cause}): the run goes on, "
                                  "its finished readings kept in memory (an interruption now loses those not saved)",
                                  RuntimeWarning, stacklevel=2)
                _UNSAVED[self.path] = error.cause
                self._saved_at = time.perf_counter()
                return
            _UNSAVED.pop(self.path, None)
            self._unsaved, self._saved_at = False, time.perf_counter()
            self._save_seconds = self._saved_at - start

    def _load(self, rays: tuple[int, int], pilot_rays: tuple[int, int], group: int) -> None:
        path = self.path
        try:
            data = json.loads(path.read_text())
        except (OSError, ValueError, RecursionError) as error:  # ValueError: JSON and UTF-8 decoding
            raise CheckpointError(
                f"checkpoint {path} is corrupt ({type(error).__name__}: {error}); delete it to start the sweep over"
            ) from None
        kept = self.bins is not None or bool(self.sums)
        if isinstance(data, dict) and data.get("format") == _FORMAT_WITHOUT_BINS and kept:
            raise CheckpointError(f"checkpoint {path} was written before bins and sums were kept "
                                  f"({_FORMAT_WITHOUT_BINS!r}): it cannot resume a run with bins or sums; delete it "
                                  "to start the sweep over")
        if not isinstance(data, dict) or data.get("format") not in (_FORMAT, _FORMAT_WITHOUT_BINS):
            raise CheckpointError(f"checkpoint {path} is not a virtspec-mi sweep checkpoint of this version "
                                  f"({_FORMAT!r}); delete it to start the sweep over")
        try:
            stored = data.get("identity")
            if not isinstance(stored, dict):
                raise _Corrupt(f"identity is {type(stored).__name__}, not an object")
            self._check_identity(stored)
            done = _indices(data.get("done"), self.done.size)
            counts = _counts(data.get("counts"), "counts", len(done), rays)
            pilot = _counts(data.get("pilot"), "pilot", len(done), pilot_rays)
            bins = None if self.bins is None else _bins(data.get("bins"), len(done), self.bins.shape[1], counts.rays)
            sums = {name: _whole_numbers(_entry(data.get("sums"), name), f"sums.{name}", 0, 2**63 - 1,
                                         f"0 <= {name}") for name in self.sums}
            for name, value in sums.items():
                if len(value) != len(done):
                    raise _Corrupt(f"sums.{name} must hold one value per done reading ({len(done)})")
            seconds = data.get("seconds")
            if type(seconds) not in (int, float) or not math.isfinite(seconds) or seconds < 0:
                raise _Corrupt(f"seconds must be a finite number >= 0 (got {seconds!r})")
        except _Corrupt as reason:
            raise CheckpointError(f"checkpoint {path} is corrupt ({reason}); "
                                  "delete it to start the sweep over") from None
        self.done[done] = True
        self.counts.put(done, counts)
        self.pilot.put(done, pilot)
        if bins is not None:
            self.bins[done] = bins
        for name, value in sums.items():
            self.sums[name][done] = value
        self.seconds = float(seconds)
        if group > 1:
            self._check_groups(group)

    def _check_identity(self, stored: dict[str, Any]) -> None:
        expected = json.loads(json.dumps(self.identity))
        if stored != expected:
            keys = sorted(k for k in set(stored) | set(expected) if stored.get(k) != expected.get(k))
            raise CheckpointError(
                f"checkpoint {self.path} belongs to a different sweep (differs in: {', '.join(keys)}); "
                "re-run with the same scene and settings, or delete it to start over"
            )

    def _check_groups(self, group: int) -> None:
        """Readings traced together must be done together, with equal counts."""

        done = self.done.reshape(-1, group)
        equal = np.ones(done.shape[0], dtype=bool)
        tallies = [getattr(counts, name) for counts in (self.counts, self.pilot) for name in Counts.names()]
        tallies += [] if self.bins is None else list(self.bins.T)
        for tally in [*tallies, *self.sums.values()]:
            values = tally.reshape(-1, group)
            equal &= np.all((values == values[:, :1]) | (np.isnan(values) & np.isnan(values[:, :1]))
                            if values.dtype.kind == "f" else values == values[:, :1], axis=1)
        bad = np.flatnonzero((done.any(axis=1) & ~done.all(axis=1)) | (done.all(axis=1) & ~equal))
        if len(bad):
            first = int(bad[0]) * group
            raise CheckpointError(
                f"checkpoint {self.path} is corrupt (readings {first} to {first + group - 1} are traced together but "
                "are not all done with equal counts); delete it to start the sweep over")

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
        if self.bins is not None:
            data["bins"] = self.bins[done].tolist()
        if self.sums:
            data["sums"] = {name: value[done].tolist() for name, value in self.sums.items()}
        with atomic_file(self.path) as temporary:  # an interruption or a full disk leaves the old file
            temporary.write_text(json.dumps(data))


def _whole_numbers(values: Any, what: str, low: int, high: int, rule: str) -> np.ndarray:
    """``values`` as int64 when it is a list of whole numbers (not bools) in [low, high], else ``_Corrupt``."""

    if not isinstance(values, list):
        raise _Corrupt(f"{what} is {type(values).__name__}, not a list")
    for value in values:
        if type(value) is not int:
            raise _Corrupt(f"{what} holds {value!r}, not a whole number")
        if not low <= value <= high:
            raise _Corrupt(f"{what} holds {value}: it must satisfy {rule}")
    return np.array(values, dtype=np.int64)


def _indices(values: Any, size: int) -> np.ndarray:
    """The ``done`` list: distinct reading indices in [0, size)."""

    done = _whole_numbers(values, "done", 0, size - 1, f"0 <= index < {size}")
    if len(np.unique(done)) != len(done):
        raise _Corrupt("done holds a reading index twice: indices must be unique")
    return done


def _counts(values: Any, what: str, length: int, rays: tuple[int, int]) -> Counts:
    """The counts of the ``length`` done readings, checked against each other and ``rays``."""

    if not isinstance(values, dict):
        raise _Corrupt(f"{what} is {type(values).__name__}, not an object")
    missing = [name for name in Counts.names() if name not in values]
    if missing:
        raise _Corrupt(f"{what} lacks {', '.join(missing)}")
    for name in Counts.names():
        if not isinstance(values[name], list) or len(values[name]) != length:
            raise _Corrupt(f"{what}.{name} must hold one value per done reading ({length})")
    low, high = rays
    label = "pilot rays" if what == "pilot" else "rays"
    rule = f"{label} = {low}" if low == high else f"{low} <= {label} <= {high}"
    fields = {"rays": _whole_numbers(values["rays"], f"{what}.rays", low, high, f"{rule} (the settings')")}
    for name in Counts.names():
        if name not in ("rays", "largest_weight"):
            fields[name] = _whole_numbers(values[name], f"{what}.{name}", 0, high, f"0 <= {name} <= rays")
    fields["largest_weight"] = _weights(values["largest_weight"], f"{what}.largest_weight")
    counts = Counts(**fields)
    bounded = {"reflected": counts.rays, "transmitted": counts.rays, "capped": counts.rays,
               "weight_violations": counts.rays, "rounded_weights": counts.rays,
               "specular_reflected": counts.reflected, "regular_transmitted": counts.transmitted}
    for name, bound in bounded.items():
        if np.any(getattr(counts, name) > bound):
            limit = "rays" if bound is counts.rays else ("reflected" if name == "specular_reflected" else "transmitted")
            raise _Corrupt(f"{what}.{name} must satisfy 0 <= {name} <= {limit} for every reading")
    if np.any(counts.reflected + counts.transmitted + counts.capped > counts.rays):
        raise _Corrupt(f"{what} must satisfy reflected + transmitted + capped <= rays for every reading")
    return counts


def _entry(values: Any, name: str) -> Any:
    """``values[name]`` of the ``sums`` object (``_Corrupt`` when it is not one, or lacks it)."""

    if not isinstance(values, dict):
        raise _Corrupt(f"sums is {type(values).__name__}, not an object")
    if name not in values:
        raise _Corrupt(f"sums lacks {name}")
    return values[name]


def _bins(values: Any, length: int, size: int, rays: np.ndarray) -> np.ndarray:
    """The bin counts of the ``length`` done readings: ``size`` whole numbers >= 0 each, adding up to <= rays."""

    if not isinstance(values, list) or len(values) != length:
        raise _Corrupt(f"bins must hold one row per done reading ({length})")
    rows = []
    for row in values:
        if not isinstance(row, list) or len(row) != size:
            raise _Corrupt(f"bins must hold {size} counts per reading")
        rows.append(_whole_numbers(row, "bins", 0, 2**63 - 1, "0 <= count"))
    bins = np.array(rows, dtype=np.int64).reshape(length, size)
    if np.any(bins.sum(axis=1) > rays):
        raise _Corrupt("bins must add up to at most the reading's rays for every reading")
    return bins


def _weights(values: list, what: str) -> np.ndarray:
    """The largest violating weights: real numbers, ``None`` for none (NaN)."""

    for value in values:
        if value is not None and (type(value) not in (int, float) or math.isnan(value)):
            raise _Corrupt(f"{what} holds {value!r}, not a number or null")
    return np.array([np.nan if v is None else float(v) for v in values], dtype=np.float64)


class ResultStore:
    """
    The checkpoint of a run made of several API calls (an albedo table's groups of cells,
    a Klems file's groups of readings): each finished call's result kept as a file in a
    directory — ``identity.json`` (what the run is: a rerun of another run is refused,
    naming what differs) and one ``<16 hex>.nc`` per label, each written whole under its
    name (a temporary ``.<name>.<random>.tmp`` beside it, renamed; by :meth:`save`, or by
    the call itself given :meth:`path` as its ``out``, its own checkpoint
    ``<16 hex>.nc.partial.json`` beside it meanwhile) — so that a rerun reuses them. Held
    by one run at a time with :func:`locked`. ``what`` names the run in messages.
    """

    _OURS = re.compile(r"identity\.json|[0-9a-f]{16}\.nc(\.partial\.json)?")
    _TEMPORARY = re.compile(r"\.(identity\.json|[0-9a-f]{16}\.nc(\.partial\.json)?)\.[0-9a-z]+\.tmp")
    _KEPT = re.compile(r"[0-9a-f]{16}\.nc(\.partial\.json)?")

    def __init__(self, directory: Path | None, identity: dict[str, Any], what: str = "run") -> None:
        self.directory = directory
        self.reused = 0
        self.saved = 0
        if directory is None:
            return
        if directory.exists() and not directory.is_dir():
            raise ValueError(f"checkpoint must be a directory (got the file {directory})")
        directory.mkdir(parents=True, exist_ok=True)
        stamp = directory / "identity.json"
        text = json.dumps(identity, sort_keys=True)
        if stamp.exists():
            if stamp.read_text() != text:
                old = json.loads(stamp.read_text())
                differ = sorted(k for k in set(old) | set(identity) if old.get(k) != identity.get(k))
                raise ValueError(f"checkpoint {directory} belongs to a different {what} (differs in: "
                                 f"{', '.join(differ)}); re-run with the same settings, or delete it")
            self.saved = sum(1 for path in directory.iterdir() if self._KEPT.fullmatch(path.name)
                             and not path.name.endswith(".partial.json"))
        else:
            atomic_write(stamp, lambda tmp: Path(tmp).write_text(text))

    def path(self, label: str) -> Path | None:
        if self.directory is None:
            return None
        return self.directory / (hashlib.blake2b(label.encode(), digest_size=8).hexdigest() + ".nc")

    def load(self, label: str, read: Any) -> Any:
        """The result kept for ``label`` (``read(path)``), or ``None``."""

        path = self.path(label)
        if path is not None and path.exists():
            self.reused += 1
            return read(path)
        return None

    def save(self, label: str, result: Any) -> None:
        path = self.path(label)
        if path is not None:
            result.write(path)
            self.saved += 1

    def kept(self) -> bool:
        """Whether the folder keeps anything to resume from: a finished call's result, or a call's own checkpoint."""

        return self.directory is not None and self.directory.is_dir() and any(
            self._KEPT.fullmatch(path.name) for path in self.directory.iterdir())

    def remove(self) -> None:
        """
        Remove the folder: what this store writes (identity.json, <16 hex>.nc, a call's
        checkpoint, their temporaries), not more.
        """

        if self.directory is None:
            return
        for path in self.directory.iterdir():
            if self._OURS.fullmatch(path.name) or self._TEMPORARY.fullmatch(path.name):
                path.unlink()
        try:
            self.directory.rmdir()
        except OSError:
            pass
