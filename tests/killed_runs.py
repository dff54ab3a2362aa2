"""
A real measuring process killed with SIGKILL mid-run, then run again (tests of checkpoints).
"""

from __future__ import annotations

import json
import signal
import subprocess
import time
from pathlib import Path

from virtspec_mi.engine.checkpoint import checkpoint_for


def kill_then_resume(command: list[str], out: Path, readings: int, cwd: Path) -> None:
    """
    Run ``command`` (which writes ``out``), SIGKILL it once its checkpoint
    ``OUT.partial.json`` exists, check that it held some but not all of the ``readings``
    and that ``out`` was not written, then run it again to completion: ``out`` written,
    the checkpoint removed.
    """

    partial = checkpoint_for(out)
    process = subprocess.Popen(command, cwd=cwd)
    deadline = time.monotonic() + 120
    while not partial.exists() and process.poll() is None and time.monotonic() < deadline:
        time.sleep(0.005)
    process.send_signal(signal.SIGKILL)
    process.wait()
    assert process.returncode == -signal.SIGKILL, "the run ended before it could be interrupted"
    done = len(json.loads(partial.read_text())["done"])
    assert 0 < done < readings and not out.exists()
    subprocess.run(command, cwd=cwd, check=True)
    assert out.is_file() and not partial.exists()
