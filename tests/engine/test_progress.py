"""
One progress bar per run (issue 42, new-user item 1): nested bars move the outermost one
within the step it announced, the bar is drawn in a terminal with updates between a
batch's start and its end (a sweep, the integrating sphere, the goniophotometer), and
nothing is drawn with ``--quiet`` or off a terminal.
"""

from __future__ import annotations

import fcntl
import os
import pty
import re
import select
import struct
import subprocess
import sys
import termios
import time
from pathlib import Path

import pytest

import virtspec_mi.engine.progress as progress
from virtspec_mi.engine.progress import Progress, expect, finished

ROOT = Path(__file__).resolve().parents[2]

# The command line as installed, with the bar's 2 s threshold lowered so that a run of a
# second counts as long (the threshold itself: test_the_threshold_decides_when_nothing_was_asked).
CHILD = ("import sys; import virtspec_mi.engine.progress as p; p._PROGRESS_AFTER_S = 0.2; "
         "from virtspec_mi.cli import main; sys.exit(main(sys.argv[1:]))")
SWEEP = ["sweep", "soybean_abmb", "--theta-i", "0", "30", "--wavelengths", "450", "650", "--rays", "20000000",
         "--chunk-size", "1048576"]
SHORT = [*SWEEP[:-4], "--rays", "5000000"]  # about a second on a quiet machine: over the lowered threshold


def _env() -> dict[str, str]:
    return {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]),
            "COLUMNS": "100"}


def _in_a_terminal(argv: list[str], timeout: float = 240.0) -> tuple[str, int]:
    """Run the command line in a pseudo-terminal (stdout and stderr both the terminal): all it drew, and its status."""

    pid, fd = pty.fork()
    if pid == 0:  # the child: the command line
        os.execve(sys.executable, [sys.executable, "-c", CHILD, *argv], _env())
    fcntl.ioctl(fd, termios.TIOCSWINSZ, struct.pack("HHHH", 24, 100, 0, 0))  # a terminal 100 columns wide
    chunks, deadline = [], time.monotonic() + timeout
    try:
        while time.monotonic() < deadline:
            ready, _, _ = select.select([fd], [], [], 1.0)
            if not ready:
                continue
            try:
                data = os.read(fd, 65536)
            except OSError:  # the child closed the terminal
                break
            if not data:
                break
            chunks.append(data)
    finally:
        os.close(fd)
    _, status = os.waitpid(pid, 0)
    return b"".join(chunks).decode("utf-8", "replace"), os.waitstatus_to_exitcode(status)


def _percentages(text: str, desc: str) -> list[int]:
    return [int(p) for p in re.findall(rf"{desc}:\s+(\d+)%\|", text)]


def test_a_sweep_in_a_terminal_draws_a_bar_that_moves_within_its_batches():
    text, status = _in_a_terminal(SWEEP)
    assert status == 0, text
    shown = _percentages(text, "readings")
    # 4 readings of 2e7 rays, in chunks of at most 2**20: the bar moves between the readings' ends
    # (the per-batch updates reach the visible bar, not only one "4 of 4" at the end)
    between = [p for p in shown if 0 < p < 100 and p % 25]
    assert between, f"no update between two readings' ends: {shown}\n{text[-2000:]}"
    assert shown == sorted(shown), shown


INSTRUMENTS = {  # a second or two each on a quiet machine: over the lowered threshold
    "sphere": ["sphere", "sphere_150mm_8d", "--wavelengths", "450,650", "--rays", "2000000", "--chunk-size", "262144"],
    "gonio": ["gonio", "soybean_abmb", "--theta-i", "0", "30", "--wavelengths", "450,650", "--rays", "4000000",
              "--chunk-size", "1048576"],
}


@pytest.mark.parametrize("command", sorted(INSTRUMENTS))
def test_the_sphere_and_the_goniophotometer_draw_their_bar_in_a_terminal_and_none_when_quiet(command):
    text, status = _in_a_terminal(INSTRUMENTS[command])
    assert status == 0, text
    shown = _percentages(text, "readings")
    assert [p for p in shown if 0 < p < 100], f"no update between the start and the end: {shown}\n{text[-2000:]}"
    assert shown == sorted(shown), shown
    quiet, status = _in_a_terminal([*INSTRUMENTS[command], "--quiet"])
    assert status == 0, quiet
    assert "%|" not in quiet and "readings:" not in quiet, quiet[-2000:]


@pytest.mark.slow
def test_a_target_in_a_terminal_draws_the_rays_traced_as_they_go():
    """
    A certified colour's length is not known in advance: its bar counts the rays and their
    rate. ΔE₀₀ ≤ 0.25 traces about 2·10⁷ rays (about a second): tqdm redraws at most every
    0.1 s, and ΔE₀₀ ≤ 0.5 (4·10⁶ rays) could end before a second draw on a quiet machine.
    """

    text, status = _in_a_terminal(["measure", "soybean_abmb", "--target", "colour,dE00=0.25", "--seed", "2"])
    assert status == 0, text
    shown = re.findall(r"target: ([\d.]+)([kMG]?) rays \[", text)
    rays = [float(n) * {"": 1, "k": 1e3, "M": 1e6, "G": 1e9}[unit] for n, unit in shown]
    assert len([r for r in rays if r > 0]) >= 2 and rays == sorted(rays), (shown, text[-2000:])


def test_quiet_in_a_terminal_draws_nothing():
    text, status = _in_a_terminal(SHORT + ["--quiet"])
    assert status == 0, text
    assert "%|" not in text and "readings:" not in text, text[-2000:]


def test_off_a_terminal_nothing_is_drawn():
    done = subprocess.run([sys.executable, "-c", CHILD, *SHORT], capture_output=True, text=True, env=_env(),
                          timeout=240, stdin=subprocess.DEVNULL)
    assert done.returncode == 0, done.stderr
    assert "%|" not in done.stderr and "%|" not in done.stdout, done.stderr[-2000:]


# -- the rule, without a kernel ----------------------------------------------------------------------------


class _Bar:
    """tqdm's place: what the bar was moved by."""

    def __init__(self, **kwargs):
        self.kwargs, self.moves, self.total = kwargs, [], kwargs.get("total")

    def update(self, n):
        self.moves.append(n)

    def write(self, text, file=None):
        self.moves.append(text)

    def close(self):
        pass


@pytest.fixture
def drawn(monkeypatch):
    import tqdm

    bars: list[_Bar] = []
    monkeypatch.setattr(tqdm, "tqdm", lambda **kwargs: bars.append(_Bar(**kwargs)) or bars[-1])
    return bars


def test_nested_bars_move_the_outermost_within_its_step(drawn):
    with Progress(True, 10, desc="table") as table:
        table.expect(4)  # the next group is worth 4 of the table's 10
        with Progress(False, 2, share=0.5) as first:  # half of the group, in 2 steps of its own
            first.update(1)
            first.update(1)
        with Progress(None, 8, share=0.5) as second:  # the other half: never drawn on its own
            second.reach(4)
        assert len(drawn) == 1  # one bar: the table's
        assert table.position == pytest.approx(3.0)  # 2 + 4/8 * 2
        table.update(4)  # the group's end: where the nested bars already took it, and on
        assert table.position == 4
    assert sum(m for m in drawn[0].moves if not isinstance(m, str)) == pytest.approx(4.0)


def test_a_nested_bar_never_passes_the_step_and_notes_go_to_the_outermost(drawn):
    with Progress(True, 10, desc="run") as run:
        run.expect(1)
        with Progress(False, 1, share=1.0) as inner:
            inner.update(5)  # more than it said: the run moves by its step, no more
            inner.note("resumed")
        assert run.position == pytest.approx(1.0)
    assert "resumed" in drawn[0].moves


def test_expect_and_finished_reach_the_innermost_open_bar_and_nothing_without_one(drawn):
    expect(5)
    finished(5)  # no bar open: nothing happens
    with Progress(True, None, desc="target", unit="ray") as target:  # open-ended: rays and their rate
        expect(100)
        with Progress(False, 10, unit="ray"):
            pass
        finished(100)
        assert target.done == 100
    assert drawn[0].kwargs["total"] is None and "rate_fmt" in drawn[0].kwargs["bar_format"]
    assert progress._stack() == []


def test_the_threshold_decides_when_nothing_was_asked(drawn, monkeypatch):
    monkeypatch.setattr(sys.stderr, "isatty", lambda: True, raising=False)
    with Progress(None, 1000) as quick:
        quick.update(999)  # done at once: expected well under the threshold
    assert not drawn
    monkeypatch.setattr(progress, "_PROGRESS_AFTER_S", 0.0)
    with Progress(None, 1000) as slow:
        slow.update(1)
        slow.update(1)
    assert len(drawn) == 1 and drawn[0].kwargs["initial"] == 1
    monkeypatch.setattr(sys.stderr, "isatty", lambda: False, raising=False)
    with Progress(None, 1000) as piped:
        piped.update(1)
    assert len(drawn) == 1  # not a terminal: no bar
    with Progress(False, 1000) as never:
        never.update(1)
        never.note("not shown")
    assert len(drawn) == 1


def test_a_fit_reads_more_than_foreseen_and_its_bar_grows(drawn):
    with Progress(True, 2, desc="fit") as fit:
        fit.update(3)
    assert fit.total == 3 and drawn[0].total == 3


def test_a_bar_dropped_unclosed_by_an_error_does_not_swallow_the_next_runs(drawn):
    import gc

    def failing() -> None:
        Progress(False, 10)  # made, then an error before its try: never closed
        raise ValueError("before the run")

    with pytest.raises(ValueError):
        failing()
    gc.collect()
    with Progress(True, 5) as later:
        assert later.parent is None
        later.update(5)
    assert len(drawn) == 1 and progress._stack() == []


@pytest.fixture
def every_update(monkeypatch):
    """Real tqdm bars that draw every update, however fast (tqdm's default waits 0.1 s between two)."""

    import tqdm.std

    drawing = tqdm.std.tqdm.__init__

    def drawn_always(self, *args, **kwargs):
        drawing(self, *args, **{**kwargs, "mininterval": 0, "miniters": 0})

    monkeypatch.setattr("tqdm.std.tqdm.monitor_interval", 0)
    monkeypatch.setattr(tqdm.std.tqdm, "__init__", drawn_always)


def test_progress_true_in_the_api_draws_the_batches_chunks(mi, capsys, every_update):
    """``vm.sweep(..., progress=True)``: drawn even off a terminal (a notebook), moving within the one batch."""

    import virtspec_mi as vm

    vm.sweep("soybean_abmb", theta_i=[0, 30, 60], wavelengths=[450, 550, 650], rays=200_000,
             chunk_size=1 << 16, progress=True)
    err = capsys.readouterr().err.replace("\r", "\n")
    shown = _percentages(err, "readings")
    assert any(0 < p < 100 for p in shown), err[-3000:]


def test_a_fit_draws_one_bar_over_its_forward_readings(mi, tmp_path, capsys, every_update):
    """``vm.fit(progress=True)``: one bar (its readings' own bars nested in it), its stage lines above it."""

    import virtspec_mi as vm
    from virtspec_mi.applications.fitting import _inputs

    _inputs(tmp_path)
    result = vm.fit(tmp_path / "leaf.csv", "prospect_d", {"Cab": (10.0, 80.0)}, quantities=("reflectance",),
                    theta_i=8.0, beam="collimated", delta=0.2, table_points=3, profile_points=0, progress=True)
    err = capsys.readouterr().err.replace("\r", "\n")
    shown = _percentages(err, "fit")
    assert shown and any(0 < p < 100 for p in shown), err[-2000:]
    assert "readings:" not in err  # the forward readings' own bars moved the fit's, drew nothing
    assert "fit: table of 3 points" in err and result.rays > 0
    assert progress._stack() == []
