"""
``ast.parse`` for the tests that read the package's source (architecture, seam, rules).

CPython 3.11.7 can refuse every later ``ast.parse`` in a process once a ``RecursionError``
was raised inside C code there (``SystemError: AST constructor recursion depth mismatch``;
the result-file fuzz tests raise such errors on purpose, and a pytest-xdist worker may run
them first). :func:`parse` then parses in a fresh interpreter and hands the tree back.
"""

from __future__ import annotations

import ast
import pickle
import subprocess
import sys

__all__ = ["parse"]

_FRESH = ("import ast, pickle, sys; "
          "sys.stdout.buffer.write(pickle.dumps(ast.parse(sys.stdin.buffer.read().decode('utf-8'))))")


def parse(source: str) -> ast.Module:
    """The module tree of ``source``, as ``ast.parse`` gives it (in a fresh interpreter if this one refuses)."""

    try:
        return ast.parse(source)
    except SystemError:
        done = subprocess.run([sys.executable, "-c", _FRESH], input=source.encode("utf-8"), capture_output=True,
                              check=True)
        return pickle.loads(done.stdout)
