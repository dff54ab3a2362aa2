"""
Files the project writes: atomic replacement, its own temporaries, write errors
===============================================================================

The bottom of the package (it imports nothing of it): how every file virtspec-mi
writes — a result file (:mod:`virtspec_mi.results.io`), a checkpoint
(:mod:`virtspec_mi.engine.checkpoint`), a Zarr store (:mod:`virtspec_mi.results.zarr`) —
reaches the disk, written once:

- :func:`atomic_file`: a new file is written into a temporary beside its name, created
  here (``O_EXCL``: never a file that was already there), flushed to disk and renamed
  onto the name in one step. A failure or an interruption leaves the old file (or none)
  and removes the temporary — the only file it removes, since it created it;
- :class:`WriteError`: what a failed write raises, an ``OSError`` whose one-line message
  names the path and the cause (:func:`cause_of`: "No space left on device (12.0 kB
  free)", "File too large", "Permission denied" …) and, when the caller knows it, where
  the readings that were being written are kept (:attr:`WriteError.kept`), with the
  object itself attached (:attr:`WriteError.result`: a result whose file could not be
  written is not lost with the file).

Nothing here removes a file or a directory it did not create. :func:`check_distinct`: the
one rule every command and API function that writes applies before any work — no output
path may be (by its name, a symbolic link, a hard link or a case-insensitive file system)
an input of the call or another output of it. And one reader:
:func:`read_netcdf` (a NetCDF file whole in memory, or a ``ValueError`` naming the file
and what it holds instead — never xarray's list of backends or a bare library text).

References
----------
POSIX ``rename(2)`` (atomic replacement within a file system), ``open(2)`` (``O_EXCL``),
``fsync(2)``.
"""

from __future__ import annotations

import errno
import os
import shutil
import uuid
from contextlib import contextmanager
from pathlib import Path
from typing import Any, Callable, Iterable, Iterator

__all__ = ["WriteError", "IN_MEMORY", "atomic_file", "atomic_write", "cause_of", "temporary_name", "flush_directory",
           "read_netcdf", "same_file", "check_distinct", "check_name_length", "shown_path", "os_error_text"]

_FULL = 1 << 20  # a write failing with less free space than this is reported as a full disk

IN_MEMORY: str = "the readings are kept in memory only (error.result)"
"""The end of :attr:`WriteError.kept` when what was being written is nowhere else (the command line then saves it)."""


class WriteError(OSError):
    """
    A file could not be written: ``path``, ``cause`` (in words) and, when known, where
    the readings being written are kept (``kept``) and the object that was being written
    (``result``: e.g. the :class:`~virtspec_mi.results.readings.Result` whose file
    failed, still whole in memory). ``errno`` is the cause's (e.g. ``errno.ENOSPC``).
    """

    def __init__(self, path: str | os.PathLike, cause: str, *, code: int | None = None, kept: str = "",
                 result: Any = None) -> None:
        self.path, self.cause, self.kept, self.result = Path(path), cause, kept, result
        super().__init__(code, self._message())
        self.filename = str(path)

    def _message(self) -> str:
        return f"could not write {shown_path(self.path)}: {self.cause}" + (f"; {self.kept}" if self.kept else "")

    def __str__(self) -> str:
        return self._message()

    def keeping(self, kept: str, result: Any = None) -> "WriteError":
        """The same error saying where the readings are kept (and holding ``result``, if given)."""

        return WriteError(self.path, self.cause, code=self.errno, kept=kept,
                          result=self.result if result is None else result)


def shown_path(path: Any, limit: int = 160) -> str:
    """
    A path as a message shows it: whole up to ``limit`` characters, else its start and its
    end around "…" and its length (a 5,000-character name is not echoed whole).
    """

    text = os.fsdecode(path) if isinstance(path, (bytes, os.PathLike)) else str(path)
    if len(text) <= limit:
        return text
    return f"{text[:limit - 40]}…{text[-30:]} ({len(text):,} characters)"


def check_name_length(name: str, path: Any) -> None:
    """
    Refuse (``ValueError`` naming ``name``, the limit and the fix) a path the file system
    cannot name — a part longer than its longest file name (``NAME_MAX``, 255 on most) or
    the whole longer than its longest path (``PATH_MAX``) — before any file is opened, the
    path shown shortened (:func:`shown_path`), never echoed whole. Not a path: left alone.
    """

    if not isinstance(path, (str, os.PathLike)):
        return
    text = os.fsdecode(path)
    try:
        most, whole = os.pathconf(_existing(Path(text)), "PC_NAME_MAX"), os.pathconf("/", "PC_PATH_MAX")
    except (OSError, ValueError, AttributeError):
        most, whole = 255, 4096
    longest = max(Path(text).parts, key=len, default="")
    if len(os.fsencode(longest)) > most:
        raise ValueError(f"{name}: a file or folder name holds at most {most} bytes here (got "
                         f"{shown_path(longest)}, {len(os.fsencode(longest)):,} bytes); give a shorter name")
    if len(os.fsencode(text)) >= whole:
        raise ValueError(f"{name}: a path holds fewer than {whole} bytes here (got {shown_path(text)}, "
                         f"{len(os.fsencode(text)):,} bytes); give a shorter path")


def _existing(path: Path) -> Path:
    """The nearest folder of ``path`` that exists (the file system whose limits apply)."""

    for folder in [path.parent, *path.parent.parents] if not path.is_absolute() else path.parents:
        try:
            if folder.is_dir():
                return folder
        except OSError:
            continue
    return Path(".")


def os_error_text(error: OSError) -> str:
    """An ``OSError`` in one line: its reason and the file(s) it names (:func:`shown_path`), never a bare errno."""

    if error.strerror and error.filename is not None:
        names = " -> ".join(shown_path(name) for name in (error.filename, error.filename2) if name is not None)
        return f"{error.strerror}: {names}"
    return str(error)


def cause_of(error: BaseException, path: str | os.PathLike) -> tuple[str, int | None]:
    """
    ``(cause in words, errno or None)`` of a failed write of ``path``: the system's reason
    (lower case), and, when the disk holding ``path`` is nearly full, that too (some
    writers, e.g. the NetCDF library, report a full disk as a generic error).
    """

    code = getattr(error, "errno", None)
    reason = getattr(error, "strerror", None) or str(error) or type(error).__name__
    reason = " ".join(str(reason).split())
    free = _free_bytes(Path(path))
    if free is not None and free < _FULL:  # some libraries report a full disk as another error (HDF5: EACCES)
        code = errno.ENOSPC if code is None else code
        full = "space" in reason or "quota" in reason
        reason = f"{reason} ({_size(free)} free)" if full else f"{reason} (the disk is full: {_size(free)} free)"
    elif code in (errno.EFBIG, None) and _size_limit() is not None:  # HDF5 reports EFBIG as another error
        reason += f" (this process may write files of at most {_size(_size_limit())}: ulimit -f)"
        code = errno.EFBIG
    return reason, code


def _size_limit() -> int | None:
    """The largest file this process may write (``RLIMIT_FSIZE``), ``None`` without a limit."""

    try:
        import resource
    except ImportError:  # not a POSIX system
        return None
    soft = resource.getrlimit(resource.RLIMIT_FSIZE)[0]
    return None if soft == resource.RLIM_INFINITY else int(soft)


def _free_bytes(path: Path) -> int | None:
    for folder in (path.parent, *path.parents):
        try:
            return shutil.disk_usage(folder).free
        except OSError:
            continue
    return None


def _size(count: int) -> str:
    for unit, scale in (("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if count >= scale:
            return f"{count / scale:.1f} {unit}"
    return f"{count} bytes"


def temporary_name(path: Path, suffix: str = ".tmp") -> Path:
    """A fresh hidden name beside ``path`` for a temporary of it: ``.NAME.<random>.tmp``."""

    return path.with_name(f".{path.name}.{uuid.uuid4().hex[:12]}{suffix}")


@contextmanager
def atomic_file(path: str | os.PathLike) -> Iterator[Path]:
    """
    A temporary file beside ``path`` (created here, empty, with the umask's permissions)
    for the block to write; when the block ends it is flushed to disk and renamed onto
    ``path`` in one step. If anything fails (the block, the flush, the rename — a full
    disk, a file size limit, Ctrl-C), the temporary is removed and ``path`` keeps its old
    content (or stays absent); an ``OSError`` or a writer's ``RuntimeError`` (the NetCDF
    library's) becomes a :class:`WriteError` naming ``path`` and the cause.
    """

    path = Path(path)
    temporary = temporary_name(path)
    try:
        os.close(os.open(temporary, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666))
    except OSError as error:
        cause, code = cause_of(error, path)
        raise WriteError(path, cause, code=code) from None
    try:
        yield temporary
        _flush(temporary)
        os.replace(temporary, path)
    except BaseException as error:
        temporary.unlink(missing_ok=True)  # ours: created above with O_EXCL
        if isinstance(error, WriteError):
            raise
        if isinstance(error, (OSError, RuntimeError)):
            cause, code = cause_of(error, path)
            raise WriteError(path, cause, code=code) from error
        raise
    flush_directory(path.parent)


def atomic_write(path: str | os.PathLike, write: Callable[[str], Any]) -> Path:
    """
    Call ``write(temporary_path)``, then rename the temporary file onto ``path``
    (:func:`atomic_file`: a temporary created here, removed on failure; a failed write —
    a full disk, a missing folder — a ``WriteError`` naming ``path``).
    """

    path = Path(path)
    with atomic_file(path) as temporary:
        write(str(temporary))
    return path


def _flush(path: Path) -> None:
    """Flush a written file to disk (a failure, e.g. a full disk, raises ``OSError``)."""

    handle = os.open(path, os.O_RDONLY)
    try:
        os.fsync(handle)
    finally:
        os.close(handle)


def flush_directory(path: Path) -> None:
    """Flush a directory's entries (a rename in it) to disk, where the system allows it."""

    try:
        _flush(path)
    except OSError:  # not every system opens or syncs directories
        pass


def same_file(first: str | os.PathLike, second: str | os.PathLike) -> bool:
    """
    Whether two paths name one file: the same path once symbolic links are resolved, or
    two existing paths of one file (a hard link, a case-insensitive file system).
    """

    if os.path.normcase(os.path.realpath(first)) == os.path.normcase(os.path.realpath(second)):
        return True
    try:
        return os.path.samefile(first, second)
    except OSError:  # one of them does not exist (yet): not the same file
        return False


def check_distinct(outputs: Iterable[tuple[str, Any]], inputs: Iterable[tuple[str, Any]] = ()) -> None:
    """
    Refuse (``ValueError``, before anything is measured or written) an output that would
    replace an input of the same call or another of its outputs: ``outputs`` and
    ``inputs`` are ``(name, path)`` pairs (the flag or parameter naming each: ``"--out"``,
    ``"measured"``; a path ``None`` or not a path — an object, a dict — is left out). A
    path the file system cannot name is refused too (:func:`check_name_length`).
    """

    def paths(pairs: Iterable[tuple[str, Any]]) -> list[tuple[str, Any]]:
        kept = [(name, path) for name, path in pairs if isinstance(path, (str, os.PathLike)) and str(path)]
        for name, path in kept:
            check_name_length(name, path)  # a name the system cannot hold: refused here, shortened
        return kept

    given, written = paths(inputs), []
    for name, path in paths(outputs):
        for other, source in given:
            if same_file(path, source):
                raise ValueError(f"{name} {path} is {other} {source}, an input of this run: writing it would "
                                 f"replace what is being read; choose another name for {name}")
        for other, earlier in written:
            if same_file(path, earlier):
                raise ValueError(f"{name} {path} is also {other} {earlier}: one output would replace the other; "
                                 f"give each output its own name")
        written.append((name, path))


def read_netcdf(path: str | os.PathLike, what: str) -> Any:
    """
    The ``xarray.Dataset`` of the NetCDF file ``path``, loaded (the file closed); a file
    that is not NetCDF (plain text, random bytes, another format) or cannot be read is a
    ``ValueError`` naming ``what`` it should be, the path and the cause.
    """

    import xarray as xr

    path = Path(path)
    if not path.is_file():
        raise ValueError(f"{what} {path} is not a file")
    with open(path, "rb") as handle:
        magic = handle.read(8)
    if not (magic.startswith(b"CDF") or magic.startswith(b"\x89HDF\r\n\x1a\n")):
        text = bool(magic) and all(32 <= b < 127 or b in b"\t\r\n" for b in magic)
        holds = "plain text" if text else "its first bytes are not those of NetCDF or HDF5"
        raise ValueError(f"{what} {path} is not a NetCDF file ({holds}); give the .nc file virtspec-mi wrote")
    try:
        with xr.open_dataset(path, engine="netcdf4") as dataset:
            return dataset.load()
    except (OSError, ValueError, RuntimeError, KeyError, IndexError, TypeError) as error:
        raise ValueError(f"{what} {path} could not be read as NetCDF ({type(error).__name__}: {error})") from None
