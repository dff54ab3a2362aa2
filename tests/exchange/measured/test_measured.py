"""
The table of measured-file formats (virtspec_mi.exchange.measured): its rows, an outside
package's format through the entry-point group, and every format end to end through
vm.read_measured, vm.compare, vm.fit and the command line.
"""

from __future__ import annotations

import json
import textwrap
from dataclasses import replace
from importlib import metadata

import numpy as np
import pytest

import virtspec_mi as vm
from measured_files import write_asd, write_columns, write_envi, write_jcamp, write_rows, write_sed, write_sig
from virtspec_mi.exchange import measured
from virtspec_mi.exchange.measured import BUILTIN, ENTRY_POINTS, FORMATS, MeasuredFile, discovered, format_for
from virtspec_mi.plugins.bsdfs.prospect_model import prospect_d

GRID = np.arange(450.0, 2400.0, 150.0)  # 13 regular wavelengths (ASD stores a first wavelength and a step)
TRUTH = 45.0
REFLECTANCE = prospect_d(GRID, Cab=TRUTH)[0]
OTHER = prospect_d(GRID, Cab=20.0)[0]
FAST = dict(evaluations=(8, 4, 2), profile_points=3, table_points=5, theta_i=8.0, beam="collimated", delta=0.1)


def _files(tmp_path) -> dict[str, object]:
    """Each format holding the PROSPECT-D leaf at Cab = 45 (a file of many: as its sample 'leaf')."""

    reference = np.linspace(9000, 21000, len(GRID))
    return {
        "asd": write_asd(tmp_path / "leaf.asd", GRID[0], 150.0, REFLECTANCE * reference, reference),
        "sig": write_sig(tmp_path / "leaf.sig", GRID, reference, REFLECTANCE * reference, 100 * REFLECTANCE),
        "sed": write_sed(tmp_path / "leaf.sed", GRID, {"Rad. (Ref.)": reference,
                                                        "Rad. (Target)": REFLECTANCE * reference,
                                                        "Reflect. %": 100 * REFLECTANCE}),
        "jcamp": MeasuredFile(write_jcamp(tmp_path / "lib.jdx", GRID, {"other": OTHER, "leaf": REFLECTANCE},
                                          yfactor=1e-7), sample="leaf"),
        "envi": MeasuredFile(write_envi(tmp_path / "lib.sli", GRID, {"other": OTHER, "leaf": REFLECTANCE},
                                        dtype="<f8", extra="z plot titles = {Wavelength, Reflectance}"),
                             sample=1),
        "table": MeasuredFile(write_rows(tmp_path / "lib.csv", GRID, {"other": OTHER, "leaf": REFLECTANCE},
                                         quantity="reflectance"), sample="leaf"),
    }


def _result(values, wavelengths, rays=10**6) -> vm.Result:
    from virtspec_mi.kernel.counts import Counts

    shape = (len(wavelengths), 1)
    counts = replace(Counts.zeros(shape), rays=np.full(shape, rays, dtype=np.int64),
                     reflected=np.round(np.asarray(values)[:, None] * rays).astype(np.int64))
    return vm.Result(("wavelength", "theta_i"), {"wavelength": np.asarray(wavelengths, float),
                                                 "theta_i": np.array([8.0])},
                     counts, None, vm.Settings(wavelengths=list(wavelengths), theta_i=8.0),
                     vm.InstrumentGeometry(8, 12.5, 100), 0.0, scene="sha256:0123456789abcdef")


def test_the_built_in_formats_are_rows_of_the_table():
    assert tuple(FORMATS)[:len(BUILTIN)] == ("asd", "sig", "sed", "jcamp", "envi", "table")
    assert all(FORMATS[row.name] is row for row in BUILTIN)
    assert format_for("x.ASD").name == "asd" and format_for("x.hdr").name == "envi" and format_for("x.nc") is None
    with pytest.raises(ValueError, match=r"format must be one of asd, sig, sed, jcamp, envi, table"):
        format_for("x.dat", "nope")


def test_every_format_reads_back_the_same_numbers_through_read_measured(tmp_path):
    for name, source in _files(tmp_path).items():
        spectrum = vm.read_measured(source)
        np.testing.assert_allclose(spectrum.wavelengths, GRID, err_msg=name)
        np.testing.assert_allclose(spectrum.values, REFLECTANCE, atol=1e-6, err_msg=name)
        assert spectrum.quantity == "reflectance"


def test_every_format_is_compared_end_to_end(tmp_path):
    result = _result(REFLECTANCE, GRID)
    for name, source in _files(tmp_path).items():
        comparison = vm.compare(result, source)
        assert len(comparison.wavelengths) == len(GRID), name
        assert comparison.points_within == len(GRID), name  # the counts round R to 1e-6, far inside mu'
        assert comparison.rmse < 1e-5, name
    with pytest.raises(ValueError, match=r"lib.jdx holds 2 spectra \(other, leaf\): choose one with sample="):
        vm.compare(result, tmp_path / "lib.jdx")
    with pytest.raises(ValueError, match=r"leaf.asd holds reflectance, not the transmittance compared"):
        vm.read_measured(tmp_path / "leaf.asd", "transmittance")


@pytest.mark.parametrize("name", ["asd", "sig", "sed", "jcamp", "envi", "table"])
def test_every_format_is_fitted_end_to_end(tmp_path, name):
    source = _files(tmp_path)[name]
    result = vm.fit(source, "prospect_d", {"Cab": (10, 90)}, measurement_uncertainty=0.01, seed=3, **FAST)
    low, high = result.intervals[0]
    assert result.consistent and low <= TRUTH <= high and high - low < 40, (name, result.intervals)


def test_the_command_line_takes_the_flags_of_a_measured_file(tmp_path, capsys):
    from virtspec_mi.cli import main

    files = _files(tmp_path)
    result = _result(REFLECTANCE, GRID)
    result.write(tmp_path / "leaf.nc")
    assert main(["compare", str(tmp_path / "leaf.nc"), str(tmp_path / "lib.csv"), "--sample", "leaf", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["points_within"] == len(GRID)
    assert main(["compare", str(tmp_path / "leaf.nc"), str(tmp_path / "lib.sli"), "--sample", "1",
                 "--measured-quantity", "transmittance"]) == 1
    assert "mislabelled" in capsys.readouterr().err
    assert main(["compare", str(tmp_path / "leaf.nc"), str(files["asd"]), "--splice", "--json"]) == 0
    assert "splice" in json.loads(capsys.readouterr().out)["note"]
    status = main(["fit", str(tmp_path / "lib.csv"), "--sample", "leaf", "--specimen", "prospect_d", "--free",
                   "Cab=10:90", "--uncertainty", "0.01", "--profile-points", "3", "--theta-i", "8", "--beam",
                   "collimated", "--delta", "0.1", "--json"])
    assert status == 0
    data = json.loads(capsys.readouterr().out)
    assert data["intervals"][0][0] <= TRUTH <= data["intervals"][0][1] < 90


# -- an outside package's format -----------------------------------------------------------------


def _outside_package(tmp_path):
    """A distribution on sys.path whose entry point of virtspec_mi.measured_formats is a two-column '.lab' reader."""

    package = tmp_path / "site"
    (package / "lab_format").mkdir(parents=True)
    (package / "lab_format" / "__init__.py").write_text(textwrap.dedent('''
        import numpy as np
        from virtspec_mi.exchange.measured.base import MeasuredFormat, RawSpectra

        def read(path, splice=False):
            table = np.loadtxt(path, comments="#")
            return RawSpectra(wavelengths=table[:, 0], labels=(path.stem,), values=table[None, :, 1],
                              quantity="transmittance", scale="percent", unit="um", told="the lab's format")

        FORMAT = MeasuredFormat("lab", (".lab",), read, "our lab's spectrometer")
        '''))
    info = package / "lab_format-1.0.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: lab-format\nVersion: 1.0\n")
    (info / "entry_points.txt").write_text(f"[{ENTRY_POINTS}]\nlab = lab_format:FORMAT\nbroken = lab_format:nothing\n")
    return package


def test_an_outside_package_adds_a_format_through_its_entry_point(tmp_path, monkeypatch):
    monkeypatch.syspath_prepend(str(_outside_package(tmp_path)))
    points = metadata.entry_points(group=ENTRY_POINTS)
    assert {"lab", "broken"} <= set(points.names)
    with pytest.warns(RuntimeWarning, match=r"entry point 'broken' \(lab_format:nothing\) could not be loaded"):
        formats = discovered(BUILTIN)
    assert list(formats)[-1] == "lab" and formats["lab"].description == "our lab's spectrometer"
    monkeypatch.setattr(measured, "FORMATS", formats)
    (tmp_path / "plate.lab").write_text("# wavelength (um), T (%)\n0.5 40\n0.6 50\n0.7 55\n")
    spectrum = vm.read_measured(tmp_path / "plate.lab", "transmittance")
    np.testing.assert_allclose(spectrum.wavelengths, [500, 600, 700])
    np.testing.assert_allclose(spectrum.values, [0.40, 0.50, 0.55])


def test_an_entry_point_that_is_no_format_or_takes_a_name_is_left_out(monkeypatch):
    class Point:
        def __init__(self, name, value, loaded):
            self.name, self.value, self._loaded = name, value, loaded

        def load(self):
            return self._loaded

    rows = [Point("x", "pkg:thing", object()), Point("asd", "pkg:asd", replace(BUILTIN[0], description="theirs"))]
    monkeypatch.setattr(measured, "entry_points", lambda group: rows if group == ENTRY_POINTS else [])
    with pytest.warns(RuntimeWarning) as warned:
        formats = discovered(BUILTIN)
    assert formats["asd"] is BUILTIN[0]
    messages = " ".join(str(w.message) for w in warned)
    assert "is not a MeasuredFormat" in messages and "takes the name 'asd', already taken" in messages


