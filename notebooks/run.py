"""
Execute the notebooks of this folder (the paper reproduced)
===========================================================

``python notebooks/run.py [--size quick|full] [--inplace] [NAME ...]``

Each notebook reads its size from the environment variable
``VIRTSPEC_NOTEBOOK_SIZE``: ``full`` (the default when a reader runs it) uses the
paper's ray densities; ``quick`` uses a reduced size so the test suite stays fast.
``--inplace`` writes the executed notebook (with outputs) back; this is how the
committed notebooks are produced (``make notebooks`` runs them at full size).
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

__all__ = ["NOTEBOOKS", "SIZE_VARIABLE", "execute"]

HERE = Path(__file__).resolve().parent
NOTEBOOKS: list[Path] = sorted(HERE.glob("[0-9][0-9]_*.ipynb"))
SIZE_VARIABLE = "VIRTSPEC_NOTEBOOK_SIZE"


def execute(path: Path, size: str, inplace: bool = False, timeout: int = 1800):
    """Run ``path`` top to bottom at ``size`` and return the executed notebook."""

    import nbformat
    from nbclient import NotebookClient

    if size not in ("quick", "full"):
        raise ValueError(f"size must be 'quick' or 'full' (got {size!r})")
    notebook = nbformat.read(path, as_version=4)
    previous = os.environ.get(SIZE_VARIABLE)
    os.environ[SIZE_VARIABLE] = size
    try:
        NotebookClient(notebook, timeout=timeout, kernel_name="python3",
                       resources={"metadata": {"path": str(path.parent)}}).execute()
    finally:
        if previous is None:
            os.environ.pop(SIZE_VARIABLE, None)
        else:
            os.environ[SIZE_VARIABLE] = previous
    if inplace:
        notebook.metadata["virtspec"] = {"size": size}
        nbformat.write(notebook, path)
    return notebook


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument("--size", default="full", choices=["quick", "full"])
    parser.add_argument("--inplace", action="store_true", help="write outputs back into the notebook")
    parser.add_argument("names", nargs="*", help="notebook names (default: all)")
    args = parser.parse_args(argv)
    chosen = [p for p in NOTEBOOKS if not args.names or any(n in p.name for n in args.names)]
    for path in chosen:
        start = time.perf_counter()
        execute(path, args.size, args.inplace)
        print(f"{path.name}: {time.perf_counter() - start:.1f} s ({args.size})", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
