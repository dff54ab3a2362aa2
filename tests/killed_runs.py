"""
A real measuring process killed with SIGKILL mid-run, then run again (tests of checkpoints),
or signalled with SIGINT/SIGTERM (tests of interrupts); a scene of a rough dielectric.
"""

from __future__ import annotations

import json
import signal
import subprocess
import time
from pathlib import Path

from virtspec_mi.engine.checkpoint import checkpoint_for


def default_signals() -> None:
    """
    A ``preexec_fn``: the child starts with SIGINT and SIGTERM at their default disposition, whatever this
    process has (``make test`` started as a background job from a script runs with SIGINT ignored, and a
    child inherits that: a test sending SIGINT must not depend on it).
    """

    for signum in (signal.SIGINT, signal.SIGTERM):
        signal.signal(signum, signal.SIG_DFL)


def kill_then_resume(command: list[str], out: Path, readings: int, cwd: Path) -> None:
    """
    Run ``command`` (which writes ``out``), SIGKILL it once its checkpoint
    ``OUT.partial.json`` exists, check that it held some but not all of the ``readings``
    and that ``out`` was not written, then run it again to completion: ``out`` written,
    the checkpoint removed.
    """

    partial = checkpoint_for(out)
    process = subprocess.Popen(command, cwd=cwd, preexec_fn=default_signals)
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


def signal_when_kept(command: list[str], out: Path, signum: int, cwd: Path, ignore_sigint: bool = False,
                     wait: float = 0.5) -> tuple[subprocess.CompletedProcess, float]:
    """
    Run ``command``; once its checkpoint holds a finished reading, wait ``wait`` s (a kernel under way) and send
    ``signum``; returns the finished process (stderr text) and the seconds it took to exit after the signal.
    """

    partial = checkpoint_for(out)
    setup = (lambda: (default_signals(), signal.signal(signal.SIGINT, signal.SIG_IGN))) if ignore_sigint else \
        default_signals
    process = subprocess.Popen(command, cwd=cwd, stderr=subprocess.PIPE, text=True, preexec_fn=setup)
    deadline = time.monotonic() + 300
    while not partial.exists() and process.poll() is None and time.monotonic() < deadline:
        time.sleep(0.01)
    time.sleep(wait)
    assert process.poll() is None, f"the run ended before it could be interrupted: {process.stderr.read()}"
    sent = time.monotonic()
    process.send_signal(signum)
    _, stderr = process.communicate(timeout=120)
    return subprocess.CompletedProcess(command, process.returncode, "", stderr), time.monotonic() - sent


ROUGH_XML = """<scene version="3.0.0">
    <shape type="disk" id="emitter"><transform name="to_world"><rotate x="1" angle="180"/><scale value="8"/>
        <translate z="100"/></transform></shape>
    <shape type="disk" id="specimen"><transform name="to_world"><scale value="12.5"/></transform>
        <bsdf type="roughdielectric"><float name="alpha" value="0.3"/><float name="int_ior" value="1.5"/></bsdf></shape>
</scene>"""
"""A scene of Mitsuba's rough dielectric (alpha = 0.3, eta = 1.5) in the paper's instrument, as an XML file's text."""


class Interrupting:
    """
    ``owner.name`` replaced (through ``monkeypatch``) by a call that raises
    ``KeyboardInterrupt`` — a Ctrl-C at that point — once it has been called ``after``
    times (``after = -1``: never); :attr:`calls` counts the calls that went through.
    """

    def __init__(self, monkeypatch, owner, name: str, after: int) -> None:
        self.original, self.after, self.calls = getattr(owner, name), after, 0
        monkeypatch.setattr(owner, name, self)

    def __call__(self, *args, **kwargs):
        if self.calls == self.after:
            raise KeyboardInterrupt
        self.calls += 1
        return self.original(*args, **kwargs)
