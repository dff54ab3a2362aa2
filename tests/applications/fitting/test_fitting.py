"""
Tests of :mod:`virtspec_mi.applications.fitting` (its ``__init__``): the application's row and
its lazy names.

The names ``fit``, ``LOSSES``, ``read_fit``, ``fit_samples`` and ``FitTable`` are the objects of
their modules, imported on first use, so that importing the package (as ``virtspec``'s parser
does) does not import SciPy's optimisers; the row declares ``virtspec fit`` and the fit's result
kind; its example's measured file reads as four wavelengths with their uncertainty. The row's
example is run by the contract test (``tests/applications/test_applications.py``).
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import virtspec_mi.applications.fitting as fitting
from virtspec_mi.applications import APPLICATIONS
from virtspec_mi.applications.fitting import FittingApplication, _inputs
from virtspec_mi.results.kinds import kind_of

ROOT = Path(__file__).resolve().parents[3]


def test_the_lazy_names_are_their_modules_objects():
    from virtspec_mi.applications.fitting import inversion, result, samples

    assert fitting.fit is inversion.fit and fitting.LOSSES is inversion.LOSSES
    assert fitting.read_fit is result.read_fit
    assert fitting.fit_samples is samples.fit_samples and fitting.FitTable is samples.FitTable
    with pytest.raises(AttributeError, match="module 'virtspec_mi.applications.fitting' has no attribute 'fitt'"):
        fitting.fitt


def test_importing_the_package_leaves_the_optimisers_out():
    script = ("import sys\nimport virtspec_mi.applications.fitting\n"
              "print('scipy.optimize' in sys.modules, 'virtspec_mi.applications.fitting.inversion' in sys.modules)")
    shown = subprocess.run([sys.executable, "-c", script], cwd=ROOT, capture_output=True, text=True, check=True,
                           env={"PYTHONPATH": str(ROOT), "PATH": ""}).stdout.split()
    assert shown == ["False", "False"]


def test_the_row_declares_the_fit_command_and_result():
    assert APPLICATIONS["fitting"] is FittingApplication
    assert [command.name for command in FittingApplication.commands] == ["fit"]
    (result,) = FittingApplication.results
    assert kind_of(result.FORMAT) is result is fitting.FitResult


def test_the_examples_measured_file(tmp_path):
    from virtspec_mi.applications.comparison import read_measured

    _inputs(tmp_path)
    spectrum = read_measured(tmp_path / "leaf.csv")
    np.testing.assert_array_equal(spectrum.wavelengths, [500.0, 560.0, 650.0, 800.0])
    np.testing.assert_allclose(spectrum.uncertainty, 0.03)
