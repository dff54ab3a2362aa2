"""
Interrupts: SIGINT and SIGTERM honoured at safe points, within about a second
=============================================================================

A long run — a sweep, a goniophotometer or sphere reading, in this process or on Dask
workers — stops on SIGINT (Ctrl-C) or SIGTERM (``kill``) at its next *safe point*:
between two kernel launches (a Dr.Jit kernel cannot be stopped, and an exception raised
inside Dr.Jit's tracing, a file write or Dask's machinery would come out as another
error, or be lost), after a batch, or while it waits for Dask workers. Kernel launches
are bounded in time (:data:`virtspec_mi.kernel.tracer.CHUNK_SECONDS`), so the next safe
point comes within about a second. The run then saves its checkpoint and raises
:class:`Interrupted`, which names the signal and the checkpoint to resume from.

- :func:`catching` — the command line's, for a whole command: SIGINT and SIGTERM become
  :class:`Interrupted` — at once outside a run, at the next safe point inside one —
  whatever their disposition was (a process started in the background by a shell
  inherits SIGINT *ignored*, which made a sweep run on to the end and exit 0).
- :func:`deferred` — the engine's, around a run: a signal received during it waits for
  the next :func:`check`. In a program that does not call :func:`catching` (the Python
  API) it takes over SIGINT and SIGTERM for the run where they have Python's default
  handlers (main thread only): a SIGINT then comes out as Python's own
  ``KeyboardInterrupt`` (its message naming the checkpoint), a SIGTERM ends the process
  as it would have — each once the checkpoint is saved.
- :func:`check` — a safe point: raises :class:`Interrupted` for a signal received (and,
  once more, for one raised where the program was: if that ``KeyboardInterrupt`` was
  swallowed on its way — raised inside an import lock's callback, Python prints
  "Exception ignored" and goes on — the run still stops here; so does a run that starts
  after it, :func:`deferred`).
- :func:`stop_now` / :func:`stopping_at_once` — the command's handler before its own
  handling begins (from the first line of the package, when it is the ``virtspec``
  command) and after it ends: one line and the signal's exit status, at once.

A second signal while one waits for its safe point acts at once.
"""

from __future__ import annotations

import os
import signal
import sys
import threading
from contextlib import contextmanager
from pathlib import Path
from typing import Any, Iterator

__all__ = ["SIGNALS", "Interrupted", "catching", "deferred", "check", "exit_status", "received", "stop_now",
           "stopping_at_once"]

SIGNALS: tuple[int, ...] = (signal.SIGINT, signal.SIGTERM)
"""The signals that stop a run."""


class Interrupted(KeyboardInterrupt):
    """
    A run stopped by a signal (a ``KeyboardInterrupt``, so code that catches Ctrl-C still
    does): ``signum``, and ``checkpoint`` — the file that keeps every finished reading
    (``None`` when the run had none) — set by the run that saved it.
    """

    def __init__(self, signum: int = signal.SIGINT, checkpoint: Path | None = None) -> None:
        super().__init__(signum)
        self.signum = int(signum)
        self.checkpoint = checkpoint

    @property
    def name(self) -> str:
        """The signal's name: ``SIGINT``, ``SIGTERM``."""

        return signal.Signals(self.signum).name

    @property
    def kept(self) -> bool:
        """True when the checkpoint exists (at least one reading had finished)."""

        return self.checkpoint is not None and Path(self.checkpoint).exists()

    def __str__(self) -> str:
        if self.kept:
            return (f"interrupted by {self.name}: every finished reading is kept in {self.checkpoint}; run the same "
                    "call again to resume")
        return f"interrupted by {self.name}" + ("" if self.checkpoint is None else ": no reading had finished")


def exit_status(signum: int) -> int:
    """The exit status of a command stopped by ``signum``: 128 + signum (130 for SIGINT, 143 for SIGTERM)."""

    return 128 + int(signum)


def stop_now(signum: int, frame: Any) -> None:
    """
    The command's handler outside its own handling (while Python imports the package, while
    it shuts down): nothing is being written, so stop at once — one line, the signal's exit
    status, no traceback (a ``KeyboardInterrupt`` raised then can also be swallowed, inside
    an import lock's callback, and the command run on to the end).
    """

    word = b"interrupted" if signum == signal.SIGINT else b"terminated by " + signal.Signals(signum).name.encode()
    os.write(2, b"virtspec: " + word + b"\n")
    os._exit(128 + signum)


def stopping_at_once() -> None:
    """SIGINT and SIGTERM handled by :func:`stop_now` (main thread only), whatever their disposition was."""

    if _main_thread():
        for signum in SIGNALS:
            signal.signal(signum, stop_now)


class _State:
    pending: int | None = None
    """A signal received inside a run, waiting for its safe point."""
    depth: int = 0
    """Runs under way (nested: a sweep of sweeps)."""
    catching: bool = False
    """The command line catches SIGINT and SIGTERM for its whole command."""
    received: int | None = None
    """The last signal received under :func:`catching` (kept: an interrupt raised inside an import or a C
    extension may come out as another error, e.g. ``SystemError``, or be swallowed by a library)."""
    unanswered: int | None = None
    """A signal whose :class:`Interrupted` was raised where the program was (outside a run): raised again at the
    next safe point, in case it was swallowed on its way (inside an import lock's callback Python ignores it)."""


def _handler(signum: int, frame: Any) -> None:
    """Inside a run: keep the signal for the next safe point (a second one acts at once); outside: stop now."""

    _State.received = signum
    if _State.depth > 0 and _State.pending is None:
        _State.pending = signum
        return
    _State.pending = None
    if _State.catching:  # the command's: raised where the program is, and again at the next safe point if swallowed
        _State.unanswered = signum
    raise Interrupted(signum)


def _main_thread() -> bool:
    return threading.current_thread() is threading.main_thread()


@contextmanager
def catching() -> Iterator[None]:
    """The command line's: SIGINT and SIGTERM become :class:`Interrupted` for the whole command (see the module)."""

    if not _main_thread():
        yield
        return
    previous = {s: signal.getsignal(s) for s in SIGNALS}
    _State.catching, _State.pending, _State.received, _State.unanswered = True, None, None, None  # none lost
    for s in SIGNALS:
        signal.signal(s, _handler)
    try:
        yield
    finally:
        for s, handler in previous.items():
            signal.signal(s, handler)
        _State.catching, _State.pending, _State.received, _State.unanswered = False, None, None, None


@contextmanager
def deferred() -> Iterator[None]:
    """
    The engine's, around a run: signals wait for the next :func:`check` (see the module).
    A SIGTERM taken over here (not under :func:`catching`) ends the process after the run
    has cleaned up, with the status a SIGTERM gives.
    """

    if _State.unanswered is not None:  # raised outside a run and swallowed on its way (an import's callback)
        signum, _State.unanswered = _State.unanswered, None
        raise Interrupted(signum)
    taken = []
    if not _State.catching and _main_thread():
        for s, default in ((signal.SIGINT, signal.default_int_handler), (signal.SIGTERM, signal.SIG_DFL)):
            if signal.getsignal(s) is default:
                signal.signal(s, _handler)
                taken.append((s, default))
    _State.depth += 1
    ended: Interrupted | None = None
    try:
        yield
        check()  # a signal that came after the last safe point
    except Interrupted as stop:
        took = {s for s, _ in taken}
        if stop.signum == signal.SIGTERM and signal.SIGTERM in took:
            ended = stop
        elif stop.signum == signal.SIGINT and signal.SIGINT in took:
            # Python's own KeyboardInterrupt, as without us (an unhandled one exits with SIGINT's status),
            # its message naming the checkpoint
            plain = KeyboardInterrupt(str(stop))
            plain.signum, plain.checkpoint = stop.signum, stop.checkpoint  # type: ignore[attr-defined]
            raise plain.with_traceback(stop.__traceback__) from None
        raise
    finally:
        _State.depth -= 1
        if _State.depth == 0:
            _State.pending = None
        for s, default in taken:
            signal.signal(s, default)
        if ended is not None:  # as the default SIGTERM would have, once the checkpoint is saved
            print(f"virtspec-mi: {ended}", file=sys.stderr, flush=True)
            os.kill(os.getpid(), signal.SIGTERM)


def received() -> int | None:
    """
    The signal received under :func:`catching` (``None`` if none): an error that comes out of a command after
    one (an interrupt raised inside an import of a C extension becomes ``SystemError`` or ``NameError``) is
    that interrupt.
    """

    return _State.received


def check() -> None:
    """A safe point: raise :class:`Interrupted` if a signal was received (else nothing; microseconds)."""

    if _State.pending is not None:
        signum, _State.pending, _State.unanswered = _State.pending, None, None
        raise Interrupted(signum)
    if _State.unanswered is not None:  # raised outside a run and swallowed on its way: raised again, once
        signum, _State.unanswered = _State.unanswered, None
        raise Interrupted(signum)
