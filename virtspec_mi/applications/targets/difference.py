"""
Certified colour difference between two colours: ``vm.colour_difference``
=========================================================================

:func:`colour_difference` takes two colours — a certified colour
(:class:`~.colour.CertifiedColour`, from ``result.colour()`` or a colour target's result),
a result (its colour is taken), or a colour known exactly (CIE L*a*b* as three numbers:
a measured target) — and returns the certified interval of ΔE₀₀ (a rigorous enclosure,
:func:`~.delta_e.delta_e_00_bounds`) and of ΔE*ab (exact over the boxes,
:func:`~.delta_e.delta_e_ab_bounds`) between them. Each certified colour holds at its own
δ, so the interval holds with probability ≥ 1 − (δ₁ + δ₂) (a union bound).

References
----------
CIE 015:2018, §8.3 (CIEDE2000); Sharma et al. (2005).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from virtspec_mi.colorimetry.delta_e import LabBox, delta_e_00_bounds, delta_e_ab_bounds

__all__ = ["ColourDifference", "colour_difference"]


@dataclass(frozen=True)
class ColourDifference:
    """ΔE₀₀ and ΔE*ab between two colours: point values and certified intervals at ``delta``."""

    dE00: float
    dE00_interval: tuple[float, float]
    dEab: float
    dEab_interval: tuple[float, float]
    delta: float

    def summary(self) -> str:
        return (f"dE00 = {self.dE00:.4f} in [{self.dE00_interval[0]:.4f}, {self.dE00_interval[1]:.4f}], dE*ab = "
                f"{self.dEab:.4f} in [{self.dEab_interval[0]:.4f}, {self.dEab_interval[1]:.4f}] (certified "
                f"together at delta = {self.delta:g}; dE00 a rigorous enclosure, dE*ab exact over the boxes)")

    def as_dict(self) -> dict[str, Any]:
        return {"dE00": self.dE00, "dE00_interval": list(self.dE00_interval), "dEab": self.dEab,
                "dEab_interval": list(self.dEab_interval), "delta": self.delta}


def _box(colour: Any, name: str) -> tuple[np.ndarray, LabBox, float]:
    """(estimate, box, δ) of a colour given any way :func:`colour_difference` takes it."""

    if hasattr(colour, "colour") and getattr(colour, "colour", None) is not None and not callable(colour.colour):
        colour = colour.colour  # a colour target's DerivedResult
    elif hasattr(colour, "colour") and callable(colour.colour):
        colour = colour.colour()  # a result
    if hasattr(colour, "Lab_interval"):
        interval = np.asarray(colour.Lab_interval, dtype=np.float64)
        if np.any(np.isnan(interval)):
            raise ValueError(f"{name}: the colour has no certified interval ({colour.note})")
        return np.asarray(colour.Lab, dtype=np.float64), LabBox(interval[:, 0], interval[:, 1]), float(colour.delta)
    if hasattr(colour, "Lab"):
        raise ValueError(f"{name}: the colour has no certified interval ({getattr(colour, 'note', '')}); give a "
                         "certified colour or L*a*b* numbers of a colour known exactly")
    expected = (f"{name} must be a certified colour (result.colour(), a colour target's result), a result, or CIE "
                "L*a*b* as three numbers")
    if isinstance(colour, (str, bytes)) or hasattr(colour, "target"):
        kind = getattr(getattr(colour, "target", None), "kind", "")
        what = f"the result of a {kind} target" if hasattr(colour, "target") else repr(colour)
        raise ValueError(f"{expected} (got {what}: not a colour)")
    try:
        Lab = np.asarray(colour, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError(f"{expected} (got {type(colour).__name__} {_shown(colour)})") from None
    if Lab.shape != (3,) or not np.all(np.isfinite(Lab)):
        raise ValueError(f"{expected}, finite (got {_shown(colour)})")
    return Lab, LabBox.point(Lab), 0.0


def _shown(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 80 else text[:77] + "..."


def colour_difference(a: Any, b: Any) -> ColourDifference:
    """The certified ΔE₀₀ and ΔE*ab intervals between colours ``a`` and ``b`` (see the module docstring)."""

    import colour

    lab_a, box_a, delta_a = _box(a, "a")
    lab_b, box_b, delta_b = _box(b, "b")
    return ColourDifference(float(colour.delta_E(lab_a, lab_b, method="CIE 2000")), delta_e_00_bounds(box_a, box_b),
                            float(colour.delta_E(lab_a, lab_b, method="CIE 1976")), delta_e_ab_bounds(box_a, box_b),
                            delta_a + delta_b)
