"""
Tests of :mod:`virtspec_mi.exchange.conventions`: the engines' table grids, from their generators' formulas.

Cycles' nodes include their clamped end points, α = r², and its index nodes satisfy
F₀ = ((η − 1)/(η + 1))² = s⁴ from η = 1 to 1.9801/0.0199 ≈ 99.5; Filament's and Unreal's are texel centres,
Filament's roughest row first; every convention's memory order names its axes and their
sizes; unknown engines and models are refused with the allowed values.

References
----------
Kulla & Conty (2017); Karis (2013) (see the module).
"""

from __future__ import annotations

import numpy as np
import pytest

from virtspec_mi.exchange.conventions import (
    ENGINES,
    convention,
    cycles_ior,
    cycles_mu,
    cycles_roughness,
    texel_centres,
)


def test_cycles_nodes_include_their_clamped_ends():
    nodes = cycles_roughness(5)
    np.testing.assert_array_equal(nodes, [1e-4, 0.25, 0.5, 0.75, 1.0])
    np.testing.assert_array_equal(cycles_mu(5), nodes)


def test_cycles_index_nodes_are_fresnel_f0_of_s_to_the_fourth():
    eta = cycles_ior(16)
    s = np.clip(np.arange(16) / 15, 1e-4, 0.99)
    np.testing.assert_allclose(((eta - 1) / (eta + 1)) ** 2, s ** 4, rtol=1e-9, atol=1e-20)
    assert eta[0] == pytest.approx(1.0, abs=1e-7)
    assert eta[-1] == pytest.approx(1.9801 / 0.0199, rel=1e-12) == pytest.approx(99.5, abs=0.01)  # s = 0.99
    assert np.all(np.diff(eta) > 0)


def test_texel_centres():
    np.testing.assert_array_equal(texel_centres(4), [0.125, 0.375, 0.625, 0.875])


def axis(conv, name):
    return {"mu": conv.mu, "alpha": conv.alpha, "eta": conv.eta}[name]


@pytest.mark.parametrize("engine, model, shape", [("cycles", "conductor", (32, 32)), ("cycles", "glass", (16, 16, 16)),
                                                  ("filament", "conductor", (128, 128)),
                                                  ("unreal", "conductor", (32, 128))])
def test_memory_orders_name_axes_of_the_engines_sizes(engine, model, shape):
    conv = convention(engine, model)
    assert conv.name == engine and conv.source and conv.notes
    assert tuple(axis(conv, name).size for name in conv.order) == shape
    assert np.all((conv.mu > 0) & (conv.mu <= 1)) and np.all((conv.alpha > 0) & (conv.alpha <= 1))
    np.testing.assert_allclose(conv.alpha, conv.roughness ** 2)


def test_cycles_glass_and_conductor():
    glass = convention("cycles", "glass")
    assert glass.extra == {"eavg_order": ("eta", "alpha")} and glass.eta.size == 16
    conductor = convention("cycles")
    assert conductor.eta is None and conductor.order == ("mu", "alpha") and conductor.alpha[0] == 1e-8


def test_filament_puts_the_roughest_row_first():
    conv = convention("filament")
    assert conv.roughness[0] == 1.0 and conv.roughness[1] == 127.5 / 128 and conv.roughness[-1] == 1.5 / 128
    assert np.all(np.diff(conv.roughness) <= 0) and conv.mu[0] == 0.5 / 128


def test_unreal_grid():
    conv = convention("unreal")
    np.testing.assert_array_equal(conv.roughness, (np.arange(32) + 0.5) / 32)
    assert conv.order == ("alpha", "mu")


@pytest.mark.parametrize("engine, model, message", [
    ("godot", "conductor", r"engine must be one of cycles, filament, unreal \(got 'godot'\)"),
    ("cycles", "plastic", r"model must be 'conductor' or 'glass' \(got 'plastic'\)"),
    ("filament", "glass", r"engine 'filament' has no glass table"),
    ("unreal", "glass", r"engine 'unreal' has no glass table"),
])
def test_refusals(engine, model, message):
    with pytest.raises(ValueError, match=message):
        convention(engine, model)
    assert set(ENGINES) == {"cycles", "filament", "unreal"}
