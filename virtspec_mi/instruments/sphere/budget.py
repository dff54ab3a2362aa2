"""
A sphere reading's error budget: reading − hemispherical, split into its sources
================================================================================

:func:`sphere_budget` (:meth:`SphereResult.budget
<virtspec_mi.instruments.sphere.result.SphereResult.budget>`, ``virtspec sphere --budget``)
splits a reading's instrument error E = reading − hemispherical into what each real
feature of the sphere adds (:data:`SOURCES`), so a lab sees which part of its instrument
dominates. Each source is a **difference of two readings of the same rays**: the sphere as
it is, and the same sphere with that one feature removed (:func:`without`), taken with the
same seed and N (common random numbers: the two readings share their first interactions
and their random numbers, so most of their noise cancels in the point difference).

- ``port_walls``: ports of depth > 0 that hold nothing (their depth set to 0: knife edges);
- ``holder``: a recessed or proud specimen or standard (the depth or ``proud`` of a port
  that holds one) and holder masks (removed);
- ``beam``: the beam's size, divergence and spill (the beam profile removed: the
  bench's pencil at the specimen's centre);
- ``wall``: the wall's mirror share or its BSDF (removed: Lambertian of ρw);
- ``field_of_view``: the detector's field of view (the whole hemisphere);
- ``substitution`` (a substitution reflectance reading of a sphere with a reference
  port): the ideal sphere (every feature above removed) read by substitution minus the
  same read by comparison (standard and specimen both mounted: the throughput cancels);
- ``ports``: what remains, the ideal sphere's own error (its comparison reading, or its
  substitution reading when substitution cannot be separated, minus hemispherical): port
  losses and the first landing;
- ``interactions``: E minus the sum of the parts above. One-at-a-time differences add up
  to E only when the features do not interact; this line says by how much they do, so the
  parts always add up to E exactly.

**Certificate (exactly which bound):** every reading's interval is the sphere's own (each
detector fraction's Clopper–Pearson interval at δ/2, the two at once by the union bound:
probability ≥ 1 − δ). A difference of two readings gets the interval of their extremes,
[a⁻ − b⁺, a⁺ − b⁻], which holds when both readings' intervals do: probability ≥ 1 − 2δ
by the union bound, whatever their dependence (the common random numbers narrow the point
difference, not this bound: the tallies keep no per-ray pairing to exploit). ``ports``
pairs a reading with the hemispherical value's Clopper–Pearson interval at δ (≥ 1 − 2δ);
``interactions`` combines every reading taken (≥ 1 − Kδ, K the readings and the
hemispherical value); **all lines at once** hold with probability ≥ 1 − Kδ
(:attr:`SphereBudget.joint_confidence`).

References
----------
Clopper & Pearson (1934); Prokhorov, Mekhontsev & Hanssen (2003), Appl. Opt. 42(19),
3832 (sphere geometry errors by Monte Carlo); Hovi et al. (2018), Remote Sens. 10(1), 25
(single and double spheres and a leaf clip read the same leaves differently).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any, Callable

import numpy as np

from virtspec_mi.instruments.sphere.geometry import Port, Sphere

__all__ = ["SOURCES", "SphereBudget", "without", "ideal_sphere", "features_of", "sphere_budget"]

SOURCES: dict[str, str] = {
    "port_walls": "port walls (edges) of ports that hold nothing",
    "holder": "holders: a recessed or proud specimen or standard, holder masks",
    "beam": "the beam's size, divergence and spill",
    "wall": "the wall's mirror share or BSDF (non-Lambertian)",
    "field_of_view": "the detector's field of view",
    "substitution": "substitution error (ideal sphere: substitution - comparison)",
    "ports": "the ideal sphere's own error (port losses, first landing)",
    "interactions": "interactions: the error minus the parts above",
}
"""Every source of the budget, in the order it is printed."""

_FEATURES = ("port_walls", "holder", "beam", "wall", "field_of_view")


def _holder_roles(measurement: str) -> tuple[str, ...]:
    return ("entrance", "sample") if measurement == "transmittance" else ("sample", "reference")


def _port_without(port: Port, feature: str, holders: tuple[str, ...]) -> Port:
    holds = port.role in holders
    if feature == "port_walls" and not holds and port.depth > 0.0:
        return replace(port, depth=0.0, edge_reflectance=None)
    if feature == "holder" and holds and (port.depth > 0.0 or port.aperture is not None or port.proud):
        return replace(port, depth=0.0, edge_reflectance=None, aperture=None, mask_reflectance=None, proud=0.0)
    if feature == "field_of_view" and port.field_of_view is not None:
        return replace(port, field_of_view=None)
    return port


def without(sphere: Sphere, feature: str, measurement: str = "reflectance") -> Sphere:
    """``sphere`` with one feature (one of ``port_walls``, ``holder``, ``beam``, ``wall``, ``field_of_view``) removed."""

    if feature not in _FEATURES:
        raise ValueError(f"feature must be one of {', '.join(_FEATURES)} (got {feature!r})")
    if feature == "beam":
        return replace(sphere, beam_profile=None)
    if feature == "wall":
        return replace(sphere, wall_specular=0.0, wall_bsdf=None)
    holders = _holder_roles(measurement)
    return replace(sphere, ports=tuple(_port_without(p, feature, holders) for p in sphere.ports))


def features_of(sphere: Sphere, measurement: str = "reflectance") -> list[str]:
    """The features ``sphere`` has (those whose removal changes it)."""

    return [f for f in _FEATURES if without(sphere, f, measurement) != sphere]


def ideal_sphere(sphere: Sphere, measurement: str = "reflectance") -> Sphere:
    """``sphere`` with every feature removed: knife-edge ports, no masks, the bench's beam, a Lambertian wall."""

    for feature in _FEATURES:
        sphere = without(sphere, feature, measurement)
    return sphere


@dataclass(frozen=True)
class SphereBudget:
    """
    A reading's error split into its sources (see the module docstring), over the
    readings' dims.

    Attributes
    ----------
    error, error_interval
        E = reading − hemispherical and its interval ([reading⁻ − h⁺, reading⁺ − h⁻]).
    parts, intervals
        Per source present (keys of :data:`SOURCES`, in order): its value and interval
        (…, 2).
    readings
        K: the readings taken (this one and each variant) plus the hemispherical value.
    delta
        Each reading's δ.
    notes
        What the budget could not separate (e.g. substitution without a reference port).
    certificate
        What certifies each reading (Clopper–Pearson; the expected-value detector's empirical Bernstein).
    """

    error: np.ndarray
    error_interval: np.ndarray
    parts: dict
    intervals: dict
    readings: int
    delta: float
    notes: tuple = ()
    certificate: str = "Clopper-Pearson"

    @property
    def joint_confidence(self) -> float:
        """1 − Kδ: the probability with which every line's interval holds at once (union bound)."""

        return max(0.0, 1.0 - self.readings * self.delta)

    def summary(self) -> str:
        """A table: each source's value and interval per reading, the error, the certificate."""

        lines = [f"error budget: reading - hemispherical split into its sources (each a difference of two readings "
                 f"of the same rays; each line's interval holds with probability >= {1 - 2 * self.delta:g}, "
                 f"interactions and all lines at once >= {self.joint_confidence:g}: union bound over {self.readings} "
                 f"{self.certificate} certificates at delta = {self.delta:g})"]
        for name in self.parts:
            value, interval = np.atleast_1d(self.parts[name]), np.atleast_1d(self.intervals[name]).reshape(-1, 2)
            cells = ", ".join(f"{v:+.5f} [{lo:+.5f}, {hi:+.5f}]" for v, (lo, hi) in zip(value.ravel(), interval))
            lines.append(f"  {name:<14} {cells}   {SOURCES[name]}")
        value, interval = np.atleast_1d(self.error), np.atleast_1d(self.error_interval).reshape(-1, 2)
        cells = ", ".join(f"{v:+.5f} [{lo:+.5f}, {hi:+.5f}]" for v, (lo, hi) in zip(value.ravel(), interval))
        lines.append(f"  {'total':<14} {cells}   reading - hemispherical (the parts add up to it)")
        lines.extend(f"  note: {note}" for note in self.notes)
        return "\n".join(lines)

    def as_dict(self) -> dict[str, Any]:
        """Plain data (JSON-ready; NaN as ``None``)."""

        def plain(values: Any) -> Any:
            array = np.asarray(values, dtype=np.float64)
            return np.where(np.isnan(array), None, array).tolist()

        return {"error": plain(self.error), "error_interval": plain(self.error_interval),
                "parts": {k: plain(v) for k, v in self.parts.items()},
                "intervals": {k: plain(v) for k, v in self.intervals.items()},
                "readings": self.readings, "delta": self.delta, "joint_confidence": self.joint_confidence,
                "notes": list(self.notes)}


def _difference(a: Any, b: Any) -> tuple[np.ndarray, np.ndarray]:
    ia, ib = a.reading_interval, b.reading_interval
    return a.reading - b.reading, np.stack([ia[..., 0] - ib[..., 1], ia[..., 1] - ib[..., 0]], axis=-1)


def _check_paired(result: Any, other: Any, what: str) -> None:
    """A variant must be read with the same seed, N and readings: its hemispherical counts are the same rays'."""

    same = (other.settings.seed == result.settings.seed and np.array_equal(other.rays, result.rays)
            and np.array_equal(other.counts["sample"]["hemispherical_reflected"],
                               result.counts["sample"]["hemispherical_reflected"]))
    if not same:
        raise ValueError(f"the budget's {what} reading is not of the same rays (common random numbers need the same "
                         "seed, rays and readings, and a fixed N: give rays=, not an adaptive budget)")


def sphere_budget(result: Any, take: Callable[..., Any]) -> SphereBudget:
    """
    The error budget of ``result`` (a :class:`~virtspec_mi.instruments.sphere.result.SphereResult`).

    Parameters
    ----------
    result
        The reading of the sphere as it is.
    take
        ``take(sphere, **options)``: the same reading (same scene, settings, seed and N) of
        another sphere, and with ``method="comparison"`` by that method; e.g.
        ``lambda sphere, **kw: vm.sphere_measure(scene, sphere=sphere, rays=N, seed=s, **kw)``.

    Returns
    -------
    SphereBudget
    """

    sphere = result.sphere_description
    measurement = str(result.options["measurement"])
    hemi = result.hemispherical_interval
    reading, interval = result.reading, result.reading_interval
    error = reading - result.hemispherical
    error_interval = np.stack([interval[..., 0] - hemi[..., 1], interval[..., 1] - hemi[..., 0]], axis=-1)
    parts, intervals, notes, taken = {}, {}, [], 1
    for feature in features_of(sphere, measurement):
        variant = take(without(sphere, feature, measurement))
        _check_paired(result, variant, feature)
        parts[feature], intervals[feature] = _difference(result, variant)
        taken += 1
    ideal = ideal_sphere(sphere, measurement)
    base = result
    if ideal != sphere:
        base = take(ideal)
        _check_paired(result, base, "ideal sphere")
        taken += 1
    if measurement == "reflectance" and result.options["method"] == "substitution" and sphere.port("reference"):
        comparison = take(ideal, method="comparison")
        _check_paired(result, comparison, "comparison")
        taken += 1
        parts["substitution"], intervals["substitution"] = _difference(base, comparison)
        base = comparison
    elif result.options["method"] == "substitution":
        notes.append("substitution is not separated from the ideal sphere's error (no reference port to read the "
                     "comparison method)" if measurement == "reflectance" else
                     "a transmittance reading's substitution error is part of the ideal sphere's error")
    base_interval = base.reading_interval
    parts["ports"] = base.reading - result.hemispherical
    intervals["ports"] = np.stack([base_interval[..., 0] - hemi[..., 1], base_interval[..., 1] - hemi[..., 0]], axis=-1)
    parts["interactions"] = error - sum(parts.values())
    lower = error_interval[..., 0] - sum(v[..., 1] for v in intervals.values())
    upper = error_interval[..., 1] - sum(v[..., 0] for v in intervals.values())
    intervals["interactions"] = np.stack([lower, upper], axis=-1)
    return SphereBudget(error=error, error_interval=error_interval, parts=parts, intervals=intervals,
                        readings=taken + 1, delta=float(result.delta), notes=tuple(notes),
                        certificate=("empirical Bernstein (readings) and Clopper-Pearson (hemispherical)"
                                     if getattr(result, "expected", False) else "Clopper-Pearson"))
