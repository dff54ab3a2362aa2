"""
``python -m virtspec_mi`` and the ``virtspec`` command (:func:`run`): the command line of
:mod:`virtspec_mi.cli`, with SIGINT and SIGTERM taken before anything else is imported.

A Ctrl-C before the command line's own handling begins (while Python imports the
package) or after it ends (while the interpreter shuts down, where a ``KeyboardInterrupt``
prints a traceback or aborts) ends the process at once with one line and the exit status
of the signal (130, 143): nothing is being written then.
"""

import atexit
import os
import signal
import sys

__all__ = ["run"]


def _stop_now(signum: int, frame: object) -> None:
    """Outside the command: nothing to save, so stop at once (no traceback, the signal's exit status)."""

    word = b"interrupted" if signum == signal.SIGINT else b"terminated by " + signal.Signals(signum).name.encode()
    os.write(2, b"virtspec: " + word + b"\n")
    os._exit(128 + signum)


def run() -> None:
    """The ``virtspec`` command: :func:`virtspec_mi.cli.main` between two signal handlers that stop at once."""

    for signum in (signal.SIGINT, signal.SIGTERM):
        signal.signal(signum, _stop_now)
    from virtspec_mi.cli import main

    status = main()
    # The command is done: end here, the exit functions run under the handlers above, instead of in the
    # interpreter's shutdown (Dr.Jit's included), where Python gives SIGINT back its default action (the
    # process killed without a word) or a KeyboardInterrupt aborts it ("Fatal Python error").
    try:
        atexit._run_exitfuncs()
        for stream in (sys.stdout, sys.stderr):
            stream.flush()
    except BrokenPipeError:  # virtspec bounds | head
        pass
    os._exit(status if isinstance(status, int) else 1)


if __name__ == "__main__":
    run()
