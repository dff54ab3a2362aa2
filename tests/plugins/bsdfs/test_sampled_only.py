"""
Tests of :mod:`virtspec_mi.plugins.bsdfs.sampled_only`: the base of the specimens that exist
only through ``sample()``.

``eval`` and ``pdf`` are zero; a subclass's parameters appear in ``mi.traverse`` as exact
Float64 values, and an update hands the new values to ``set_parameters``; a width other than
one, or a parameter the base does not have, is refused with its name.

References
----------
Mitsuba 3, ``mi.BSDF`` (Python BSDF plugins), ``mi.traverse`` / ``SceneParameters``.
"""

from __future__ import annotations

import numpy as np
import pytest


@pytest.fixture(scope="module")
def classes(mi):
    from virtspec_mi.plugins.bsdfs.sampled_only import SampledOnlyBSDF

    class Absorber(SampledOnlyBSDF):
        """A specimen with one parameter, ``rate``, in [0, 1]."""

        def __init__(self, props):
            super().__init__(props)
            self.rate = props.get("rate", 1.66e-4)
            self.applied = []

        def exposed_parameters(self):
            return {"rate": self.rate}

        def set_parameters(self, values):
            if "rate" in values and not 0.0 <= values["rate"] <= 1.0:
                raise ValueError(f"Absorber: 'rate' must satisfy 0 <= rate <= 1 (got {values['rate']:g})")
            self.applied.append(dict(values))
            self.rate = values.get("rate", self.rate)

    return SampledOnlyBSDF, Absorber


def test_eval_and_pdf_are_zero(mi, classes):
    base, _ = classes
    bsdf = base(mi.Properties())
    si = mi.SurfaceInteraction3f()
    ctx = mi.BSDFContext()
    wo = mi.Vector3f(0.0, 0.0, 1.0)
    assert np.all(np.array(bsdf.eval(ctx, si, wo)) == 0.0) and np.all(np.array(bsdf.pdf(ctx, si, wo)) == 0.0)
    value, pdf = bsdf.eval_pdf(ctx, si, wo)
    assert np.all(np.array(value) == 0.0) and np.all(np.array(pdf) == 0.0)
    assert bsdf.exposed_parameters() == {} and bsdf.wavelength_range is None and not bsdf.wavelength_independent
    bsdf.check_wavelengths([100.0, 5000.0])  # no spectral parameter: nothing refused
    bsdf.set_parameters({})
    with pytest.raises(ValueError, match="SampledOnlyBSDF has no parameter 'alpha' to set"):
        bsdf.set_parameters({"alpha": 1.0, "beta": 2.0})


def test_parameters_traverse_as_exact_float64_and_update(mi, classes):
    _, absorber = classes
    bsdf = absorber(mi.Properties())
    params = mi.traverse(bsdf)
    assert list(params.keys()) == ["rate"]
    assert float(params["rate"][0]) == 1.66e-4  # Float64: exactly as given
    params["rate"] = mi.Float64(0.25)
    params.update()
    assert bsdf.rate == 0.25 and bsdf.applied[-1] == {"rate": 0.25}


def test_updates_are_refused_with_the_name(mi, classes):
    _, absorber = classes
    bsdf = absorber(mi.Properties())
    params = mi.traverse(bsdf)
    params["rate"] = mi.Float64(2.0)
    with pytest.raises(ValueError, match=r"'rate' must satisfy 0 <= rate <= 1 \(got 2\)"):
        params.update()
    params = mi.traverse(bsdf)
    params["rate"] = mi.Float64([0.1, 0.2])
    with pytest.raises(ValueError, match=r"Absorber: 'rate' must be one number \(got 2\)"):
        params.update()
