"""
A target that survives interruption (applications/targets/resume.py): a betting run
checkpointed after every batch, and a pooled two-stage run after every trace, killed
with SIGKILL mid-run, resumed, gives the result of the uninterrupted run bit for bit (the
wall time excepted), tracing only the batches the file did not hold; a checkpoint of
another run is refused and left as it is.
"""

from __future__ import annotations

import json
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from killed_runs import Interrupting, default_signals

CHILD = '''
import json, sys, time
import numpy as np
import virtspec_mi as vm
import virtspec_mi.applications.targets.sequential as sequential
import virtspec_mi.instruments.hemispherical.allocated as allocated

sequential.FIRST_SHARE = 0.05  # many small batches: a sequence to interrupt
sequential._next_information = lambda have, widths, tolerances: np.where(widths <= tolerances, 0.0, 1.4 * have)
traced = []
original = allocated.trace_allocated
def counting(*args, **kwargs):
    traced.append(1)
    out = original(*args, **kwargs)
    if sys.argv[2] == "slow":
        time.sleep(0.4)
    return out
allocated.trace_allocated = counting
scene = vm.instrument_scene({"type": "diffuse", "reflectance": {"type": "regular", "wavelength_min": 300,
                             "wavelength_max": 1000, "values": "0.03, 0.05, 0.08, 0.04"}})
keywords = {} if sys.argv[1] == "-" else {"checkpoint": sys.argv[1]}
bands = [(500, 520)] if sys.argv[3] == "betting" else [(500, 520), (600, 620), (700, 720)]
result = vm.measure(scene, target=vm.band(*bands, step=10.0, tolerance=0.004), delta=0.05, seed=3,
                    bound=sys.argv[3], **keywords)
data = result.as_dict()
data.pop("seconds", None)
print(json.dumps({"result": data, "traced": len(traced)}, sort_keys=True))
'''


def _run(tmp_path: Path, checkpoint: str, bound: str, pace: str = "fast") -> dict:
    done = subprocess.run([sys.executable, str(tmp_path / "child.py"), checkpoint, pace, bound], capture_output=True,
                          text=True, check=True, cwd=tmp_path, preexec_fn=default_signals)
    return json.loads(done.stdout.strip().splitlines()[-1])


@pytest.mark.parametrize("bound", ["betting", "two-stage"])
def test_a_target_killed_mid_sequence_resumes_to_the_same_result(mi, tmp_path, bound):
    """
    Betting: one band in many small batches; two-stage: three bands, a pilot and a second
    batch each (six traces). Killed once three traces are kept: mid-run either way.
    """

    (tmp_path / "child.py").write_text(CHILD)
    checkpoint = tmp_path / "target.partial.json"
    process = subprocess.Popen([sys.executable, str(tmp_path / "child.py"), str(checkpoint), "slow", bound],
                               cwd=tmp_path, preexec_fn=default_signals, stdout=subprocess.DEVNULL)
    deadline = time.monotonic() + 300
    kept = 0
    while process.poll() is None and time.monotonic() < deadline:
        try:
            kept = len(json.loads(checkpoint.read_text())["traces"])
        except (OSError, ValueError, KeyError):
            kept = 0
        if kept >= 3:  # the pilot and two batches finished: mid-sequence
            break
        time.sleep(0.02)
    process.send_signal(signal.SIGKILL)
    process.wait()
    assert process.returncode == -signal.SIGKILL, "the run ended before it could be interrupted"
    kept = len(json.loads(checkpoint.read_text())["traces"])  # the file is whole after the kill
    resumed = _run(tmp_path, str(checkpoint), bound)
    whole = _run(tmp_path, "-", bound)
    assert resumed["result"] == whole["result"]  # bit-identical: every count, interval, batch, reading
    traces = len(whole["result"]["batches"]) * (2 if bound == "two-stage" else 1)  # betting: its pilot is one more
    assert traces > kept >= 3 and whole["result"]["bound"] == bound
    assert resumed["traced"] == whole["traced"] - kept  # only what the file did not hold was traced again
    assert not checkpoint.exists()  # removed once the result is returned


def test_a_checkpoint_of_another_run_is_refused_and_kept(mi, tmp_path):
    import virtspec_mi as vm
    from virtspec_mi.engine.checkpoint import CheckpointError

    scene = vm.instrument_scene({"type": "diffuse", "reflectance": {"type": "regular", "wavelength_min": 300,
                                 "wavelength_max": 1000, "values": "0.03, 0.05, 0.08, 0.04"}})
    target = vm.band((500, 520), step=10.0, tolerance=0.01)
    path = tmp_path / "run.json"
    first = vm.measure(scene, target=target, delta=0.05, seed=3, bound="betting", checkpoint=path)
    assert not path.exists()  # removed with the result returned
    path.write_text(json.dumps({"format": "virtspec-mi target checkpoint 1", "identity": {"other": 1},
                                "traces": []}))
    with pytest.raises(CheckpointError, match="belongs to another measurement"):
        vm.measure(scene, target=target, delta=0.05, seed=3, bound="betting", checkpoint=path)
    assert path.exists()
    path.write_text("{not json")
    with pytest.raises(CheckpointError, match="not a target checkpoint"):
        vm.measure(scene, target=target, delta=0.05, seed=3, bound="betting", checkpoint=path)
    again = vm.measure(scene, target=target, delta=0.05, seed=3, bound="betting", checkpoint=tmp_path / "b.json")
    assert again["band_500-520"] == first["band_500-520"] and again.batches == first.batches
    with pytest.raises(ValueError, match="checkpoint must be a file path"):
        vm.measure(scene, target=target, checkpoint=3)


def test_the_command_line_keeps_a_targets_checkpoint(mi, tmp_path, capsys):
    from virtspec_mi.cli import main

    path = tmp_path / "b04.json"
    argv = ["measure", "diamond_collimated", "--target", "band:B04,tolerance=0.05", "--seed", "1", "--json"]
    assert main([*argv, "--bound", "betting", "--checkpoint", str(path)]) == 0
    kept = json.loads(capsys.readouterr().out)
    assert main([*argv, "--bound", "betting"]) == 0
    plain = json.loads(capsys.readouterr().out)
    for data in (kept, plain):  # the wall time and the checksum that seals it differ
        data.pop("seconds"), data.pop("checksum")
    assert kept == plain and not path.exists()
    assert main(["measure", "diamond_collimated", "--checkpoint", str(path)]) != 0
    assert "--checkpoint acts only with --target: give --target too" in capsys.readouterr().err


def test_a_sweep_of_a_target_interrupted_resumes_to_the_same_results(mi, tmp_path, monkeypatch):
    import numpy as np

    import virtspec_mi as vm
    import virtspec_mi.instruments.hemispherical.allocated as allocated

    scene = vm.instrument_scene({"type": "diffuse", "reflectance": {"type": "regular", "wavelength_min": 300,
                                 "wavelength_max": 1000, "values": "0.03, 0.05, 0.08, 0.04"}})
    target = vm.band((500, 520), step=10.0, tolerance=0.01)
    keywords = dict(theta_i=[0, 30, 60], target=target, delta=0.05, seed=3, bound="betting")
    whole = vm.sweep(scene, **keywords)
    traces = Interrupting(monkeypatch, allocated, "trace_allocated", after=5)  # the second angle under way
    path = tmp_path / "sweep.json"
    with pytest.raises(KeyboardInterrupt):
        vm.sweep(scene, checkpoint=path, **keywords)
    assert len(json.loads(path.read_text())["traces"]) == 5
    traces.calls, traces.after = 0, -1  # no interruption now; count what is traced again
    resumed = vm.sweep(scene, checkpoint=path, **keywords)
    assert not path.exists()
    total = sum(len(r.batches) + 1 for r in whole)  # each angle: its pilot and its batches
    assert traces.calls == total - 5 and total > 8
    for a, b in zip(whole, resumed):
        assert a.batches == b.batches and a["band_500-520"] == b["band_500-520"]
        assert np.array_equal(a.readings.rays, b.readings.rays)
