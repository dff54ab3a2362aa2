"""
Tests of :mod:`virtspec_mi.runtime` (its ``__init__``): the Mitsuba variant, set up once, with
every plugin registered.

References
----------
Mitsuba 3, ``mi.set_variant``, ``mi.register_bsdf``, ``mi.register_integrator``.
"""

from __future__ import annotations

from virtspec_mi import runtime
from virtspec_mi.plugins import SPECIMENS


def test_the_variant_is_the_default_unless_the_environment_names_one(monkeypatch):
    monkeypatch.delenv("VIRTSPEC_VARIANT", raising=False)
    assert runtime.variant() == runtime.DEFAULT_VARIANT == "llvm_ad_spectral"
    monkeypatch.setenv("VIRTSPEC_VARIANT", "cuda_ad_spectral")
    assert runtime.variant() == "cuda_ad_spectral"


def test_mitsuba_is_set_up_once(mi, monkeypatch):
    monkeypatch.delenv("VIRTSPEC_VARIANT", raising=False)
    assert runtime.mitsuba() is mi and mi.variant() == runtime.variant()
    render = mi.render
    assert runtime.mitsuba() is mi and mi.render is render  # not wrapped twice
    # the wrapper that lets the integrator's ValueError through (tests/api/test_api.py renders with a bad spp)
    assert getattr(mi.render, "clears_spectrophotometer_errors", False)


def load(mi, spec: dict) -> str:
    """``"loaded"``, or the message of the error loading ``spec`` raised."""

    try:
        mi.load_dict(spec)
    except Exception as error:  # Mitsuba wraps a plugin's own error in a RuntimeError
        return str(error)
    return "loaded"


def test_every_plugin_is_registered_and_loads(mi):
    assert set(runtime.PLUGINS) == {"virtspec_flipped", "spectrophotometer"}
    assert "Plugin \"no_such_plugin_38\" not found" in load(mi, {"type": "no_such_plugin_38"})
    for name in SPECIMENS:  # each loads, or is refused by its own constructor (tabulated needs a table)
        outcome = load(mi, {"type": name})
        assert outcome == "loaded" or (f"{name}: " in outcome and "not found" not in outcome), (name, outcome)
    assert mi.load_dict({"type": "virtspec_flipped", "nested": {"type": "diffuse"}}) is not None
    assert mi.load_dict({"type": "spectrophotometer"}) is not None
    runtime.register()  # again: harmless
    assert mi.load_dict({"type": "simple_dielectric"}) is not None


def test_specimens_lists_each_with_its_first_docstring_line(mi):
    listed = runtime.specimens()
    assert set(SPECIMENS) <= set(listed)
    for name, line in listed.items():
        assert line and "\n" not in line and "(see the module docstring)" not in line, name

