"""
Tests of :mod:`virtspec_mi.applications.targets.bands`: a sensor's response as a functional.

Trapezoid weights integrate linear functions exactly; a band's functional has non-negative
weights summing to 1, so a constant spectrum reads its constant and a linear one reads the
response-weighted mean wavelength; every way of giving a response (a Sentinel-2 name, edges,
``"650-680"``, a dict, a file) gives the band it says, and every bad one is refused with the
reason.

References
----------
ESA (2015), *Sentinel-2 User Handbook*, Table 1.
"""

from __future__ import annotations

import numpy as np
import pytest

from virtspec_mi.applications.targets.bands import SENTINEL_2, band, quadrature_weights


def test_trapezoid_weights_integrate_linear_functions_exactly():
    grid = np.array([400.0, 401.0, 403.5, 410.0, 420.0])
    weights = quadrature_weights(grid)
    assert weights.sum() == pytest.approx(20.0)
    assert weights @ (2.0 * grid + 1.0) == pytest.approx((420.0 ** 2 - 400.0 ** 2) + 20.0)
    np.testing.assert_array_equal(quadrature_weights([550.0]), [1.0])


def test_a_sentinel_band_is_its_rectangle():
    b04 = band("S2A_B04")
    centre, width = SENTINEL_2["B04"]
    assert b04.name == "B04" and b04.edges == (centre - width / 2, centre + width / 2)
    assert np.all(np.diff(b04.wavelengths) <= 1.0 + 1e-9) and np.all(b04.response == 1.0)
    assert "rectangular" in b04.source
    assert band("b8a").name == "B8A"


def test_a_functional_reads_the_weighted_mean():
    functional = band((650.0, 680.0)).functional("transmittance")
    assert functional.name == "band_650-680" and functional.quantity == "transmittance"
    assert np.all(functional.weights > 0) and functional.weights.sum() == pytest.approx(1.0)
    assert functional.weights @ np.full(functional.wavelengths.size, 0.37) == pytest.approx(0.37)
    assert functional.weights @ functional.wavelengths == pytest.approx(665.0)  # linear q: the centre
    assert "650-680 nm" in functional.long_name


def test_a_triangular_response_from_a_dict_and_a_file(tmp_path):
    triangle = {500.0: 0.0, 510.0: 1.0, 520.0: 0.0}
    from_dict = band(triangle, name="tri")
    assert from_dict.edges == (510.0, 510.0) and from_dict.source == "given"
    path = tmp_path / "response.csv"
    path.write_text("# nm, response\n520, 0\n500, 0\n505, 0.5\n510, 1\n515, 0.5\n")
    from_file = band(str(path))
    np.testing.assert_array_equal(from_file.wavelengths, [500.0, 505.0, 510.0, 515.0, 520.0])  # sorted
    functional = from_file.functional()
    assert functional.weights @ functional.wavelengths == pytest.approx(510.0)
    assert from_file.name == "response" and from_file.source == "file response.csv"


def test_edges_as_text_and_the_step():
    assert band("650-680").edges == (650.0, 680.0)
    coarse = band((650.0, 680.5), step=10.0)
    np.testing.assert_array_equal(coarse.wavelengths, [650.0, 660.0, 670.0, 680.0, 680.5])


@pytest.mark.parametrize("response, message", [
    ((680.0, 650.0), r"band edges must be 0 < low < high nm \(got 680, 650\)"),
    (("low", 650.0), r"band edge low must be a number \(got 'low'\)"),
    ((600.0, float("nan")), r"band edge high must be a finite number"),
    ({500.0: -0.1, 510.0: 1.0}, r"band band: the response must be finite, >= 0 and somewhere > 0"),
    ({500.0: 0.0, 510.0: 0.0}, r"the response must be finite, >= 0 and somewhere > 0"),
    ({-5.0: 1.0}, r"wavelengths must be positive nm"),
    ("no_such_band_file.txt", r"no file 'no_such_band_file.txt'"),
    (42, r"response must be a Sentinel-2 band .* \(got 42\)"),
])
def test_bad_responses_are_refused_with_the_reason(response, message):
    with pytest.raises(ValueError, match=message):
        band(response)


def test_bad_files_and_steps_are_refused(tmp_path):
    three = tmp_path / "three.txt"
    three.write_text("500 1 2\n510 1 2\n")
    with pytest.raises(ValueError, match=r"two columns \(wavelength nm, response\), got 3"):
        band(three)
    words = tmp_path / "words.txt"
    words.write_text("500 high\n")
    with pytest.raises(ValueError, match=r"two numeric columns"):
        band(words)
    with pytest.raises(ValueError, match=r"step must be a positive number of nm \(got 0\)"):
        band("B04", step=0)
