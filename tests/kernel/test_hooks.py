"""
Tests of :mod:`virtspec_mi.kernel.hooks`: the members every exit hook has.

The base class states its defaults (a per-ray hook, no sums, no incidence, not spectral,
the beam meets the specimen, pairing 0) and refuses to be used unimplemented; a subclass
with plain values pickles (a Dask worker receives it). The kernel's use of the hooks is
tested through the instruments that have one (the goniophotometer, the gloss meter, the
sphere).

References
----------
Baranoski et al. (2001), Sect. 3.
"""

from __future__ import annotations

import dataclasses
import pickle

import numpy as np
import pytest

from virtspec_mi.kernel.hooks import ChunkRays, ExitHook


class TwoBins(ExitHook):
    """Reflected rays in bin 0, transmitted in bin 1, the rest not binned (code 2)."""

    def __init__(self, label: str) -> None:
        self.label = label

    @property
    def size(self) -> int:
        return 2

    def bin(self, wo, fate, phi_i, wi=None):
        fate = np.asarray(fate)
        return np.where(fate == 1, 0, np.where(fate == 2, 1, self.size))


def test_defaults_of_the_base_class():
    hook = ExitHook()
    assert hook.needs_rays is False and hook.sums == () and hook.incidence is False and hook.spectral is False
    specimen = object()
    assert hook.beam_bsdf(specimen) is specimen
    assert hook.pairing(37.5) == 0


def test_the_base_class_refuses_to_be_used_unimplemented():
    hook = ExitHook()
    with pytest.raises(NotImplementedError):
        hook.size
    with pytest.raises(NotImplementedError):
        hook.bin(None, None, 0.0)
    with pytest.raises(NotImplementedError):
        hook.exits(None)


def test_a_plain_value_hook_pickles_and_keeps_its_bins():
    hook = pickle.loads(pickle.dumps(TwoBins("a")))
    assert hook.label == "a" and hook.size == 2
    np.testing.assert_array_equal(hook.bin(None, [0, 1, 2, 3, 4], 0.0), [2, 0, 1, 2, 2])


def test_chunk_rays_has_the_documented_members():
    names = [f.name for f in dataclasses.fields(ChunkRays)]
    assert names == ["lanes", "slot", "root", "wavelengths", "specimen", "column", "ray_index", "safe_point"]
    rays = ChunkRays({}, None, 1, np.array([500.0]), None, lambda v, k, s: v, lambda p, s: p)
    assert rays.safe_point is None and rays.ray_index(3, None) == 3
