"""The validate-once boundary (virtspec_mi/base/checks.py): limits checked before anything is built,
numbers that are not numbers, messages that show the value given. Issue 12."""

from __future__ import annotations

import math
import resource

import numpy as np
import pytest

from virtspec_mi.base import checks
from virtspec_mi.base.checks import (
    MAX_RAYS,
    MAX_VALUES,
    check_float32,
    check_rays,
    check_readings,
    check_wavelength_range,
    number,
    parse_theta_i,
    parse_wavelengths,
)
from virtspec_mi.settings import Settings


def _fast_and_small(call, message: str) -> None:
    """
    ``call`` raises ValueError matching ``message`` without building the grid: the process's
    peak memory grows by less than 50 MiB (a grid of 10^8 values would take gigabytes). No
    timing: the machine's load must not decide a test.
    """

    before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    with pytest.raises(ValueError, match=message):
        call()
    assert resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - before < 50 * 1024  # KiB


@pytest.mark.parametrize("call, message", [
    (lambda: parse_wavelengths("400:700:1e-6"), r"'400:700:1e-6' holds 300,000,001 values; .*at most 100,000"),
    (lambda: parse_theta_i("0:90:1e-7"), r"theta_i range '0:90:1e-7' holds 900,000,001 values; .*at most 100,000"),
    (lambda: parse_wavelengths("1:1e12:1"), r"holds 1,000,000,000,000 values"),
    (lambda: parse_wavelengths("1:1e300:1e-300"), r"holds inf values|holds 1e\+600"),
    (lambda: parse_wavelengths("400:inf:1"), r"wavelengths range '400:inf:1' needs finite start, stop and step"),
    (lambda: parse_theta_i("0:inf:1"), r"theta_i range '0:inf:1' needs finite start, stop and step"),
    (lambda: parse_wavelengths("nan:700:1"), r"wavelengths must be a number \(got NaN\)"),
    (lambda: parse_wavelengths(" ".join(["500"] * (MAX_VALUES + 1))), "at most 100,000 values per call"),
    (lambda: parse_wavelengths("400:1300:0.01 2000:2200:0.01"), "at most 100,000 values per call"),
    (lambda: parse_wavelengths(range(MAX_VALUES + 1)), r"at most 100,000 values per call \(got 100,001\)"),
    (lambda: parse_wavelengths(iter(lambda: 500.0, None)), "at most 100,000 values per call"),  # endless
])
def test_grids_are_counted_before_they_are_built(call, message):
    _fast_and_small(call, message)


def test_grids_at_the_limit_are_built():
    assert len(parse_wavelengths(f"1:{MAX_VALUES}:1")) == MAX_VALUES
    assert len(parse_theta_i(np.linspace(0, 90, MAX_VALUES))) == MAX_VALUES


@pytest.mark.parametrize("value", [1e-300, 1e39, 1e-4, 1.000001e6, float("inf"), 0.0, -400.0])
def test_wavelengths_float32_cannot_hold_are_refused(value):
    # 1e-300 and 1e39 became 0 and inf in the kernel's float32 and were traced
    with pytest.raises(ValueError, match=r"wavelengths must be finite and > 0 nm, 0.001 <= wavelength <= 1e\+06"):
        Settings(wavelengths=value)
    assert Settings(wavelengths=[1e-3, 1e6]).wavelengths == (1e-3, 1e6)


def test_messages_show_every_digit_given():
    with pytest.raises(ValueError, match=r"\(got 399.99999999\)"):
        check_wavelength_range([399.99999999], (400, 2500), "abm_b")  # said "(got 400)"
    with pytest.raises(ValueError, match=r"\(got 90.00000000001\)"):
        Settings(theta_i=90.00000000001)
    with pytest.raises(ValueError, match=r"\(got 95\)"):
        Settings(theta_i=95.0)
    with pytest.raises(ValueError, match=r"mu must satisfy 0 < mu < 0.5 \(got 0.50000000001\)"):
        Settings(mu=0.50000000001)


@pytest.mark.parametrize("name", ["theta_i", "phi_i", "mu", "delta", "rays", "pilot_rays", "pilot_delta",
                                  "seed", "chunk_size", "wavelengths"])
def test_integers_beyond_the_float_range_name_the_setting(name):
    # OverflowError: int too large to convert to float
    with pytest.raises(ValueError, match=f"^{name} must .*an integer of 401 digits"):
        Settings(**{name: 10**400})


@pytest.mark.parametrize("value", [True, np.bool_(True), "x", None, [1.0], complex(1, 0)])
def test_what_is_not_a_number(value):
    with pytest.raises(ValueError, match="speed must be a number"):
        number("speed", value)
    assert number("speed", "2.5") == 2.5 and number("speed", np.float32(2.5)) == 2.5


def test_numpy_booleans_are_not_numbers():
    for name in ("theta_i", "mu", "rays", "seed"):
        with pytest.raises(ValueError, match=name):
            Settings(**{name: np.bool_(True)})


def test_check_rays_names_the_setting():
    with pytest.raises(ValueError, match=r"pilot_rays must satisfy 1 <= pilot_rays <= 4294967295 \(got 0\)"):
        check_rays(0, name="pilot_rays")
    assert check_rays(MAX_RAYS) == MAX_RAYS and check_rays(2**40, math.inf) == 2**40


def test_check_readings_caps_readings_and_total_rays():
    check_readings(checks.MAX_READINGS, checks.MAX_TOTAL_RAYS)
    with pytest.raises(ValueError, match=r"at most 1,000,000 readings .*got 1,000,001"):
        check_readings(checks.MAX_READINGS + 1, 0)
    with pytest.raises(ValueError, match=r"at most 1e\+13 rays \(got 10,000,000,000,001"):
        check_readings(10, checks.MAX_TOTAL_RAYS + 1)


@pytest.mark.parametrize("value, ok", [
    (1.0, True), (0.0, True), (1.2e-38, True), (3.4e38, True), (-2.0, True),
    (1e-40, False), (1e39, False), (math.inf, False), (math.nan, False), (True, False), ("1", False), (10**400, False),
])
def test_check_float32(value, ok):
    def call():
        return check_float32("plugin: 'x'", value, "be a number", lambda v: True)

    if ok:
        assert call() == float(value)
    else:
        with pytest.raises(ValueError, match=r"plugin: 'x' must be a number \(a float32"):
            call()
    assert check_float32("x", math.inf, "be > 0", lambda v: v > 0, allow_inf=True) == math.inf


def test_validated_checks_each_named_argument_once_and_keeps_the_trusting_body():
    import inspect

    from virtspec_mi.base.checks import check_delta, check_mu, validated

    seen = []

    @validated(mu=check_mu, delta=check_delta)
    def rule(mu, delta, other=None):
        seen.append((mu, delta, other))
        return mu

    assert rule("0.25", delta=0.5) == 0.25 and seen[-1] == (0.25, 0.5, None)  # checked and converted
    assert inspect.signature(rule) == inspect.signature(rule.unchecked)
    with pytest.raises(ValueError, match="mu must satisfy"):  # in the order of the signature: mu first
        rule(0.7, 1.5)
    assert rule.unchecked(0.7, 1.5) == 0.7  # below the boundary: trusted as given
    with pytest.raises(TypeError, match="has no parameter"):
        validated(rays=check_mu)(lambda mu: mu)


def test_public_bound_entries_still_check_what_users_give():
    import virtspec_mi as vm

    for call, message in [(lambda: vm.hoeffding_rays(0.7, 0.01), "mu must satisfy 0 < mu < 0.5 \\(got 0.7\\)"),
                          (lambda: vm.chebyshev_rays(0.01, True), "delta must be a number"),
                          (lambda: vm.hoeffding_mu(0, 0.01), "rays must satisfy 1 <= rays"),
                          (lambda: vm.chebyshev_mu(10, 1.0), "delta must satisfy 0 < delta < 1")]:
        with pytest.raises(ValueError, match=message):
            call()
    assert vm.hoeffding_rays("0.005", "0.01") == 105_967  # strings read as numbers, as everywhere


def test_a_number_parameter_of_a_python_call_refuses_text():
    with pytest.raises(ValueError, match=r"^epsilon must be a number, not text \(got '0.1'\); write epsilon=0.1$"):
        checks.real("epsilon", "0.1")
    with pytest.raises(ValueError, match="write delta=a number"):
        checks.real("delta", "small")
    assert checks.real("epsilon", np.float32(0.25)) == 0.25 and checks.real("epsilon", 1) == 1.0
