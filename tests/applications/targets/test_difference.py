"""
Tests of :mod:`virtspec_mi.applications.targets.difference`: certified ΔE between two colours.

Two exact colours give a point interval equal to CIEDE2000 and the Euclidean ΔE*ab; boxes
widen the intervals to enclose the point values; the deltas add (a union bound); results
and targets' results are taken by their colour; everything else is refused with what was
given.

References
----------
CIE 015:2018, §8.3; Sharma, Wu & Dalal (2005), Color Res. Appl. 30(1), 21–30 (test data).
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from virtspec_mi.applications.targets.difference import ColourDifference, colour_difference


@pytest.mark.parametrize("a, b, expected", [  # Sharma et al. (2005), Table 1: pairs 1, 7 and 17
    ([50.0, 2.6772, -79.7751], [50.0, 0.0, -82.7485], 2.0425),
    ([50.0, 0.0, 0.0], [50.0, -1.0, 2.0], 2.3669),
    ([50.0, 2.5, 0.0], [73.0, 25.0, -18.0], 27.1492),
])
def test_exact_colours_give_ciede2000_and_enclosures_of_it(a, b, expected):
    difference = colour_difference(a, b)
    assert difference.dE00 == pytest.approx(expected, abs=1e-4)
    assert difference.dEab == pytest.approx(np.linalg.norm(np.subtract(a, b)))
    lo, hi = difference.dE00_interval  # rigorous, not exact even for points (colorimetry.delta_e)
    assert 0.0 <= lo <= difference.dE00 <= hi
    assert difference.dEab_interval == pytest.approx((difference.dEab, difference.dEab))  # exact
    assert difference.delta == 0.0


def test_a_colour_and_itself_differ_by_nothing():
    same = colour_difference([40.0, 12.0, -7.0], (40.0, 12.0, -7.0))
    assert same.dE00 == 0.0 and same.dE00_interval == (0.0, 0.0) and same.dEab_interval == (0.0, 0.0)


def certified(Lab, half_width, delta=0.01, note=""):
    Lab = np.asarray(Lab, dtype=np.float64)
    return SimpleNamespace(Lab=Lab, Lab_interval=np.stack([Lab - half_width, Lab + half_width], axis=1),
                           delta=delta, note=note)


def test_boxes_widen_the_intervals_and_the_deltas_add():
    a = certified([60.0, 10.0, 20.0], 0.5, delta=0.01)
    difference = colour_difference(a, [58.0, 12.0, 18.0])
    assert difference.delta == 0.01
    assert difference.dEab_interval[0] < difference.dEab < difference.dEab_interval[1]
    assert difference.dE00_interval[0] < difference.dE00 < difference.dE00_interval[1]
    both = colour_difference(a, certified([58.0, 12.0, 18.0], 0.2, delta=0.005))
    assert both.delta == pytest.approx(0.015)
    assert both.dEab_interval[1] > difference.dEab_interval[1]
    # exact over the boxes: the farthest corners are 2·0.7·√3 further apart than the centres at most
    assert both.dEab_interval[1] <= difference.dEab + 0.7 * np.sqrt(3) + 1e-9


def test_results_and_targets_are_taken_by_their_colour():
    colour = certified([50.0, 0.0, 0.0], 0.1)
    result = SimpleNamespace(colour=lambda: colour)  # a result: result.colour()
    target = SimpleNamespace(colour=colour)  # a colour target's result: its colour
    assert colour_difference(result, target).dE00 == 0.0


@pytest.mark.parametrize("given, message", [
    ("red", r"a must be a certified colour .* \(got 'red': not a colour\)"),
    ([1.0, 2.0], r"a must be a certified colour .*, finite \(got \[1.0, 2.0\]\)"),
    ([1.0, np.nan, 2.0], r", finite \(got \[1.0, nan, 2.0\]\)"),
    (object, r"a must be a certified colour .* \(got type "),
    (SimpleNamespace(Lab=np.zeros(3), note="no rays"), r"a: the colour has no certified interval \(no rays\); give"),
    (SimpleNamespace(Lab=np.zeros(3), Lab_interval=np.full((3, 2), np.nan), delta=0.1, note="escaped"),
     r"a: the colour has no certified interval \(escaped\)"),
    (SimpleNamespace(target=SimpleNamespace(kind="index")), r"\(got the result of a index target: not a colour\)"),
])
def test_what_is_not_a_colour_is_refused(given, message):
    with pytest.raises(ValueError, match=message):
        colour_difference(given, [50.0, 0.0, 0.0])


def test_summary_and_dictionary():
    difference = ColourDifference(1.0, (0.5, 1.5), 2.0, (1.0, 3.0), 0.02)
    assert difference.summary() == ("dE00 = 1.0000 in [0.5000, 1.5000], dE*ab = 2.0000 in [1.0000, 3.0000] "
                                    "(certified together at delta = 0.02; dE00 a rigorous enclosure, dE*ab exact "
                                    "over the boxes)")
    assert difference.as_dict() == {"dE00": 1.0, "dE00_interval": [0.5, 1.5], "dEab": 2.0,
                                    "dEab_interval": [1.0, 3.0], "delta": 0.02}
