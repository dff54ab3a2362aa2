"""
Print the manual's port-fraction convention table (docs/guide/sphere.md) (``virtspec_mi.instruments.sphere.theory``).

Grid: wall reflectance ρw ∈ {0.90, 0.95, 0.98, 0.99} × port fraction f ∈ {1 %, 5 %, 10 %},
where the sphere has three ports (entrance, sample, detector) whose exact cap fraction is
f each, and a Lambertian sample of reflectance 0.5 sits in the sample port. Each row
gives the detector fraction ``ρs · T_sample`` (the share of the rays entering the sphere
that the detector counts) in three models:

- cap fractions, cap surfaces: Goebel / iadpython's ``a_d · Sphere.multiplier(ρs, ρs)``;
- projected fractions ``r²/4R²`` of the same ports, cap surfaces (IAD's convention);
- exact geometry: cap fractions, specimen a flat disk in its port (the simulation).

A second table gives the single-beam substitution error and the comparison method's
residual for grey Lambertian specimens (SCE, standard 0.99) on two illustrative spheres
(:data:`EXAMPLE_SPHERES`; dimensions for illustration, not a particular instrument).

The manual's tables (docs/guide/sphere.md) must equal this script's output
(``tests/instruments/sphere/test_theory.py``).
Run: ``.venv/bin/python tools/sphere_conventions.py``.
"""

from __future__ import annotations

from virtspec_mi.instruments.sphere import theory as st

WALL_REFLECTANCES = (0.90, 0.95, 0.98, 0.99)
PORT_FRACTIONS = (0.01, 0.05, 0.10)
SAMPLE_REFLECTANCE = 0.5
GREYS = (0.05, 0.20, 0.50, 0.80, 0.95)
STANDARD_REFLECTANCE = 0.99


def _sphere(diameter: float, wall: float, sample: float, detector: float, entrance: float, trap: float,
            reference: float) -> dict:
    """Port diameters (mm) on a sphere of ``diameter`` → the keywords of ``sphere_theory`` readings."""

    def fraction(port: float) -> float:
        return st.cap_fraction(port / 2, diameter / 2)

    return dict(wall_reflectance=wall, sample_fraction=fraction(sample), detector_fraction=fraction(detector),
                open_fraction=fraction(entrance), trap_fraction=fraction(trap),
                reference_fraction=fraction(reference))


EXAMPLE_SPHERES = {
    "150 mm sphere, ρw 0.98, 25 mm sample/entrance/specular/reference ports, 10 mm detector":
        _sphere(150.0, 0.98, 25.0, 10.0, 25.0, 25.0, 25.0),
    "50 mm sphere, ρw 0.95, 12 mm sample/entrance/specular/reference ports, 5 mm detector":
        _sphere(50.0, 0.95, 12.0, 5.0, 12.0, 12.0, 12.0),
}


def detector_fraction(wall_reflectance: float, fraction: float, port_surface: str) -> float:
    """ρs · T_sample for three ports of fraction ``fraction`` each."""

    return SAMPLE_REFLECTANCE * st.detected_fraction(
        wall_reflectance, SAMPLE_REFLECTANCE, sample_fraction=fraction, detector_fraction=fraction,
        open_fraction=fraction, port_surface=port_surface)


def markdown_table() -> str:
    """The table as Markdown lines."""

    lines = [
        "| ρw | port fraction f (cap) | same port, r²/4R² | detector fraction, cap fractions (Goebel, iadpython) "
        "| with r²/4R² fractions | shift | exact geometry (flat specimen) | flat vs cap |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for rho_w in WALL_REFLECTANCES:
        for fraction in PORT_FRACTIONS:
            projected = fraction * (1.0 - fraction)  # the same port's r²/4R²
            cap = detector_fraction(rho_w, fraction, "cap")
            flat = detector_fraction(rho_w, fraction, "flat")
            projected_reading = SAMPLE_REFLECTANCE * st.detected_fraction(
                rho_w, SAMPLE_REFLECTANCE, sample_fraction=projected, detector_fraction=projected,
                open_fraction=projected, port_surface="cap")
            lines.append(
                f"| {rho_w:.2f} | {fraction:.2f} | {projected:.4f} | {cap:.5f} | {projected_reading:.5f} "
                f"| {projected_reading / cap - 1:+.2%} | {flat:.5f} | {flat / cap - 1:+.2%} |")
    return "\n".join(lines)


def error_table() -> str:
    """Substitution error and comparison residual (reading − ρ, exact flat geometry, SCE) as Markdown."""

    names = list(EXAMPLE_SPHERES)
    lines = ["| ρ (grey, Lambertian) | " + " | ".join(
        f"{which}, sphere {i + 1}" for i in range(len(names)) for which in ("substitution", "comparison")) + " |",
        "|---" * (1 + 2 * len(names)) + "|"]
    for rho in GREYS:
        cells = []
        for name in names:
            kw = dict(EXAMPLE_SPHERES[name], standard_reflectance=STANDARD_REFLECTANCE, mode="SCE")
            cells.append(f"{st.substitution_reading(rho, **kw) - rho:+.4f}")
            cells.append(f"{st.comparison_reading(rho, **kw) - rho:+.4f}")
        lines.append(f"| {rho:.2f} | " + " | ".join(cells) + " |")
    lines.append("")
    lines += [f"Sphere {i + 1}: {name}." for i, name in enumerate(names)]
    return "\n".join(lines)


if __name__ == "__main__":
    print(markdown_table())
    print()
    print(error_table())
