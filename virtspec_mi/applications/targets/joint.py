"""
A colour's joint confidence region: facets along CIELAB, ΔE₀₀ enclosed over the region
======================================================================================

The betting route (:mod:`.sequential`) certifies a colour from one **joint region** of
CIE XYZ, not from three boxes of X, Y and Z:

1. At the pilot's point x̃ = (X̃, Ỹ, Z̃) (pilot rays only: fixed before the sequence
   starts) the Jacobian G = ∂(L*, a*, b*)/∂(X, Y, Z) of CIELAB (CIE 015:2018, eqs.
   8.11–8.16) gives three **facet functionals** Fᵢ = Σₖ (G·W)ᵢₖ pₖ — the linearised L*,
   a* and b* of the reflectance (W: the tristimulus weights; weights of any sign). Each
   is certified by its own stratified betting confidence sequence
   (:class:`~virtspec_mi.budgets.betting.BettingSequence`) at δ/3: an interval
   [ℓᵢ, hᵢ] that holds at every batch at once.
2. The **region** R = {x ∈ XYZ : ℓᵢ ≤ (G·x)ᵢ ≤ hᵢ, i = 1, 2, 3} ∩ {what a spectrum
   in [0, 1] can give} is one set: with probability ≥ 1 − δ the true XYZ lies in it at
   every batch at once (below). Every coordinate and every function of XYZ — X, Y, Z,
   L*, a*, b*, sRGB, ΔE₀₀ — is read off that one set, so all of them hold *together* at δ.
3. R is covered by pieces (:func:`region_boxes`: the facets' box split into
   parts × parts × parts pieces; each piece's XYZ hull by interval arithmetic through
   G⁻¹, and its CIELAB box by the mean-value form Lab(x) ∈ Lab(x_c) + [J]·G⁻¹·(y − y_c),
   [J] the range of CIELAB's Jacobian over the hull, intersected with the exact image of
   the hull by :func:`~virtspec_mi.colorimetry.delta_e.lab_box`'s corner rule), and ΔE₀₀
   around the estimate is bounded over each piece's box (the rigorous bound of
   :mod:`~virtspec_mi.colorimetry.delta_e`): the radius certified is the largest over the
   pieces. XYZ, L*a*b* and sRGB intervals are the hulls over the pieces.

**Theorem.** P(∃ batch B: XYZ* ∉ R_B) ≤ δ.
*Proof.* XYZ* ∉ R_B only if some facet's interval misses (G·XYZ*)ᵢ = Fᵢ(p*) at batch B.
Facet i's sequence misses at some batch with probability ≤ δ/3 (Ville's inequality for
its stratified betting capital, :mod:`virtspec_mi.budgets.betting`: its stakes are
functions of the pilot and of the batches before, the rays of a batch fresh); a union
over the three facets gives ≤ δ. The cover contains R (each point y of the facets' box
lies in one piece, and G⁻¹y in its hull: the hull is widened by |I − G⁻¹G|·|x| so that the
rounding of the inverse cannot leave a point out; Lab of it in the piece's box by the mean
value theorem, applied to each coordinate on the segment from x_c, which lies in the
hull), and ΔE₀₀'s bound over each box is an upper bound. ∎ G only chooses *which* directions are certified: a G that is off (a
pilot far from the truth) widens the region, never invalidates it.

**Why facets, not one product set for X, Y, Z.** The capital of a stratum in
:mod:`~virtspec_mi.budgets.betting` stakes λₖ = t·I·|wₖ|/nₖ in the orientation of the
functional's signs, one-sided, for each functional: it depends on the functional asked.
One product supermartingale with the same stakes for every functional would define one
set in the space of all stratum means, but its stakes would have to serve every
direction at once, and each stratum's stake loses capital where the data sit
(≈ −λ²nₖv/2): a projection on X would pay the losses of the strata staked for Z too.
A union bound over directions chosen *for the quantity asked* is cheaper: the box of
X, Y and Z maps to CIELAB with a* = 500(f(X/Xₙ) − f(Y/Yₙ)) widened by both X's and Y's
half-widths, while the a* facet's variance is that of the difference, X̂ and Ŷ being
strongly correlated (they share the rays of 500–650 nm). The three facets cost the same
δ/3 each that X, Y and Z did.

References
----------
CIE 015:2018 *Colorimetry*, eqs. 8.11–8.16 (CIELAB) and §8.3 (CIEDE2000).
Spertus, Sridhar & Stark (2024), arXiv:2409.06680; Waudby-Smith & Ramdas (2023), JRSS-B
(the sequences). Boole's inequality (the union over the facets).
"""

from __future__ import annotations

import numpy as np

from virtspec_mi.colorimetry.certified import CertifiedColour, _srgb_matrix
from virtspec_mi.colorimetry.cie import Colour
from virtspec_mi.colorimetry.delta_e import LabBox, radius

__all__ = ["PARTS", "lab_jacobian", "facet_weights", "region_boxes", "lab_boxes", "region_colour",
           "facet_tolerances"]

PARTS: int = 2
"""The facets' box is split into PARTS³ pieces to enclose the region (finer: tighter, slower)."""

_EPSILON = (6 / 29) ** 3
_KAPPA = 1 / (3 * (6 / 29) ** 2)


def _white_XYZ(white_xy: np.ndarray) -> np.ndarray:
    x, y = (float(v) for v in np.asarray(white_xy, dtype=np.float64))
    return np.array([100 * x / y, 100.0, 100 * (1 - x - y) / y])


def _f(t: np.ndarray) -> np.ndarray:
    t = np.asarray(t, dtype=np.float64)
    return np.where(t > _EPSILON, np.cbrt(np.maximum(t, _EPSILON)), _KAPPA * t + 4 / 29)


def _df(t: np.ndarray) -> np.ndarray:
    t = np.asarray(t, dtype=np.float64)
    return np.where(t > _EPSILON, np.maximum(t, _EPSILON) ** (-2 / 3) / 3, _KAPPA)


def lab_jacobian(XYZ: np.ndarray, white_xy: np.ndarray) -> np.ndarray:
    """G = ∂(L*, a*, b*)/∂(X, Y, Z) at ``XYZ`` (Y = 100 for the white ``white_xy``), shape (3, 3)."""

    n = _white_XYZ(white_xy)
    d = _df(np.maximum(np.asarray(XYZ, dtype=np.float64), 1e-6) / n) / n
    return np.array([[0.0, 116 * d[1], 0.0], [500 * d[0], -500 * d[1], 0.0], [0.0, 200 * d[1], -200 * d[2]]])


def facet_weights(G: np.ndarray, tristimulus: np.ndarray) -> np.ndarray:
    """The facet functionals' weights G·W (``tristimulus`` W: shape (3, K)), shape (3, K)."""

    return np.asarray(G, dtype=np.float64) @ np.asarray(tristimulus, dtype=np.float64)


def region_boxes(G: np.ndarray, low: np.ndarray, high: np.ndarray, floor: np.ndarray, ceiling: np.ndarray,
                 white_xy: np.ndarray, parts: int = PARTS) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """
    Pieces whose union contains R = {x : ``low`` ≤ G·x ≤ ``high``, ``floor`` ≤ x ≤
    ``ceiling``}: the box [low, high] split into parts × parts × parts pieces P, each with its XYZ
    hull (G⁻¹P by interval arithmetic, widened for the inverse's rounding, clipped to
    [max(floor, 0), ceiling]; a piece whose hull misses it is left out) and a CIELAB box
    containing Lab(G⁻¹P) by the mean-value form about the piece's centre y_c:

        Lab(G⁻¹y) ∈ Lab(G⁻¹y_c) + [J]·G⁻¹·(y − y_c),   [J] ⊇ {∂Lab/∂XYZ(ξ) : ξ in the hull}

    ([J] exact from f′ of CIELAB being non-increasing). Returns (XYZ lower, XYZ upper,
    Lab lower, Lab upper), each shape (N, 3).
    """

    G = np.asarray(G, dtype=np.float64)
    low, high = np.asarray(low, dtype=np.float64), np.asarray(high, dtype=np.float64)
    inverse = np.linalg.inv(G)
    edges = [np.linspace(lo, hi, parts + 1) for lo, hi in zip(low, high)]
    grids = np.meshgrid(*[np.arange(parts)] * 3, indexing="ij")
    index = np.stack([g.ravel() for g in grids], axis=1)
    bottom = np.stack([edges[i][index[:, i]] for i in range(3)], axis=1)
    top = np.stack([edges[i][index[:, i] + 1] for i in range(3)], axis=1)
    centre, half = (bottom + top) / 2, (top - bottom) / 2
    x, r = centre @ inverse.T, half @ np.abs(inverse).T
    lowest = np.maximum(np.asarray(floor, dtype=np.float64), 0.0)
    ceiling = np.asarray(ceiling, dtype=np.float64)
    scale = max(float(np.abs(ceiling).max()), float(np.abs(x).max() + r.max()))
    r = r + np.abs(np.eye(3) - inverse @ G).sum(axis=1) * scale + 1e-12 * (np.abs(x) + r)
    lower, upper = np.maximum(x - r, lowest), np.minimum(x + r, ceiling)
    keep = np.all(lower <= upper, axis=1)
    x, r, half, lower, upper = x[keep], r[keep], half[keep], lower[keep], upper[keep]
    n = _white_XYZ(white_xy)
    steep, flat = _df((x - r) / n) / n, _df((x + r) / n) / n  # f' non-increasing: its range over the hull
    factors = np.array([[0, 116, 0], [500, -500, 0], [0, 200, -200]], dtype=np.float64)
    J_low = np.minimum(factors[None] * steep[:, None, :], factors[None] * flat[:, None, :])
    J_high = np.maximum(factors[None] * steep[:, None, :], factors[None] * flat[:, None, :])
    mid, rad = (J_low + J_high) / 2, (J_high - J_low) / 2
    M_mid, M_rad = mid @ inverse, rad @ np.abs(inverse)
    spread = np.einsum("nij,nj->ni", np.abs(M_mid) + M_rad, half)
    f = _f(x / n)
    Lab = np.stack([116 * f[:, 1] - 16, 500 * (f[:, 0] - f[:, 1]), 200 * (f[:, 1] - f[:, 2])], axis=1)
    spread = spread * (1 + 1e-9) + 1e-9 * (np.abs(Lab) + 1.0)  # the point's and the products' rounding
    return lower, upper, Lab - spread, Lab + spread


def lab_boxes(lower: np.ndarray, upper: np.ndarray, white_xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """
    The exact CIELAB image of each XYZ box (rows of ``lower``, ``upper``), as
    :func:`~virtspec_mi.colorimetry.delta_e.lab_box` gives it for one: (lower, upper) Lab, shape (N, 3).
    """

    n = _white_XYZ(white_xy)
    fl, fu = _f(np.asarray(lower) / n), _f(np.asarray(upper) / n)
    Lab_low = np.stack([116 * fl[:, 1] - 16, 500 * (fl[:, 0] - fu[:, 1]), 200 * (fl[:, 1] - fu[:, 2])], axis=1)
    Lab_high = np.stack([116 * fu[:, 1] - 16, 500 * (fu[:, 0] - fl[:, 1]), 200 * (fu[:, 1] - fl[:, 2])], axis=1)
    return Lab_low, Lab_high


def _radius(Lab: np.ndarray, Lab_low: np.ndarray, Lab_high: np.ndarray) -> tuple[float, float]:
    """The largest ΔE₀₀ and ΔE*ab bounds between ``Lab`` and the boxes (each row one box)."""

    de00 = deab = 0.0
    far = np.abs(Lab_low - Lab).max(axis=1) + np.abs(Lab_high - Lab).max(axis=1)
    for i in np.argsort(-far):  # every box is bounded: the order only makes the largest come early
        a, b = radius(Lab, LabBox(Lab_low[i], Lab_high[i]))
        de00, deab = max(de00, a), max(deab, b)
    return de00, deab


def region_colour(estimate: Colour, G: np.ndarray, low: np.ndarray, high: np.ndarray, floor: np.ndarray,
                  ceiling: np.ndarray, white_xy: np.ndarray, delta: float, rays: int, method: str,
                  parts: int = PARTS) -> CertifiedColour:
    """
    The :class:`~virtspec_mi.colorimetry.certified.CertifiedColour` of the region R (facets
    G with intervals [``low``, ``high``], within [``floor``, ``ceiling``]): the hulls of X, Y,
    Z, L*a*b* and sRGB over its boxes, and the ΔE₀₀ and ΔE*ab radii around ``estimate``
    over them (the module docstring).
    """

    import colour as cs

    lower, upper, Lab_low, Lab_high = region_boxes(G, low, high, floor, ceiling, white_xy, parts)
    if len(lower) == 0:  # the facets' box misses what a spectrum can give: the truth is outside only w.p. <= delta
        lower, upper = np.maximum(np.asarray(floor, dtype=np.float64), 0.0)[None], np.asarray(ceiling)[None]
        Lab_low, Lab_high = lab_boxes(lower, upper, white_xy)
    else:  # each piece's Lab box within the exact image of its XYZ hull too
        corner_low, corner_high = lab_boxes(lower, upper, white_xy)
        Lab_low, Lab_high = np.maximum(Lab_low, corner_low), np.minimum(Lab_high, corner_high)
    de00, deab = _radius(np.asarray(estimate.Lab, dtype=np.float64), Lab_low, Lab_high)
    XYZ_low, XYZ_high = lower.min(axis=0), upper.max(axis=0)
    matrix = _srgb_matrix(tuple(float(v) for v in white_xy))
    positive, negative = np.clip(matrix, 0, None), np.clip(matrix, None, 0)
    linear_low = positive @ (XYZ_low / 100.0) + negative @ (XYZ_high / 100.0)
    linear_high = positive @ (XYZ_high / 100.0) + negative @ (XYZ_low / 100.0)
    encode = cs.models.eotf_inverse_sRGB
    srgb = np.stack([np.asarray(encode(linear_low)), np.asarray(encode(linear_high))], axis=1)
    fields = {name: getattr(estimate, name) for name in ("XYZ", "Lab", "sRGB", "illuminant", "observer",
                                                         "wavelengths", "coverage", "note")}
    return CertifiedColour(**fields, XYZ_interval=np.stack([XYZ_low, XYZ_high], axis=1),
                           Lab_interval=np.stack([Lab_low.min(axis=0), Lab_high.max(axis=0)], axis=1),
                           sRGB_interval=srgb, dE00_radius=float(de00), dEab_radius=float(deab), delta=float(delta),
                           rays=int(rays), method=method)


def facet_tolerances(Lab: np.ndarray, facets: np.ndarray, variances: np.ndarray, tolerance: float,
                     margin: float) -> np.ndarray:
    """
    Half-widths tᵢ to plan each facet for (a heuristic: the certificate never depends on
    it): ΔE₀₀ over the CIELAB box Lab ± t at most ``margin``·``tolerance``, tᵢ ∝ (cᵢ/sᵢ)^⅓
    with cᵢ = (Σₖ |Fᵢₖ|σₖ)² (Neyman's cost of facet i, ``variances`` σₖ²) and sᵢ the
    radius's slope in tᵢ — the fewest rays for a radius linear in t — scaled to fit.
    """

    from virtspec_mi.applications.targets.targets import _scaled

    Lab = np.asarray(Lab, dtype=np.float64)

    def radius_of(t: np.ndarray) -> float:
        return radius(Lab, LabBox(Lab - t, Lab + t))[0]

    probe = 1e-2
    base = radius_of(np.full(3, 1e-9))
    slopes = np.array([(radius_of(np.where(np.arange(3) == i, probe, 1e-9)) - base) / probe for i in range(3)])
    cost = (np.abs(facets) @ np.sqrt(np.asarray(variances, dtype=np.float64))) ** 2
    shape = (cost / (np.abs(slopes) + 1e-9)) ** (1 / 3)
    return _scaled(shape / shape.max(), lambda t: radius_of(t) <= margin * tolerance)

