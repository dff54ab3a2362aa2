"""
Tests of virtspec_mi.applications.comparison: a simulated spectrum against a measured one.

Measured data that ship with an installed package: colour-science's ColorChecker N
Ohta patches (written to CSV files here), measured through a Mitsuba ``diffuse``
specimen whose reflectance is the patch spectrum; and the NPSG C++ reference values of
the soybean leaf (the NPSG C++ reference runs (soybean), ``tests/abm_reference.py``) against an ABM-B
measurement.

Tolerances come from the certificate: each simulated point is within its
``certified_mu`` of the true value with probability ≥ 1 − δ, so n points are all
within with probability ≥ 1 − nδ (union bound); the readings here are certified at
δ = 10⁻³/n, a false-failure probability ≤ 10⁻³ per test.
"""

from __future__ import annotations

import json
import subprocess
import sys
from dataclasses import replace

import colour
import numpy as np
import pytest

import virtspec_mi as vm
from abm_reference import SOYBEAN, SOYBEAN_RAYS, SOYBEAN_WAVELENGTHS, ROUNDING
from virtspec_mi.applications.comparison import Comparison, MeasuredSpectrum, compare, read_measured

CHART = colour.SDS_COLOURCHECKERS["ColorChecker N Ohta"]
WAVELENGTHS = "362:798:4"  # 110 wavelengths; 382-778 nm compared (100, 80 of them between the 5 nm data)
COMPARED = 100
RISK = 1e-3  # false-failure probability of a test


def virtspec(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "virtspec_mi.cli", *args], capture_output=True, text=True)


def patch_scene(name: str) -> dict:
    """The patch as a specimen over 360-800 nm: its 380-780 nm data, the end values held 20 nm beyond (the
    instrument refuses wavelengths outside a specimen's spectrum; the measured file keeps 380-780 nm)."""

    sd = CHART[name]
    step = float(sd.wavelengths[1] - sd.wavelengths[0])
    pad = int(round(20 / step))
    values = [sd.values[0]] * pad + list(sd.values) + [sd.values[-1]] * pad
    return vm.instrument_scene({"type": "diffuse", "reflectance": {
        "type": "regular", "wavelength_min": float(sd.wavelengths[0]) - pad * step,
        "wavelength_max": float(sd.wavelengths[-1]) + pad * step, "values": ", ".join(f"{v:.6g}" for v in values)}})


def write_patch(name: str, path) -> str:
    colour.write_sds_to_csv_file({"reflectance": CHART[name]}, str(path))
    return str(path)


@pytest.fixture(scope="module")
def dark_skin(mi):
    """The 'dark skin' patch measured 362-798 nm every 4 nm, each point certified at delta = RISK / 100."""

    return vm.sweep(patch_scene("dark skin"), theta_i=[8], wavelengths=WAVELENGTHS, beam="collimated",
                    delta=RISK / COMPARED, seed=1)


@pytest.fixture(scope="module")
def patch_csv(tmp_path_factory):
    return write_patch("dark skin", tmp_path_factory.mktemp("measured") / "dark_skin.csv")


def synthetic(values, wavelengths, rays=10**6, violations=0) -> vm.Result:
    """A one-angle result of given reflectance (exact counts), optionally with weight violations."""

    from virtspec_mi.kernel.counts import Counts

    shape = (len(wavelengths), 1)
    counts = replace(Counts.zeros(shape), rays=np.full(shape, rays, dtype=np.int64),
                     reflected=np.round(np.asarray(values)[:, None] * rays).astype(np.int64),
                     weight_violations=np.full(shape, violations, dtype=np.int64))
    return vm.Result(("wavelength", "theta_i"), {"wavelength": np.asarray(wavelengths, float),
                                                 "theta_i": np.array([8.0])},
                     counts, None, vm.Settings(wavelengths=wavelengths, theta_i=8.0), vm.InstrumentGeometry(8, 12.5, 100), 0.0,
                     scene="sha256:0123456789abcdef")


# --- the ColorChecker: the right spectrum within tolerance, a wrong one flagged -------------


def test_a_patch_is_found_within_its_certified_tolerance(dark_skin, patch_csv):
    c = compare(dark_skin, patch_csv)
    assert isinstance(c, Comparison) and c.quantity == "reflectance" and c.theta_i == 8.0
    # 380-780 nm compared, nothing extrapolated; 4 nm steps meet the 5 nm data every 20 nm
    assert len(c.wavelengths) == COMPARED and c.wavelengths[0] == 382 and c.wavelengths[-1] == 778
    np.testing.assert_array_equal(c.left_out, [362, 366, 370, 374, 378, 782, 786, 790, 794, 798])
    assert c.interpolated == COMPARED - 20
    np.testing.assert_allclose(c.measured, np.interp(c.wavelengths, CHART["dark skin"].wavelengths,
                                                     CHART["dark skin"].values))
    # union bound: every point within its certified mu' with probability >= 1 - RISK
    assert np.all(c.certified_mu <= 0.005) and not np.any(c.measurement_uncertainty)
    assert c.points_within == COMPARED and c.share_within == 1.0, c.summary()
    assert c.rmse <= 0.005 and c.mean_absolute_difference <= c.rmse
    # the colour: 101 independent readings average out (the 24-patch check sees <= 0.19 at N = 105,967)
    assert c.delta_E < 0.5 and c.delta_E_note == ""
    text = c.summary()
    assert f"compared {COMPARED} of 110 wavelengths" in text and "80 interpolated linearly" in text
    assert "left out (outside the measured range, never extrapolated): 362, 366, 370" in text
    assert f"{COMPARED} of {COMPARED} points (100.0%)" in text and "Delta E 2000 = " in text


@pytest.mark.parametrize("other", ["light skin", "foliage"])
def test_a_wrong_spectrum_is_flagged(dark_skin, other, tmp_path):
    c = compare(dark_skin, write_patch(other, tmp_path / "other.csv"))
    assert c.rmse > 0.05 and c.delta_E > 5
    assert c.share_within < 0.5


def test_a_spectral_distribution_and_a_wavelength_tuple_are_measured_spectra(dark_skin):
    sd = CHART["dark skin"]
    by_sd = compare(dark_skin, sd)
    by_tuple = compare(dark_skin, (sd.wavelengths[::-1], sd.values[::-1]))  # any order
    np.testing.assert_array_equal(by_sd.residuals, by_tuple.residuals)
    assert by_sd.spectrum.source == "dark skin" and by_sd.points_within == COMPARED


def test_an_uncertainty_column_widens_the_tolerance(dark_skin, tmp_path):
    sd = CHART["dark skin"]
    plain = tmp_path / "plain.csv"
    plain.write_text("\n".join(f"{w:g},{v:.6g},0.002" for w, v in zip(sd.wavelengths, sd.values)) + "\n")
    c = compare(dark_skin, plain)
    np.testing.assert_allclose(c.measurement_uncertainty, 0.002)
    np.testing.assert_allclose(c.tolerance, c.certified_mu + 0.002)
    assert "+ measurement uncertainty (<= 0.002)" in c.summary()
    wider = compare(dark_skin, plain, measurement_uncertainty=0.01)  # the argument overrides the column
    np.testing.assert_allclose(wider.measurement_uncertainty, 0.01)


def test_a_result_file_is_compared_and_plotted(dark_skin, patch_csv, tmp_path):
    path = dark_skin.write(tmp_path / "dark_skin.nc")
    c = compare(path, patch_csv)
    assert c.result_name == "dark_skin.nc" and c.points_within == COMPARED
    figure = c.plot(tmp_path / "compare.png")
    assert (tmp_path / "compare.png").stat().st_size > 0 and len(figure.axes) == 2
    data = c.as_dict()
    json.dumps(data)  # JSON-ready
    assert data["compared"] == COMPARED and data["points_within"] == COMPARED and data["left_out"][0] == 362
    assert data["scene"].startswith("sha256:") and data["delta_E_2000"] < 0.5 and data["within"] == [True] * COMPARED


# --- leaf data: sparse reference values, colour refused -------------------------------------


def test_soybean_abm_b_against_the_npsg_reference_values(mi, tmp_path):
    """
    the NPSG C++ reference runs (soybean), 8 deg adaxial, sieve and detour on: R and T at 7 wavelengths, each the
    C++ reference's estimate from 10^6 rays printed to 3 decimals. Its uncertainty is its
    own Hoeffding tolerance plus the rounding; ours is certified. 28 events (7 wavelengths
    x R, T x both sides), each at RISK / 28: all points within with probability >= 1 - RISK.
    """

    delta = RISK / 28
    reference = np.array([row[1] for row in SOYBEAN[True]])  # the "8" column: (R, T) per wavelength
    uncertainty = vm.hoeffding_mu(SOYBEAN_RAYS, delta) + ROUNDING
    table = tmp_path / "npsg_soybean.csv"
    header = "wavelength,reflectance,transmittance,reflectance_uncertainty,transmittance_uncertainty\n"
    table.write_text(header + "".join(f"{w},{r},{t},{uncertainty:.6f},{uncertainty:.6f}\n"
                                      for w, (r, t) in zip(SOYBEAN_WAVELENGTHS, reference)))
    leaf = vm.measure(vm.instrument_scene({"type": "abm_b"}), theta_i=8, beam="collimated",
                      wavelengths=SOYBEAN_WAVELENGTHS, delta=delta)
    for quantity in ("reflectance", "transmittance"):
        c = compare(leaf, table, quantity=quantity)
        assert len(c.wavelengths) == 7 and c.interpolated == 0 and not len(c.left_out)
        np.testing.assert_allclose(c.measured, reference[:, 0 if quantity == "reflectance" else 1])
        assert c.points_within == 7, c.summary()
        # sparse: the colour is refused with colorimetry's reason, the rest is reported
        assert np.isnan(c.delta_E) and "covers 465-800 nm, only 70.5%" in c.delta_E_note
        text = c.summary()
        assert "Delta E 2000: not computed" in text and "7 of 7 points" in text and "RMSE" in text
        assert c.as_dict()["delta_E_2000"] is None


# --- reading measured files ------------------------------------------------------------------


def test_measured_files_in_every_format(tmp_path):
    import xarray as xr

    wavelengths, values, u = np.array([400.0, 500.0, 600.0]), np.array([0.2, 0.3, 0.4]), np.array([0.01, 0.02, 0.03])
    xr.Dataset({"reflectance": ("wavelength", values), "reflectance_uncertainty": ("wavelength", u)},
               coords={"wavelength": wavelengths}).to_netcdf(tmp_path / "m.nc")
    (tmp_path / "m.txt").write_text("# a spectrometer's export\n600 0.4 0.03\n400 0.2 0.01\n500 0.3 0.02\n")
    (tmp_path / "m.csv").write_text("wavelength;R\n400;0.2\n500;0.3\n600;0.4\n")
    for name, uncertain in (("m.nc", True), ("m.txt", True), ("m.csv", False)):
        spectrum = read_measured(tmp_path / name)
        np.testing.assert_array_equal(spectrum.wavelengths, wavelengths)
        np.testing.assert_array_equal(spectrum.values, values)
        if uncertain:
            np.testing.assert_array_equal(spectrum.uncertainty, u)
        else:
            assert spectrum.uncertainty is None
    # a result file is a measured spectrum too: its certified mu is the uncertainty
    other = synthetic([0.2, 0.3, 0.4], [400, 500, 600]).write(tmp_path / "other.json")
    spectrum = read_measured(other)
    np.testing.assert_allclose(spectrum.uncertainty, vm.hoeffding_mu(10**6, 0.01))


@pytest.mark.parametrize("text, message", [
    ("400,20\n500,30\n", r"fractions in \[0, 1\] \(got up to 30.*percentages\? divide by 100"),
    ("0.4,0.2\n0.5,0.3\n", r"must be in nm \(got 0.4-0.5.*micrometres"),
    ("400,0.2\n400,0.3\n", r"wavelengths must be distinct"),
    ("400,0.2,0.1,0.3\n", r"plain rows must be wavelength,value\[,uncertainty\]"),
    ("wavelength,a,b\n400,0.1,0.2\n", r"bad.csv: it does not tell whether it holds reflectance or transmittance"),
    ("400,0.2\n500,x\n", r"line 2: expected numbers"),
    ("400,0.2,-0.1\n", r"measurement_uncertainty must be finite and >= 0"),
])
def test_bad_measured_files_are_refused_with_the_reason(tmp_path, text, message):
    (tmp_path / "bad.csv").write_text(text)
    with pytest.raises(ValueError, match=message):
        read_measured(tmp_path / "bad.csv")


@pytest.mark.parametrize("text, message", [
    ("wavelength,reflectance\n400,0.2\n550,-0.02\n600,-0.1\n",
     r"measured reflectance must lie in \[0, 1\] \(spectrum.csv, column 'reflectance': -0.02 at 550 nm is below 0; 2 "
     r"such points\): a reflectance is a fraction — give the measurement's uncertainty if these are measurement noise"),
    ("400,0.2\n700,1.2\n", r"\(spectrum.csv, column 'column 2': 1.2 at 700 nm is above 1; 1 such point\)"),
    ("wavelength,reflectance,uncertainty\n400,-0.02,0.01\n",
     r"-0.02 at 400 nm is below 0 by more than its uncertainty 0.01"),
])
def test_measured_values_a_fraction_cannot_take_are_refused_by_file_column_and_wavelength(tmp_path, text, message):
    (tmp_path / "spectrum.csv").write_text(text)
    with pytest.raises(ValueError, match=message):
        compare(synthetic([0.2, 0.3], [400, 500]), tmp_path / "spectrum.csv")


def test_measurement_noise_within_its_uncertainty_is_compared(tmp_path):
    (tmp_path / "spectrum.csv").write_text("wavelength,reflectance,uncertainty\n400,-0.005,0.01\n500,1.004,0.01\n")
    spectrum = read_measured(tmp_path / "spectrum.csv")
    np.testing.assert_array_equal(spectrum.values, [-0.005, 1.004])
    import xarray as xr

    xr.Dataset({"transmittance": ("wavelength", [0.1, 1.3 / 1.2])}, coords={"wavelength": [400.0, 500.0]}).to_netcdf(
        tmp_path / "t.nc")
    with pytest.raises(ValueError, match=r"measured transmittance must lie in \[0, 1\] \(t.nc, column "
                                         r"'transmittance': 1.08333 at 500 nm is above 1"):
        read_measured(tmp_path / "t.nc", quantity="transmittance")


def test_bad_comparisons_are_refused_with_the_reason(tmp_path):
    result = synthetic([0.2, 0.3], [400, 500])
    with pytest.raises(ValueError, match=r"lie outside the measured range 600-700 nm.*nothing to compare"):
        compare(result, ([600, 700], [0.1, 0.2]))
    with pytest.raises(ValueError, match=r"quantity must be one of reflectance, transmittance, absorptance"):
        compare(result, ([400, 500], [0.1, 0.2]), quantity="colour")
    with pytest.raises(ValueError, match=r"illuminant must be a name of colour.SDS_ILLUMINANTS"):
        compare(result, ([400, 500], [0.1, 0.2]), illuminant="D99")
    with pytest.raises(ValueError, match=r"measured must end in one of \.csv"):
        compare(result, tmp_path / "m.xlsx")
    with pytest.raises(ValueError, match=r"measured file not found"):
        compare(result, tmp_path / "missing.csv")
    with pytest.raises(ValueError, match=r"measurement_uncertainty must be a number or one value per measured"):
        compare(result, ([400, 500], [0.1, 0.2]), measurement_uncertainty=[0.1, 0.2, 0.3])
    with pytest.raises(ValueError, match=r"theta_i must be one of the result's angles \[8.0\] \(got 9\)"):
        compare(result, ([400, 500], [0.1, 0.2]), theta_i=9)


def test_exact_agreement_one_point_and_an_uncertified_result():
    result = synthetic([0.2, 0.3, 0.4], [400, 500, 600])
    exact = compare(result, ([400, 600], [0.2, 0.4]))  # 500 nm interpolated: 0.3
    assert exact.rmse == pytest.approx(0, abs=1e-15) and exact.interpolated == 1 and exact.points_within == 3
    single = compare(result, ([500], [0.25]))  # one measured point: one compared, the rest left out
    assert len(single.wavelengths) == 1 and list(single.left_out) == [400, 600]
    assert "at least two wavelengths" in single.delta_E_note
    broken = compare(synthetic([0.2, 0.3, 0.4], [400, 500, 600], violations=3), ([400, 600], [0.2, 0.4]))
    assert np.all(np.isnan(broken.certified_mu)) and np.isnan(broken.share_within) and broken.points_within == 0
    assert "NOT CERTIFIED" in broken.summary() and broken.as_dict()["share_within"] is None


def test_measured_spectrum_checks_its_input():
    spectrum = MeasuredSpectrum.of([500, 400], [0.3, 0.2], [0.02, 0.01], source="s")
    np.testing.assert_array_equal(spectrum.wavelengths, [400, 500])
    np.testing.assert_array_equal(spectrum.uncertainty, [0.01, 0.02])
    with pytest.raises(ValueError, match="one length"):
        MeasuredSpectrum.of([400, 500], [0.2])


# --- the command line ------------------------------------------------------------------------


def test_cli_compare_plot_and_colour_json(dark_skin, patch_csv, tmp_path):
    path = str(dark_skin.write(tmp_path / "dark_skin.json"))
    printed = virtspec("compare", path, patch_csv, "--json", "--plot", str(tmp_path / "c.svg"))
    assert printed.returncode == 0, printed.stderr
    data = json.loads(printed.stdout)
    assert data["points_within"] == COMPARED and data["result"] == "dark_skin.json" and data["delta_E_2000"] < 0.5
    assert (tmp_path / "c.svg").read_text().lstrip().startswith("<?xml")
    printed = virtspec("compare", path, write_patch("light skin", tmp_path / "wrong.csv"), "--illuminant", "A")
    assert printed.returncode == 0 and "Delta E 2000 = " in printed.stdout and "under A" in printed.stdout
    printed = virtspec("plot", path, "--against", patch_csv)
    assert printed.returncode == 0, printed.stderr
    assert (tmp_path / "dark_skin_vs_dark_skin.png").stat().st_size > 0 and "plot: " in printed.stdout
    printed = virtspec("colour", path, "--json")
    assert printed.returncode == 0, printed.stderr
    colour_ = json.loads(printed.stdout)
    assert set(colour_) >= {"XYZ", "Lab", "sRGB", "hex", "coverage", "note", "illuminant", "observer"}
    assert colour_["hex"].startswith("#") and len(colour_["hex"]) == 7 and colour_["coverage"] > 0.99
    printed = virtspec("compare", path, str(tmp_path / "missing.csv"))
    assert printed.returncode == 1 and "virtspec: error: measured file not found" in printed.stderr


@pytest.mark.parametrize("text, message", [
    ("wavelength,reflectance\n400,0.2\n500,\n600,0.4\n", r"bad.csv, line 3: no reflectance value \(empty or NaN"),
    ("400,0.2\n500,nan\n600,nan\n", r"line 2: no reflectance value .* and 1 more such rows"),
    ("wavelength,reflectance,uncertainty\n400,0.2,0.01\n500,0.3,\n", r"line 3: no uncertainty"),
    ("400;500\n400;0,5\n500;0,6\n", r"line 1: '400,500' holds wavelengths where the other rows hold values"),
    ("wavelength,transmittance\n400,0.2\n500,0.3\n", r"bad.csv holds transmittance, no reflectance column"),
])
def test_gaps_and_headers_of_numbers_are_refused_by_line_never_dropped(tmp_path, text, message):
    (tmp_path / "bad.csv").write_text(text)
    with pytest.raises(ValueError, match=message):
        read_measured(tmp_path / "bad.csv")


def test_a_netcdf_spectrum_with_nan_is_refused_by_wavelength(tmp_path):
    import xarray as xr

    values = np.array([0.2, np.nan, 0.4])
    xr.Dataset({"reflectance": ("wavelength", values)}, coords={"wavelength": [400.0, 500.0, 600.0]}).to_netcdf(
        tmp_path / "m.nc")
    with pytest.raises(ValueError, match=r"m.nc: reflectance is NaN at 1 wavelength \(the first 500 nm, index 1\)"):
        read_measured(tmp_path / "m.nc")
