"""Tests of virtspec_mi.base.llvm: a working libLLVM is chosen, a bad one refused with the fix."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

from virtspec_mi.base import llvm


def test_major_version_from_file_names():
    assert llvm._major_from_name("/usr/lib/x86_64-linux-gnu/libLLVM-15.so.1") == 15
    assert llvm._major_from_name("/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1") == 19
    assert llvm._major_from_name("/usr/lib/llvm-19/lib/libLLVM.so") == 19


def test_a_working_library_is_found_and_loaded():
    path = llvm.find_libllvm()
    assert path is not None, "set-up (make setup) must provide libLLVM >= 17"
    version = subprocess.run(
        [sys.executable, "-m", "virtspec_mi", "llvm", "check"], capture_output=True, text=True
    )
    assert version.returncode == 0, version.stderr
    assert int(version.stdout.split()[1].split(".")[0]) >= llvm.MINIMUM_LLVM_MAJOR
    assert "RuntimeWarning" not in version.stderr  # make setup's command runs without runpy's warning


def _run_with_llvm(path: str, code: str) -> subprocess.CompletedProcess:
    env = dict(os.environ, DRJIT_LIBLLVM_PATH=path)
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env)


MEASURE = (
    "import virtspec_mi as vm\n"
    "vm.measure(vm.instrument_scene({'type': 'simple_dielectric'}), theta_i=10, rays=1000)\n"
)


def test_bad_libllvm_is_refused_with_the_fix_not_an_abort():
    bad = [path for major, path in llvm.candidate_libraries() if major < llvm.MINIMUM_LLVM_MAJOR]
    if not bad:
        pytest.skip("no libLLVM < 17 on this machine to refuse (Debian 12 ships 14 and 15)")
    result = _run_with_llvm(bad[0], MEASURE)
    assert result.returncode == 1, result.stderr  # an exception, not SIGABRT (-6)
    assert not any(line.startswith("LLVM ERROR") for line in result.stderr.splitlines())
    assert "LLVMError" in result.stderr and "libllvm19" in result.stderr
    assert "DRJIT_LIBLLVM_PATH" in result.stderr


def test_missing_libllvm_path_is_refused_with_the_fix():
    result = _run_with_llvm("/nonexistent/libLLVM.so.19.1", MEASURE)
    assert result.returncode == 1
    assert "does not exist" in result.stderr and "libllvm19" in result.stderr


def test_cli_reports_a_bad_libllvm_in_one_line(scenes_dir):
    result = subprocess.run(
        [sys.executable, "-m", "virtspec_mi.cli", "measure", str(scenes_dir / "diamond_conical.xml")],
        capture_output=True, text=True, env=dict(os.environ, DRJIT_LIBLLVM_PATH="/nonexistent/libLLVM.so"),
    )
    assert result.returncode == 1
    assert result.stderr.startswith("virtspec: error: DRJIT_LIBLLVM_PATH=")
