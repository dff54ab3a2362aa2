"""
Certified colour differences: ΔE*ab and CIEDE2000 over boxes of CIE L*a*b*
==========================================================================

Each colour here is a **box** of CIE L*a*b* (lower and upper per coordinate), the image
of a certified box of CIE XYZ (:func:`lab_box`; a colour known exactly is a box of no
width). Over two boxes:

- ΔE*ab (CIE 015:2018, eq. 8.17) — exact: the least and the largest Euclidean distance
  between points of the boxes (:func:`delta_e_ab_bounds`).
- ΔE₀₀ (CIEDE2000; CIE 015:2018, eqs. 8.37–8.58; Sharma et al. 2005) — a rigorous
  enclosure, not exact (:func:`delta_e_00_bounds`). With x = ΔL′/S_L, y = ΔC′/S_C,
  z = ΔH′/S_H (k_L = k_C = k_H = 1), ΔE₀₀² = x² + y² + z² + R_T·y·z and
  ΔC′² + ΔH′² = Δa′² + Δb′² (ΔH′ = 2√(C₁′C₂′)·sin(Δh′/2)), so with r ≥ |R_T|

      x² + (1 − r/2)·D²/max(S_C, S_H)² ≤ ΔE₀₀² ≤ x² + (1 + r/2)·D²/min(S_C, S_H)²,

  D² = Δa′² + Δb′², Δa′ = (1 + G)·Δa (one G for both colours, 0 ≤ G ≤ 1/2). Each
  factor is bounded over the boxes by the monotone pieces of its formula: S_L by the
  range of L̄′, G, S_C and R_C by the range of C̄* (C̄′ ≥ C̄*), and T and Δθ (of S_H and
  R_T = −sin(2Δθ)·R_C) by their least and largest values over the range of h̄′, found on
  a grid of 0.25° widened by their Lipschitz constants (|dT/dh̄′| ≤ 2.41 rad⁻¹,
  |dΔθ/dh̄′| ≤ 1.03); a box around the achromatic axis, or hues that may lie half a turn
  apart, take the whole circle. It is a Lipschitz-style bound (the factors' extremes
  taken apart), not the exact image, so the radius it certifies is a little wider than
  the largest ΔE₀₀ in the box; it never is narrower.

References
----------
CIE 015:2018 *Colorimetry*, 4th ed., §8.2.1 (eqs. 8.17) and §8.3 (CIEDE2000).
Sharma, G., Wu, W. & Dalal, E. N. (2005). The CIEDE2000 color-difference formula:
implementation notes, supplementary test data, and mathematical observations.
*Color Res. Appl.* 30(1), 21–30, eqs. (1)–(15).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["LabBox", "lab_box", "delta_e_ab_bounds", "delta_e_00_bounds", "radius"]

_T_SLOPE = 0.17 + 2 * 0.24 + 3 * 0.32 + 4 * 0.20  # |dT/dh| per radian
_THETA_SLOPE = 30 * (2 / 625) * (625 / 2) ** 0.5 * math.exp(-0.5)  # |dΔθ/dh̄| (degrees per degree) ≤ 1.03
_GRID = 0.25  # degrees


@dataclass(frozen=True)
class LabBox:
    """CIE L*a*b* ``lower`` ≤ Lab ≤ ``upper`` (each shape (3,)); a point where they are equal."""

    lower: np.ndarray
    upper: np.ndarray

    @classmethod
    def point(cls, Lab: np.ndarray) -> "LabBox":
        Lab = np.asarray(Lab, dtype=np.float64)
        return cls(Lab, Lab)


def lab_box(XYZ_lower: np.ndarray, XYZ_upper: np.ndarray, white_xy: np.ndarray) -> LabBox:
    """
    The exact image of the XYZ box (Y = 100 for the white; the reference white ``white_xy``)
    under XYZ → L*a*b* (CIE 015:2018, eqs. 8.11–8.16): L* rises with Y, a* with X and falls
    with Y, b* rises with Y and falls with Z, so each bound is the value at one corner.
    """

    import colour

    lo, hi = np.asarray(XYZ_lower, dtype=np.float64) / 100.0, np.asarray(XYZ_upper, dtype=np.float64) / 100.0
    corners = np.array([[lo[0], lo[1], lo[2]], [hi[0], hi[1], hi[2]],   # L* low, high
                        [lo[0], hi[1], lo[2]], [hi[0], lo[1], lo[2]],   # a* low, high
                        [lo[0], lo[1], hi[2]], [lo[0], hi[1], lo[2]]])  # b* low, high
    Lab = np.asarray(colour.XYZ_to_Lab(corners, white_xy), dtype=np.float64)
    return LabBox(np.array([Lab[0, 0], Lab[2, 1], Lab[4, 2]]), np.array([Lab[1, 0], Lab[3, 1], Lab[5, 2]]))


def _axis_gaps(a: LabBox, b: LabBox) -> tuple[np.ndarray, np.ndarray]:
    """Per coordinate, the least and the largest |difference| between points of the boxes."""

    largest = np.maximum(b.upper - a.lower, a.upper - b.lower)
    least = np.maximum(0.0, np.maximum(b.lower - a.upper, a.lower - b.upper))
    return least, largest


def delta_e_ab_bounds(a: LabBox, b: LabBox) -> tuple[float, float]:
    """The least and the largest ΔE*ab between a colour of box ``a`` and one of box ``b`` (exact)."""

    least, largest = _axis_gaps(a, b)
    return float(np.sqrt(np.sum(least ** 2))), float(np.sqrt(np.sum(largest ** 2)))


def _chroma_range(box: LabBox) -> tuple[float, float]:
    """Least and largest C*ab = √(a*² + b*²) over the box."""

    a = np.array([box.lower[1], box.upper[1]])
    b = np.array([box.lower[2], box.upper[2]])
    near_a = 0.0 if a[0] <= 0 <= a[1] else np.abs(a).min()
    near_b = 0.0 if b[0] <= 0 <= b[1] else np.abs(b).min()
    return float(math.hypot(near_a, near_b)), float(math.hypot(np.abs(a).max(), np.abs(b).max()))


def _g(c_bar: float) -> float:
    """G of CIEDE2000 (eq. 8.40): decreasing in C̄*."""

    c7 = c_bar ** 7
    return 0.5 * (1.0 - math.sqrt(c7 / (c7 + 25.0 ** 7)))


def _s_l(l_bar: float) -> float:
    return 1.0 + 0.015 * (l_bar - 50.0) ** 2 / math.sqrt(20.0 + (l_bar - 50.0) ** 2)


def _hue_arc(box: LabBox, g_low: float, g_high: float) -> tuple[float, float] | None:
    """The arc (centre, half-width) of h′ in degrees over the box with a′ = (1 + G)·a*, or ``None`` (all hues)."""

    a_lo = min((1 + g_low) * box.lower[1], (1 + g_high) * box.lower[1])
    a_hi = max((1 + g_low) * box.upper[1], (1 + g_high) * box.upper[1])
    b_lo, b_hi = box.lower[2], box.upper[2]
    if a_lo <= 0 <= a_hi and b_lo <= 0 <= b_hi:
        return None
    corners = np.degrees(np.arctan2([b_lo, b_lo, b_hi, b_hi], [a_lo, a_hi, a_lo, a_hi]))
    centre = float(np.degrees(np.arctan2((b_lo + b_hi) / 2, (a_lo + a_hi) / 2)))
    deviations = (corners - centre + 180.0) % 360.0 - 180.0
    low, high = centre + deviations.min(), centre + deviations.max()
    return (low + high) / 2, (high - low) / 2


def _mean_hue_range(a: tuple[float, float] | None, b: tuple[float, float] | None) -> np.ndarray:
    """A grid (degrees in [0, 360)) covering every h̄′ of two hue arcs; the whole circle when unsure."""

    whole = np.arange(0.0, 360.0, _GRID)
    if a is None or b is None:
        return whole
    gap = (b[0] - a[0] + 180.0) % 360.0 - 180.0
    if abs(gap) + a[1] + b[1] >= 179.0:  # the two hues may lie about half a turn apart: h̄′ jumps by 180°
        return whole
    centre, half = a[0] + gap / 2, (a[1] + b[1]) / 2
    steps = max(2, int(math.ceil(2 * half / _GRID)) + 1)
    return np.linspace(centre - half, centre + half, steps) % 360.0


def _t(h: np.ndarray) -> np.ndarray:
    r = np.radians
    return (1 - 0.17 * np.cos(r(h - 30)) + 0.24 * np.cos(r(2 * h)) + 0.32 * np.cos(r(3 * h + 6))
            - 0.20 * np.cos(r(4 * h - 63)))


def delta_e_00_bounds(a: LabBox, b: LabBox) -> tuple[float, float]:
    """
    A lower and an upper bound of ΔE₀₀ (CIEDE2000, k_L = k_C = k_H = 1) between any colour of
    box ``a`` and any of box ``b`` (see the module docstring: rigorous, not exact).
    """

    least, largest = _axis_gaps(a, b)
    l_low, l_high = (a.lower[0] + b.lower[0]) / 2, (a.upper[0] + b.upper[0]) / 2
    nearest = min(max(50.0, l_low), l_high)
    s_l_low, s_l_high = _s_l(nearest), max(_s_l(l_low), _s_l(l_high))
    (ca_low, ca_high), (cb_low, cb_high) = _chroma_range(a), _chroma_range(b)
    c_low, c_high = (ca_low + cb_low) / 2, (ca_high + cb_high) / 2
    g_high, g_low = _g(c_low), _g(c_high)
    cp_low, cp_high = c_low, (1 + g_high) * c_high
    hues = _mean_hue_range(_hue_arc(a, g_low, g_high), _hue_arc(b, g_low, g_high))
    spacing = _GRID if len(hues) < 2 else float(np.max(np.abs(np.diff(np.unwrap(np.radians(hues))))) * 180 / math.pi)
    t = _t(hues)
    t_low = float(t.min()) - _T_SLOPE * math.radians(spacing) / 2
    t_high = float(t.max()) + _T_SLOPE * math.radians(spacing) / 2
    theta = 30.0 * np.exp(-(((hues - 275.0) / 25.0) ** 2))
    theta_high = min(30.0, float(theta.max()) + _THETA_SLOPE * spacing / 2)
    r_c = 2.0 * math.sqrt(cp_high ** 7 / (cp_high ** 7 + 25.0 ** 7))
    r = r_c * math.sin(math.radians(2.0 * theta_high))
    s_c_low, s_c_high = 1 + 0.045 * cp_low, 1 + 0.045 * cp_high
    s_h_low, s_h_high = 1 + 0.015 * cp_low * max(t_low, 0.0), 1 + 0.015 * cp_high * t_high
    d_high2 = ((1 + g_high) * largest[1]) ** 2 + largest[2] ** 2
    d_low2 = least[1] ** 2 + least[2] ** 2
    upper2 = (largest[0] / s_l_low) ** 2 + (1 + r / 2) * d_high2 / min(s_c_low, s_h_low) ** 2
    lower2 = (least[0] / s_l_high) ** 2 + max(0.0, 1 - r / 2) * d_low2 / max(s_c_high, s_h_high) ** 2
    return float(math.sqrt(lower2)), float(math.sqrt(upper2))


def radius(estimate: np.ndarray, box: LabBox) -> tuple[float, float]:
    """(ΔE₀₀, ΔE*ab): the largest difference between ``estimate`` and a colour of ``box`` (bounds above)."""

    point = LabBox.point(estimate)
    return delta_e_00_bounds(point, box)[1], delta_e_ab_bounds(point, box)[1]
