"""
Tests of :mod:`virtspec_mi.kernel.spectra`: the wavelengths a Mitsuba object's spectra hold data for.

Each kind of limited spectrum is found with its range and its parameter (nested BSDFs by
their ``mi.traverse`` prefix, a lone texture by the name given); uniform values hold
everywhere; :func:`check_covered` refuses a wavelength outside a range with a message that
names the owner, the parameter, the range and the wavelengths as given, and accepts the
range's edges.

References
----------
Mitsuba 3 documentation, "Spectra" and "Textures".
"""

from __future__ import annotations

import pytest

from virtspec_mi.kernel.spectra import DataRange, _shown, check_covered, data_ranges

REGULAR = {"type": "regular", "wavelength_min": 400, "wavelength_max": 700, "values": "0.2, 0.5, 0.8"}
RGB = {"type": "rgb", "value": [0.2, 0.5, 0.8]}


def test_regular_irregular_and_rgb_spectra_have_their_ranges(mi):
    cie = (float(mi.MI_CIE_MIN), float(mi.MI_CIE_MAX))
    assert data_ranges(mi.load_dict({"type": "diffuse", "reflectance": REGULAR})) == [
        DataRange("reflectance", 400.0, 700.0, "a regular spectrum, 0 outside its range")]
    irregular = {"type": "irregular", "wavelengths": "420, 500, 680", "values": "0.2, 0.5, 0.8"}
    [item] = data_ranges(mi.load_dict({"type": "diffuse", "reflectance": irregular}))
    assert (item.low, item.high) == (420.0, 680.0) and "irregular" in item.kind
    [item] = data_ranges(mi.load_dict({"type": "diffuse", "reflectance": RGB}))
    assert (item.low, item.high) == cie and "RGB colour" in item.kind


def test_uniform_values_hold_everywhere(mi):
    assert data_ranges(mi.load_dict({"type": "diffuse", "reflectance": 0.5})) == []
    assert data_ranges(mi.load_dict({"type": "dielectric", "int_ior": 1.5})) == []
    check_covered(mi.load_dict({"type": "diffuse", "reflectance": 0.5}), [100.0, 2500.0], "the specimen D")


def test_nested_bsdfs_are_named_by_their_prefix(mi):
    blend = mi.load_dict({"type": "blendbsdf", "weight": 0.5,
                          "a": {"type": "diffuse", "reflectance": RGB},
                          "b": {"type": "diffuse", "reflectance": REGULAR}})
    ranges = {item.parameter: (item.low, item.high) for item in data_ranges(blend)}
    assert ranges == {"bsdf_0.reflectance": (360.0, 830.0), "bsdf_1.reflectance": (400.0, 700.0)}
    with pytest.raises(ValueError, match=r"for the specimen B: its 'bsdf_1.reflectance' is a regular spectrum"):
        check_covered(blend, [500.0, 750.0], "the specimen B")


def test_check_covered_accepts_the_edges_and_names_what_it_refuses(mi):
    bsdf = mi.load_dict({"type": "diffuse", "reflectance": REGULAR})
    check_covered(bsdf, [400.0, 550.0, 700.0], "the specimen D")
    with pytest.raises(ValueError) as refused:
        check_covered(bsdf, [399.99999999, 550.0, 701.0], "the specimen D")
    assert str(refused.value) == ("wavelengths must satisfy 400 <= wavelength <= 700 nm for the specimen D: its "
                                  "'reflectance' is a regular spectrum, 0 outside its range (got 399.99999999, 701)")


def test_a_lone_texture_takes_the_name_given_and_long_lists_are_cut(mi):
    texture = mi.load_dict(REGULAR)
    [item] = data_ranges(texture)
    assert item.parameter == ""
    with pytest.raises(ValueError, match=r"its 'mu_a' is a regular spectrum, 0 outside its range "
                                         r"\(got 300, 310, 320, 330, 340 \.\.\.\)"):
        check_covered(texture, [300.0 + 10 * k for k in range(7)], "the specimen S", "mu_a")


def test_wavelengths_are_shown_with_every_digit_given():
    assert _shown(500.0) == "500"
    assert _shown(399.99999999) == "399.99999999"
    assert _shown(512.5) == "512.5"
    assert _shown(1e20) == "1e+20"
