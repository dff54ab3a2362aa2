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
import sys

from virtspec_mi.base.interrupts import stopping_at_once

__all__ = ["run"]


def run() -> None:
    """The ``virtspec`` command: :func:`virtspec_mi.cli.main` between two signal handlers that stop at once."""

    stopping_at_once()  # (already since the package's first line when run as the command: virtspec_mi/__init__.py)
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
