"""
Print the manual's sphere validation tables (docs/guide/sphere.md): the simulation against
``virtspec_mi.instruments.sphere.theory`` (through the one mapping, ``virtspec_mi.instruments.sphere.model.theory_inputs``) and the correction of
instrument readings. The manual's tables (docs/guide/sphere.md) must equal this script's output
(``tests/instruments/sphere/test_model.py``, a slow test). The same cases are asserted, one by one,
by ``tests/instruments/sphere/test_walk.py`` and ``tests/instruments/sphere/test_model.py``.

1. The ideal sphere (``tests/instruments/sphere/test_walk.py``'s grid): 150 mm, three ports
   (sample, entrance, detector) of cap fraction f each, a 0.5 grey Lambertian lit by a
   conical beam, N = 105,967 rays: the detector fraction simulated, against the flat
   model (exact cap fractions, the simulation's geometry), the cap model with cap
   fractions (Goebel; iadpython 0.5.3's ``Sphere``) and with the IAD program's r²/4R².
2. Grey samples in the 150 mm 8°/d sphere without its baffle (the theory models none):
   the readings of single-beam substitution and of the comparison method with their
   certified intervals (δ = 10⁻³), against the theory.
3. The correction (``SphereResult.corrected``) of readings in the 60 mm leaf sphere: the
   soybean leaf (``abm_b``) and a turbid slab (``turbid_slab``), R and T.

Run: python tools/sphere_validation.py   (about 15 s)
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]

import virtspec_mi as vm  # noqa: E402
from virtspec_mi.instruments.sphere import theory as st  # noqa: E402
from virtspec_mi.budgets.bounds import hoeffding_mu  # noqa: E402
from virtspec_mi.settings import Settings  # noqa: E402
from virtspec_mi.instruments.sphere.geometry import Port, Sphere  # noqa: E402
from virtspec_mi.instruments.sphere import SphereOptions  # noqa: E402
from virtspec_mi.instruments.sphere.model import theory_inputs  # noqa: E402

RAYS, DELTA = 105_967, 1e-3
LAB, LEAF = ROOT / "scenes/sphere_150mm_8d.xml", ROOT / "scenes/sphere_leaf_60mm.xml"
SLAB = {"type": "turbid_slab", "mu_a": 1.0, "mu_s": 100.0, "g": 0.75, "thickness": 0.1, "eta": 1.4}


def _scene(path: Path, bsdf: str):
    text = re.sub(r'<bsdf type="[a-z_]+">.*?</bsdf>', bsdf, path.read_text(), flags=re.S)
    return vm.mitsuba().load_string(text.replace('<default name="data_dir" value=""/>', ''))


def ideal_table() -> str:
    """Table 1: the ideal sphere's detector fraction, simulated and in three models."""

    from virtspec_mi.engine.plan import kernel_options
    from virtspec_mi.instruments.sphere.walk import SPECIMEN, Holder, holder_frame
    from virtspec_mi.kernel.tracer import ReadingPlan, tally_readings
    from virtspec_mi.runtime.scene import find_bench

    mu = hoeffding_mu(RAYS, DELTA)
    lines = ["| ρw | f | simulated | flat model (exact caps) | cap model, caps (Goebel, iadpython) "
             "| cap model, r²/4R² (IAD) | \\|sim − flat\\| / μ |", "|---|---|---|---|---|---|---|"]
    for rho_w in (0.90, 0.95, 0.98, 0.99):
        for f in (0.01, 0.05, 0.10):
            radius = st.port_radius_for_fraction(f, 75.0)
            sphere = Sphere(150, rho_w, (Port("sample", "sample", 180, 0, radius),
                                         Port("entrance", "entrance", 0, 0, radius),
                                         Port("detector", "detector", 90, 90, radius)))
            instrument = find_bench(vm.instrument_scene({"type": "diffuse", "reflectance": 0.5},
                                                             specimen_radius=radius))
            holder = Holder(0, SPECIMEN, radius, holder_frame(sphere.ports[0].axis, False))
            layout = sphere.layout([holder], [6, 7, 0], 100_000, [551.0])
            tally = tally_readings(instrument, [ReadingPlan(551.0, 0.0, 0.0, RAYS)], hook=layout,
                                   **kernel_options(Settings(theta_i=0, beam="conical")))
            simulated = tally.bins[0].reshape(4, layout.codes)[:, 0].sum() / RAYS
            kw = theory_inputs(sphere, SphereOptions(), [551.0])
            fractions = {k: kw[k] for k in ("sample_fraction", "detector_fraction", "open_fraction")}
            projected = {k: v * (1 - v) for k, v in fractions.items()}
            flat, cap, iad = (0.5 * st.detected_fraction(rho_w, 0.5, port_surface=s, **fr)
                              for s, fr in (("flat", fractions), ("cap", fractions), ("cap", projected)))
            lines.append(f"| {rho_w:.2f} | {f:.2f} | {simulated:.5f} | {flat:.5f} | {cap:.5f} | {iad:.5f} "
                         f"| {abs(simulated - flat) / mu:.2f} |")
    lines.append("")
    lines.append(f"N = {RAYS:,} rays per case, μ = {mu:.5f} (Hoeffding at δ = {DELTA:g}).")
    return "\n".join(lines)


def grey_table() -> str:
    """Table 2: grey samples in the 150 mm sphere without its baffle, substitution and comparison."""

    import dataclasses

    sphere = dataclasses.replace(vm.mitsuba().load_file(str(LAB)).integrator().sphere_options.sphere, baffle=None)
    lines = ["| ρ | substitution [certified interval] | theory | comparison [certified interval] | theory |",
             "|---|---|---|---|---|"]
    for rho in (0.05, 0.25, 0.45, 0.65, 0.85, 0.95):
        scene = _scene(LAB, f'<bsdf type="diffuse"><float name="reflectance" value="{rho}"/></bsdf>')
        cells = []
        for method in ("substitution", "comparison"):
            r = vm.sphere_measure(scene, sphere=sphere, rays=RAYS, delta=DELTA, method=method)
            low, high = r.reading_interval[0]
            theory = st.instrument_reading(rho, **r.theory_inputs())[0]
            cells += [f"{r.reading[0]:.4f} [{low:.4f}, {high:.4f}]", f"{theory:.4f}"]
        lines.append(f"| {rho:.2f} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def correction_table() -> str:
    """Table 3: readings, their correction and the same rays' hemispherical values in the leaf sphere."""

    leaf = vm.mitsuba().load_file(str(LEAF))
    slab = _scene(LEAF, '<bsdf type="turbid_slab">' + "".join(
        f'<float name="{k}" value="{v}"/>' for k, v in SLAB.items() if k != "type") + "</bsdf>")

    def diffuse(bsdf: dict, wavelengths: str) -> np.ndarray:
        """Reflectance for diffuse light (a cosine-weighted beam) of the specimen's lit face."""

        return np.ravel(vm.measure(vm.instrument_scene(bsdf), beam="diffuse", rays=RAYS,
                                   wavelengths=wavelengths).reflectance)

    adaxial, abaxial = diffuse({"type": "abm_b"}, "550, 850"), diffuse({"type": "abm_b", "side": "abaxial"}, "550, 850")
    slab_u = diffuse(SLAB, "550")
    fresnel = st.fresnel_reflectance(8.0, SLAB["eta"])
    cases = [
        ("soybean leaf, R", vm.sphere_measure(leaf, rays=RAYS, delta=DELTA, wavelengths="550, 850"), {}, adaxial),
        ("soybean leaf, T", vm.sphere_measure(leaf, measurement="transmittance", theta_i=0, rays=RAYS, delta=DELTA,
                                              wavelengths="550, 850"), {}, abaxial),
        ("turbid slab, R", vm.sphere_measure(slab, rays=RAYS, delta=DELTA, wavelengths="550"),
         {"specular_reflectance": fresnel}, slab_u),
        ("turbid slab, T", vm.sphere_measure(slab, measurement="transmittance", theta_i=0, rays=RAYS, delta=DELTA,
                                             wavelengths="550"), {}, slab_u),
    ]
    lines = ["| specimen | λ (nm) | hemispherical | reading (error) | theory's reading | corrected, Lambertian "
             "[interval] | residual | u (diffuse light) | corrected with u [interval] | residual |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for name, r, assumptions, u in cases:
        told = dict(assumptions, sample_reflectance=u)
        kw = r.theory_inputs()
        if r.options["measurement"] == "transmittance":
            theory = st.transmittance_reading(r.hemispherical, sample_reflectance=u, **kw)
            corrected, interval = r.corrected(**told), r.corrected_interval(**told)  # u is required here
        else:
            r_s = assumptions.get("specular_reflectance", 0.0)
            theory = st.instrument_reading(r.hemispherical - r_s, specular_reflectance=r_s, **kw)
            corrected, interval = r.corrected(**assumptions), r.corrected_interval(**assumptions)
        with_u, with_u_interval = r.corrected(**told), r.corrected_interval(**told)
        for k, lam in enumerate(r.wavelengths):
            lambertian = ("—", "—") if r.options["measurement"] == "transmittance" else (
                f"{corrected[k]:.4f} [{interval[k, 0]:.4f}, {interval[k, 1]:.4f}]",
                f"{corrected[k] - r.hemispherical[k]:+.4f}")
            lines.append(f"| {name} | {lam:g} | {r.hemispherical[k]:.4f} | {r.reading[k]:.4f} "
                         f"({r.instrument_error[k]:+.4f}) | {theory[k]:.4f} | {lambertian[0]} | {lambertian[1]} "
                         f"| {u[k]:.3f} | {with_u[k]:.4f} [{with_u_interval[k, 0]:.4f}, {with_u_interval[k, 1]:.4f}] "
                         f"| {with_u[k] - r.hemispherical[k]:+.4f} |")
    lines.append("")
    lines.append(f"N = {RAYS:,} rays per configuration, δ = {DELTA:g}; single-beam substitution, SCI; slab "
                 f"{', '.join(f'{k} = {v}' for k, v in SLAB.items() if k != 'type')}, its R corrected with the "
                 f"Fresnel reflectance at 8° ({fresnel:.4f}) as specular part. u: the reflectance for diffuse light "
                 "of the face the sphere sees (`vm.measure(..., beam=\"diffuse\")`: the leaf's adaxial face for R, "
                 "abaxial for T); a transmittance correction needs it, a reflectance correction assumes u = R "
                 "(Lambertian) unless given.")
    return "\n".join(lines)


if __name__ == "__main__":
    print(ideal_table())
    print()
    print(grey_table())
    print()
    print(correction_table())
