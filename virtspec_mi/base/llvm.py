"""
libLLVM selection for Dr.Jit's LLVM backend
===========================================

Dr.Jit 1.5 compiles its CPU kernels with the system's libLLVM. Under libLLVM 14, 15
and 16 it aborts the *whole process* (``LLVM ERROR: Cannot select: ... fminimum``)
the first time a kernel uses ``dr.minimum``/``dr.maximum``; libLLVM 19 works. This
module finds a working library, points Dr.Jit at it through ``DRJIT_LIBLLVM_PATH``
*before* Dr.Jit initialises, and refuses a bad one with an error that names the fix.

It imports nothing heavy, so ``python -m virtspec_mi.base.llvm`` can run from the
project's set-up before anything else:

- ``python -m virtspec_mi.base.llvm find``: print the library that would be used; exit 1
  when there is none (set-up then installs Debian's ``libllvm19``).
- ``python -m virtspec_mi.base.llvm check``: load Dr.Jit with it and check the version.
"""

from __future__ import annotations

import glob
import os
import re
import sys
from pathlib import Path

__all__ = [
    "MINIMUM_LLVM_MAJOR",
    "LLVMError",
    "candidate_libraries",
    "find_libllvm",
    "select_libllvm",
    "check_loaded_llvm",
    "main",
]

MINIMUM_LLVM_MAJOR: int = 17
"""Oldest libLLVM major version accepted: 14, 15 and 16 abort Dr.Jit 1.5; 19 is tested."""

_SEARCH_PATTERNS = (
    "/usr/lib/x86_64-linux-gnu/libLLVM*.so*",
    "/usr/lib/aarch64-linux-gnu/libLLVM*.so*",
    "/usr/lib/llvm-*/lib/libLLVM*.so*",
    "/usr/lib64/libLLVM*.so*",
    "/usr/lib/libLLVM*.so*",
    "/usr/local/lib/libLLVM*.so*",
)

_FIX = (
    "Install a working libLLVM (Debian/Ubuntu: 'sudo apt-get install libllvm19'; Fedora: 'sudo dnf install "
    "llvm-libs'; macOS: 'brew install llvm'; in a checkout 'make setup' does it) and, if it is not found "
    "automatically, point DRJIT_LIBLLVM_PATH at it, e.g. DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1 "
    "or DRJIT_LIBLLVM_PATH=$(brew --prefix llvm)/lib/libLLVM.dylib; then 'virtspec llvm check' (the manual's "
    "installation page)"
)


class LLVMError(RuntimeError):
    """No working libLLVM is available to Dr.Jit's LLVM backend."""


def _major_from_name(path: str) -> int | None:
    """Major version written in a libLLVM file name (``libLLVM-15.so.1``, ``libLLVM.so.19.1``)."""

    name = os.path.basename(path)
    match = re.match(r"libLLVM-(\d+)", name) or re.match(r"libLLVM\.so\.(\d+)", name)
    if match is None:
        match = re.search(r"llvm-(\d+)", path)
    return int(match.group(1)) if match else None


def candidate_libraries() -> list[tuple[int, str]]:
    """All libLLVM files found in the usual places, as ``(major, path)``, newest first."""

    found: dict[str, tuple[int, str]] = {}
    for pattern in _SEARCH_PATTERNS:
        for path in glob.glob(pattern):
            major = _major_from_name(path)
            real = os.path.realpath(path)
            if major is not None and os.path.isfile(real) and real not in found:
                found[real] = (major, path)
    return sorted(found.values(), key=lambda item: (-item[0], len(item[1])))


def find_libllvm() -> str | None:
    """Path of the newest libLLVM with major version ≥ :data:`MINIMUM_LLVM_MAJOR`, or ``None``."""

    for major, path in candidate_libraries():
        if major >= MINIMUM_LLVM_MAJOR:
            return path
    return None


def select_libllvm() -> str:
    """
    Point ``DRJIT_LIBLLVM_PATH`` at a working libLLVM before Dr.Jit initialises.

    A path the user already set is kept (and checked once Dr.Jit has loaded it); otherwise
    the newest acceptable library found is chosen.

    Raises
    ------
    LLVMError
        When no acceptable library can be found.
    """

    chosen = os.environ.get("DRJIT_LIBLLVM_PATH")
    if chosen:
        if not Path(chosen).exists():
            raise LLVMError(f"DRJIT_LIBLLVM_PATH={chosen!r} does not exist. {_FIX}.")
        return chosen
    chosen = find_libllvm()
    if chosen is None:
        versions = ", ".join(str(major) for major, _ in candidate_libraries()) or "none"
        raise LLVMError(
            f"No working libLLVM found (found major versions: {versions}; Dr.Jit 1.5 needs "
            f">= {MINIMUM_LLVM_MAJOR}: 14, 15 and 16 abort with 'Cannot select ... fminimum'). "
            f"{_FIX}."
        )
    os.environ["DRJIT_LIBLLVM_PATH"] = chosen
    return chosen


def check_loaded_llvm() -> tuple[int, int, int]:
    """
    Check the libLLVM version Dr.Jit actually loaded; refuse a bad one before any kernel runs.

    Raises
    ------
    LLVMError
        When Dr.Jit could not load libLLVM or loaded a version that aborts on use.
    """

    import drjit as dr

    version = tuple(dr.detail.llvm_version())
    path = os.environ.get("DRJIT_LIBLLVM_PATH", "(Dr.Jit's own choice)")
    if version[0] < 0:
        raise LLVMError(f"Dr.Jit could not load libLLVM from {path}. {_FIX}.")
    if version[0] < MINIMUM_LLVM_MAJOR:
        raise LLVMError(
            f"Dr.Jit loaded libLLVM {'.'.join(map(str, version))} from {path}; Dr.Jit 1.5 "
            f"needs libLLVM >= {MINIMUM_LLVM_MAJOR} (older versions abort the process with "
            f"'LLVM ERROR: Cannot select ... fminimum'). {_FIX}."
        )
    return version  # type: ignore[return-value]


def main(argv: list[str]) -> int:
    """``find`` or ``check`` (``virtspec llvm …`` and ``make setup`` call it); returns the exit status."""

    command = argv[0] if argv else "check"
    if command == "find":
        path = find_libllvm()
        if path is None:
            print("no libLLVM >= %d found" % MINIMUM_LLVM_MAJOR, file=sys.stderr)
            return 1
        print(path)
        return 0
    if command == "check":
        try:
            select_libllvm()
            version = check_loaded_llvm()
        except LLVMError as error:
            print(f"error: {error}", file=sys.stderr)
            return 1
        print(f"libLLVM {'.'.join(map(str, version))} at {os.environ['DRJIT_LIBLLVM_PATH']}")
        return 0
    print("usage: virtspec llvm {find,check}", file=sys.stderr)
    return 2


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
