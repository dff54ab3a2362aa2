"""
Messages speak as their reader writes (issue 42, new-user item 3): Python to a Python
user, flags to a command-line user, chosen in one place (virtspec_mi.base.surface).
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import virtspec_mi as vm
from virtspec_mi.base.surface import command_line, on_command_line, spoken
from virtspec_mi.cli import main


def test_spoken_is_python_unless_the_command_line_runs():
    assert not on_command_line() and spoken("vm.band(...)", "--target band:...") == "vm.band(...)"
    with command_line():
        assert on_command_line() and spoken("vm.band(...)", "--target band:...") == "--target band:..."
    assert not on_command_line()


def test_a_warning_on_the_command_line_is_one_line_without_python():
    with command_line():
        shown = warnings.formatwarning("the checkpoint could not be saved", RuntimeWarning, "checkpoint.py", 283,
                                       "self.flush()")
    assert shown == "virtspec: warning: the checkpoint could not be saved\n"
    assert warnings.formatwarning("x", UserWarning, "f.py", 1).startswith("f.py:1: UserWarning")  # Python's again


def test_an_index_of_a_black_specimen_names_the_bands_as_its_reader_writes_them():
    with pytest.raises(ValueError, match=r"measure the bands instead \(vm\.band\(\.\.\.\)\)"):
        vm.index("NDVI").tolerances(np.array([0.0, 0.0]), 0.01)
    with command_line(), pytest.raises(ValueError, match=r"measure the bands instead \(--target band:\.\.\.\)"):
        vm.index("NDVI").tolerances(np.array([0.0, 0.0]), 0.01)


def test_a_target_refusing_wavelengths_shows_the_flag_form_on_the_command_line(mi):
    from virtspec_mi.applications.targets.measure import measure_target
    from virtspec_mi.runtime.scene import loaded

    scene = loaded("diamond_collimated")
    with pytest.raises(ValueError, match=r"e\.g\. vm\.band\('B04', tolerance=0\.002\)"):
        measure_target(scene, None, vm.colour(), {"wavelengths": [500.0]})
    with command_line(), pytest.raises(ValueError, match=r"e\.g\. --target band:B04,tolerance=0\.002\)") as refused:
        measure_target(scene, None, vm.colour(), {"wavelengths": [500.0]})
    assert "vm." not in str(refused.value)


def test_a_targets_summary_on_the_command_line_names_no_python(mi, capsys):
    assert main(["measure", "diamond_collimated", "--target", "band:B04,tolerance=0.05", "--seed", "1"]) == 0
    shown = "".join(capsys.readouterr())
    assert "result.readings" not in shown and "per-wavelength readings (in --json)" in shown, shown
    assert main(["measure", "diamond_collimated", "--target", "colour", "--wavelengths", "400:700:10"]) != 0
    shown = "".join(capsys.readouterr())
    assert "--target band:B04,tolerance=0.002" in shown and "vm." not in shown and "result." not in shown, shown


def test_the_tables_speak_flags_on_the_command_line(capsys):
    assert main(["albedo-table", "--engine", "cycles", "--cosines", "1,0.5", "--alpha", "0.3"]) == 1
    err = capsys.readouterr().err
    assert "--engine cycles fixes the grid: give --engine none with --cosines, --alpha" in err and "=" not in err, err
    with pytest.raises(ValueError, match=r"engine='cycles' fixes the grid: give engine=None with mu, alpha"):
        vm.albedo_table("conductor", engine="cycles", mu=[1.0, 0.5])


def test_the_colour_tolerance_has_one_name_and_its_short_name_on_both_surfaces():
    from virtspec_mi.applications.targets.parse import parse_target

    assert vm.colour(dE00=1.0) == vm.colour(tolerance_dE00=1.0) == parse_target("colour,dE00=1") \
        == parse_target("colour,tolerance_dE00=1")
    assert vm.colour().tolerance_dE00 == 0.5
    with pytest.raises(ValueError, match="tolerance_dE00 and dE00 are one tolerance"):
        vm.colour(1.0, dE00=2.0)
    with pytest.raises(ValueError, match="given twice"):
        parse_target("colour,dE00=1,tolerance_dE00=2")


def test_a_name_too_long_for_the_file_system_is_refused_naming_the_parameter_not_echoed(mi, tmp_path):
    long = "x" * 5000
    for call, name in ((lambda: vm.measure(long, rays=10), "scene"),
                       (lambda: vm.sweep("diamond_collimated", rays=10, out=tmp_path / f"{long}.nc"), "out")):
        with pytest.raises(ValueError, match=rf"^{name}: a file or folder name holds at most \d+ bytes") as refused:
            call()
        assert len(str(refused.value)) < 400 and "give a shorter name" in str(refused.value)


def test_a_fits_window_message_names_the_flags_on_the_command_line():
    from virtspec_mi.applications.fitting.windows import fit_windows

    wavelengths = np.arange(400.0, 800.0, 10.0)
    with pytest.raises(ValueError, match=r"^loss='windows' needs a window .* give windows=\{name"):
        fit_windows({}, ["specimen.thickness"], wavelengths)
    with command_line(), pytest.raises(ValueError, match=r"^--loss windows needs a window .* give --window NAME="):
        fit_windows({}, ["specimen.thickness"], wavelengths)
