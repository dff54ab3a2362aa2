"""
``tabulated``: a BSDF that renders a goniophotometer reading
============================================================

The measured table (:mod:`virtspec_mi.plugins.bsdfs.bsdf_table`) holds, per wavelength λ and
incidence θi, the fraction p_k = m_k/N of incident rays that left into each (θo, φo)
bin k, reflected (θo < 90°) or transmitted (θo > 90°); the rest was absorbed. This
plugin is the BSDF that is piecewise constant within the bins and reproduces those
fractions exactly:

- ``eval``: f(ωi, ωo)·|cos θo| with f = p_k/Ω_k on the bin k holding ωo,
  Ω_k = ∫_bin |cos θo| dωo (the table's BRDF/BTDF estimate, sr⁻¹); 0 outside the
  measured bins;
- ``sample``: picks bin k with probability p_k/P (P = Σ_k p_k = R + T of the row), then a
  direction uniform in projected solid angle within the bin (uniform in sin²θo and in
  φo), and returns the **weight P** = f·|cos θo|/pdf — the same for every direction.
  Weights lie in [0, 1], so the spectrophotometer's Russian roulette (survive with
  probability P) counts a ray into bin k with probability exactly p_k: its R and T
  are the table's Σ p_k over the reflected and the transmitted bins. The bin is found
  by a binary search of the row's cumulative sums (computed in float64, stored in
  float32: each bin's probability is exact to float32 rounding, ~10⁻⁷ of P); P is
  clipped into [0, 1] against float32 rounding of the mixture;
- ``pdf``: (p_k/P)/Ω_k·|cos θo| (solid-angle measure), i.e. piecewise constant in the
  projected-solid-angle measure, exactly the density ``sample`` draws from.

Between table rows
    θi (from |cos| of ωi) and λ are interpolated **linearly** between the two
    neighbouring tabulated values and clamped at the ends of the table (the instrument
    refuses wavelengths beyond the table's, :attr:`Tabulated.wavelength_range`: it holds
    no data there): the BSDF is
    the bilinear mixture Σ_r c_r p_{r,k}/Ω_k of up to four rows r, and ``sample`` draws
    from the mixture exactly (a row with probability c_r P_r / Σ c P, then a bin of
    it). At a tabulated (λ, θi) the table's row is used unmixed.
Wavelengths
    The spectral variants carry four wavelengths per ray: ``eval`` returns each lane's
    own f; ``sample`` draws from the first lane's (the hero wavelength's) mixture, and
    lane j's weight is f_j·|cos θo|/pdf_0 — lane 0's weight is P, the others may exceed
    1 (rendering only; the instrument traces one wavelength per reading in all lanes).
Azimuths
    The table is taken as rotation invariant about the normal: an incident direction at
    azimuth φ uses the table rotated by φ − φi (φi: the table's ``phi_i``). With
    ``phi_folded`` the table holds the relative azimuth |φo − φ| ∈ [0°, 180°]; a folded
    bin stands for its two mirror halves, each drawn with probability ½.
Sides
    Light arriving from below (ωi·n < 0) uses the same table mirrored through the
    surface (a two-sided BSDF).
Components
    Component 0 is the reflected lobe (``GlossyReflection``), component 1 the
    transmitted lobe (``GlossyTransmission``, ``NonSymmetric``). With one of them
    disabled in the ``BSDFContext``, ``sample`` draws from the enabled one only (weight:
    its own total), and ``eval``/``pdf`` are normalised the same way.

Parameters
----------
filename : string, default none
    A NetCDF file in the goniophotometer layout (dims ``wavelength``, ``theta_i``,
    ``theta_o``, ``phi_o``; ``bin_counts``, ``rays``, ``brdf``, bin edges, attributes
    ``phi_i`` and ``phi_folded``); validated by :func:`virtspec_mi.plugins.bsdfs.bsdf_table.read_table`.
wavelength, theta_i, theta_o_lower, theta_o_upper, phi_o_lower, phi_o_upper : Float64, default none
    Instead of ``filename`` (dict scenes): the table's coordinates (nm, degrees), as
    :func:`virtspec_mi.runtime.scene.tabulated_bsdf` builds them from a dataset.
fraction : Float64 or TensorXf64, default none
    With the arrays above: p_k = m_k/N over (wavelength, theta_i, theta_o, phi_o), C
    order (a flat ``Float64``: Mitsuba's dict parser takes a tensor whose first axis
    has 3 entries for a colour first and prints conversion warnings).
phi_i : float, default 0
    With the arrays above: the table's φi in degrees.
phi_folded : boolean, default false
    With the arrays above: φo is the folded relative azimuth |φo − φi| ∈ [0, 180].

Exactly one of ``filename`` and ``fraction`` must be given; a bad table raises a
``ValueError`` naming the variable and its allowed range.

References
----------
Nicodemus et al. (1977), NBS Monograph 160 (BRDF, projected solid angle); Pharr, Jakob
& Humphreys, *Physically Based Rendering* (4th ed.), Sect. 2.3 (inversion sampling of
piecewise-constant 1-D distributions); Mitsuba 3 ``mi.BSDF`` (Python BSDF plugins).
"""

from __future__ import annotations

import math
from typing import Any

import drjit as dr
import mitsuba as mi
import numpy as np

from virtspec_mi.plugins.bsdfs.bsdf_table import TABLE_PROPERTIES, BSDFTable, read_table
from virtspec_mi.plugins.specimen import Parameter

__all__ = ["Tabulated"]

_LANES: int = 4  # wavelengths per ray in Mitsuba's spectral variants
_MIN_COS: float = 1e-7  # a sampled direction keeps |cos θo| ≥ this: its hemisphere is never ambiguous


def _f32(values: np.ndarray) -> mi.Float:
    """A Dr.Jit ``Float`` (float32 in the ``llvm_ad_spectral`` variant) of a float64 NumPy array."""

    return mi.Float(np.ascontiguousarray(values, dtype=np.float32))


def _table_from_props(props: mi.Properties) -> BSDFTable:
    """The table named by ``filename`` or carried by the array parameters."""

    has_file = "filename" in props
    has_arrays = "fraction" in props
    if has_file == has_arrays:
        raise ValueError("tabulated: give exactly one of 'filename' (a NetCDF goniophotometer table) "
                         "and the table arrays ('fraction', 'wavelength', 'theta_i', bin edges; "
                         "virtspec_mi.runtime.scene.tabulated_bsdf builds them)")
    if has_file:
        return read_table(str(props.get("filename")))
    values = {}
    for name in TABLE_PROPERTIES:
        if name in ("phi_i", "phi_folded"):
            continue
        if name not in props:
            raise ValueError(f"tabulated: parameter {name!r} is missing (the table arrays come together)")
        values[name] = np.array(props.get(name), dtype=np.float64).ravel()
    shape = (len(values["wavelength"]), len(values["theta_i"]), len(values["theta_o_lower"]), len(values["phi_o_lower"]))
    if values["fraction"].size == math.prod(shape):
        values["fraction"] = values["fraction"].reshape(shape)  # else BSDFTable names the shape
    return BSDFTable(**values, phi_i=float(props.get("phi_i", 0.0)), phi_folded=bool(props.get("phi_folded", False)))


class Tabulated(mi.BSDF):
    """Piecewise-constant BSDF of a goniophotometer table (see the module docstring)."""

    # the specimen protocol: no parameter; the range and the flag are the table's (set in __init__)
    PARAMETERS: tuple[Parameter, ...] = ()
    wavelength_range: tuple[float, float] | None = None
    wavelength_independent: bool = False

    def check_wavelengths(self, wavelengths: Any) -> None:
        """The specimen protocol: the table's range is :attr:`wavelength_range`; nothing more to check."""

    def __init__(self, props: mi.Properties) -> None:
        super().__init__(props)
        table = _table_from_props(props)
        self.table = table
        self.wavelength_independent = table.shape[0] == 1
        # The wavelengths the table holds data for (the instrument refuses others); one row holds for all.
        self.wavelength_range = None if self.wavelength_independent else (
            float(np.min(table.wavelength)), float(np.max(table.wavelength)))
        n_wavelength, n_theta_i, n_theta_o, n_phi_o = table.shape
        self.n_wavelength, self.n_theta_i, self.n_theta_o, self.n_phi_o = table.shape
        self.bins = n_theta_o * n_phi_o
        fraction = table.fraction.reshape(n_wavelength * n_theta_i, self.bins)
        cumulative = table.cumulative()
        reflected_bins = int(table.reflected_bins.sum()) * n_phi_o  # θo-major: reflected bins come first
        self.reflected_bins = reflected_bins
        total = cumulative[:, -1]
        reflected = cumulative[:, reflected_bins - 1] if reflected_bins > 0 else np.zeros(len(total))
        positive = fraction > 0
        k = np.arange(self.bins)
        last_any = np.where(positive, k, 0).max(axis=1)
        last_reflected = np.where(positive & (k < reflected_bins), k, 0).max(axis=1)

        self._fraction = _f32(fraction.ravel())
        self._cdf = _f32(cumulative.ravel())
        self._total = _f32(total)
        self._reflected = _f32(reflected)
        self._last_any = mi.UInt32(last_any.astype(np.uint32))
        self._last_reflected = mi.UInt32(last_reflected.astype(np.uint32))
        self._solid_angle = _f32(table.solid_angles.ravel())
        self._wavelength = _f32(table.wavelength)
        self._theta_i = _f32(table.theta_i)
        # θo edges as -cos θ (increasing), exact 0 / ±1 at 90°, 0°, 180°
        edges = np.append(table.theta_o_lower, table.theta_o_upper[-1])
        cos_edges = np.cos(np.radians(edges))
        cos_edges[edges == 90.0], cos_edges[edges == 0.0], cos_edges[edges == 180.0] = 0.0, 1.0, -1.0
        self._neg_cos_edges = _f32(-cos_edges)
        self._sin2_lower = _f32(np.sin(np.radians(table.theta_o_lower)) ** 2)
        self._sin2_upper = _f32(np.sin(np.radians(table.theta_o_upper)) ** 2)
        phi_edges = np.radians(np.append(table.phi_o_lower, table.phi_o_upper[-1]))
        self._phi_edges = _f32(phi_edges)
        self._phi_range = (float(phi_edges[0]), float(phi_edges[-1]))
        self._phi_i = math.radians(table.phi_i)
        self._folded = table.phi_folded
        self._upper_is_reflected = mi.Bool(table.reflected_bins)
        flags = mi.BSDFFlags.FrontSide | mi.BSDFFlags.BackSide
        self.m_components = [mi.BSDFFlags.GlossyReflection | flags,
                             mi.BSDFFlags.GlossyTransmission | flags | mi.BSDFFlags.NonSymmetric]
        self.m_flags = self.m_components[0] | self.m_components[1]

    # ------------------------------------------------------------------ rows
    @staticmethod
    def _interval(grid: mi.Float, n: int, x: mi.Float) -> tuple[mi.UInt32, mi.UInt32, mi.Float]:
        """Neighbours (i0, i1) of x in the increasing ``grid`` and the weight t of i1 (clamped ends)."""

        if n == 1:
            zero = dr.zeros(mi.UInt32, dr.width(x))
            return zero, zero, dr.zeros(mi.Float, dr.width(x))
        i0 = dr.binary_search(0, n - 2, lambda i: dr.gather(mi.Float, grid, i + 1) <= x)
        i0 = mi.UInt32(i0)
        g0, g1 = dr.gather(mi.Float, grid, i0), dr.gather(mi.Float, grid, i0 + 1)
        t = dr.clip((x - g0) / (g1 - g0), 0.0, 1.0)
        return i0, i0 + 1, t

    def _rows(self, theta_i_deg: mi.Float, wavelength: mi.Float) -> list[tuple[mi.UInt32, mi.Float]]:
        """The (up to four) table rows of the mixture and their bilinear weights."""

        i0, i1, s = self._interval(self._theta_i, self.n_theta_i, theta_i_deg)
        l0, l1, t = self._interval(self._wavelength, self.n_wavelength, wavelength)
        rows = []
        for li, wl in ((l0, 1.0 - t), (l1, t)) if self.n_wavelength > 1 else ((l0, mi.Float(1.0)),):
            for ii, wi in ((i0, 1.0 - s), (i1, s)) if self.n_theta_i > 1 else ((i0, mi.Float(1.0)),):
                rows.append((li * self.n_theta_i + ii, wl * wi))
        return rows

    # ------------------------------------------------------------------ geometry
    def _local(self, si: mi.SurfaceInteraction3f) -> tuple[mi.Float, mi.Vector3f, mi.Float]:
        """(side sign, ωi mirrored to the upper side, θi in degrees)."""

        side = dr.select(si.wi.z < 0.0, -1.0, 1.0)
        wi = mi.Vector3f(si.wi.x, si.wi.y, si.wi.z * side)
        theta_i = dr.acos(dr.clip(wi.z, -1.0, 1.0)) * (180.0 / math.pi)
        return side, wi, theta_i

    def _bin(self, wi: mi.Vector3f, wo: mi.Vector3f) -> tuple[mi.UInt32, mi.Bool]:
        """Flattened bin index of ωo (both mirrored to ωi's upper side) and whether it is measured."""

        key = -wo.z
        n = self.n_theta_o
        j = mi.UInt32(dr.binary_search(0, n, lambda i: dr.gather(mi.Float, self._neg_cos_edges, i) <= key))
        valid = (key >= dr.gather(mi.Float, self._neg_cos_edges, mi.UInt32(0))) & (
            key <= dr.gather(mi.Float, self._neg_cos_edges, mi.UInt32(n)))
        a = dr.clip(mi.Int32(j) - 1, 0, n - 1)
        delta = dr.atan2(wo.y, wo.x) - dr.atan2(wi.y, wi.x)
        if self._folded:
            delta = dr.abs(dr.atan2(dr.sin(delta), dr.cos(delta)))  # |wrap to (−π, π]|
        else:
            delta = delta + self._phi_i
            delta = delta - 2.0 * math.pi * dr.floor(delta * (0.5 / math.pi))  # [0, 2π)
        m = self.n_phi_o
        low, high = self._phi_range
        b = mi.UInt32(dr.binary_search(0, m, lambda i: dr.gather(mi.Float, self._phi_edges, i) <= delta))
        valid &= (delta >= low) & (delta <= high)
        b = dr.clip(mi.Int32(b) - 1, 0, m - 1)
        return mi.UInt32(a) * m + mi.UInt32(b), valid

    def _enabled(self, ctx: mi.BSDFContext) -> tuple[bool, bool]:
        return ctx.is_enabled(mi.BSDFFlags.GlossyReflection, 0), ctx.is_enabled(mi.BSDFFlags.GlossyTransmission, 1)

    def _selected_total(self, row: mi.UInt32, reflection: bool, transmission: bool) -> mi.Float:
        if reflection and transmission:
            return dr.gather(mi.Float, self._total, row)
        reflected = dr.gather(mi.Float, self._reflected, row)
        if reflection:
            return reflected
        if transmission:
            return dr.maximum(dr.gather(mi.Float, self._total, row) - reflected, 0.0)
        return dr.zeros(mi.Float, dr.width(row))

    def _mixture(self, rows, k: mi.UInt32) -> mi.Float:
        """Σ_r c_r p_{r,k}."""

        value = mi.Float(0.0)
        for row, weight in rows:
            value += weight * dr.gather(mi.Float, self._fraction, row * self.bins + k)
        return value

    @staticmethod
    def _lobe_enabled(wo_z: mi.Float, reflection: bool, transmission: bool) -> mi.Bool:
        if reflection and transmission:
            return mi.Bool(True)
        if reflection:
            return wo_z > 0.0
        if transmission:
            return wo_z < 0.0
        return mi.Bool(False)

    # ------------------------------------------------------------------ BSDF interface
    def eval(self, ctx, si, wo, active=True):
        value, _ = self.eval_pdf(ctx, si, wo, active)
        return value

    def pdf(self, ctx, si, wo, active=True):
        _, pdf = self.eval_pdf(ctx, si, wo, active)
        return pdf

    def eval_pdf(self, ctx, si, wo, active=True):
        reflection, transmission = self._enabled(ctx)
        side, wi, theta_i = self._local(si)
        wo_local = mi.Vector3f(wo.x, wo.y, wo.z * side)
        k, valid = self._bin(wi, wo_local)
        valid &= mi.Bool(active) & self._lobe_enabled(wo_local.z, reflection, transmission) & (wo_local.z != 0.0)
        solid_angle = dr.gather(mi.Float, self._solid_angle, k)
        cos_o = dr.abs(wo_local.z)
        wavelengths = si.wavelengths
        lanes = []
        pdf = mi.Float(0.0)
        for lane in range(_LANES if self.n_wavelength > 1 else 1):
            rows = self._rows(theta_i, wavelengths[lane])
            mixed = self._mixture(rows, k)
            lanes.append(dr.select(valid, mixed / solid_angle * cos_o, 0.0))
            if lane == 0:
                total = mi.Float(0.0)
                for row, weight in rows:
                    total += weight * self._selected_total(row, reflection, transmission)
                pdf = dr.select(valid & (total > 0.0), mixed / (total * solid_angle) * cos_o, 0.0)
        value = mi.Spectrum(*lanes) if len(lanes) == _LANES else mi.Spectrum(lanes[0])
        return value, pdf

    def sample(self, ctx, si, sample1, sample2, active=True):
        reflection, transmission = self._enabled(ctx)
        side, wi, theta_i = self._local(si)
        rows = self._rows(theta_i, si.wavelengths[0])
        totals = [weight * self._selected_total(row, reflection, transmission) for row, weight in rows]
        mixture_total = mi.Float(0.0)
        for value in totals:
            mixture_total += value
        # pick a row of the mixture with probability c_r P_r / Σ c P, and the target in its CDF
        goal = sample1 * mixture_total
        row = rows[0][0]
        row_weight = rows[0][1]
        before = mi.Float(0.0)
        chosen_before = mi.Float(0.0)
        for index, ((candidate, weight), value) in enumerate(zip(rows, totals)):
            if index > 0:
                take = (goal >= before) & (value > 0.0)
                row = dr.select(take, candidate, row)
                row_weight = dr.select(take, weight, row_weight)
                chosen_before = dr.select(take, before, chosen_before)
            before += value
        offset = mi.Float(0.0) if reflection else dr.gather(mi.Float, self._reflected, row)
        target = offset + (goal - chosen_before) / dr.maximum(row_weight, 1e-30)
        base = row * self.bins
        k = mi.UInt32(dr.binary_search(0, self.bins - 1,
                                       lambda i: dr.gather(mi.Float, self._cdf, base + i) <= target))
        last = dr.gather(mi.UInt32, self._last_reflected if (reflection and not transmission) else self._last_any, row)
        k = dr.minimum(k, last)
        if transmission and not reflection:
            k = dr.maximum(k, self.reflected_bins)
        a, b = k // self.n_phi_o, k % self.n_phi_o
        # uniform in projected solid angle within the bin: sin²θ and φ uniform
        s0, s1 = dr.gather(mi.Float, self._sin2_lower, a), dr.gather(mi.Float, self._sin2_upper, a)
        sin2 = dr.lerp(s0, s1, sample2.x)
        upper = dr.gather(mi.Bool, self._upper_is_reflected, a)
        cos_o = dr.maximum(dr.safe_sqrt(1.0 - sin2), _MIN_COS)
        cos_o = dr.select(upper, cos_o, -cos_o)
        u = sample2.y
        if self._folded:
            negative = u < 0.5
            u = dr.select(negative, 2.0 * u, 2.0 * u - 1.0)
        p0, p1 = dr.gather(mi.Float, self._phi_edges, b), dr.gather(mi.Float, self._phi_edges, b + 1)
        phi = dr.lerp(p0, p1, u)
        if self._folded:
            phi = dr.select(negative, -phi, phi)
        else:
            phi = phi - self._phi_i
        phi += dr.atan2(wi.y, wi.x)
        sin_o = dr.safe_sqrt(1.0 - cos_o * cos_o)
        sin_phi, cos_phi = dr.sincos(phi)
        wo_local = mi.Vector3f(sin_o * cos_phi, sin_o * sin_phi, cos_o)

        ok = mi.Bool(active) & (mixture_total > 0.0)
        bs = dr.zeros(mi.BSDFSample3f)
        bs.wo = dr.select(ok, mi.Vector3f(wo_local.x, wo_local.y, wo_local.z * side), mi.Vector3f(0.0, 0.0, 1.0))
        solid_angle = dr.gather(mi.Float, self._solid_angle, k)
        mixed = self._mixture(rows, k)
        bs.pdf = dr.select(ok, mixed / (mixture_total * solid_angle) * dr.abs(cos_o), 0.0)
        bs.eta = 1.0
        bs.sampled_component = dr.select(upper, mi.UInt32(0), mi.UInt32(1))
        bs.sampled_type = dr.select(upper, mi.UInt32(+mi.BSDFFlags.GlossyReflection),
                                    mi.UInt32(+mi.BSDFFlags.GlossyTransmission))
        weight0 = dr.clip(mixture_total, 0.0, 1.0)
        if self.n_wavelength > 1:
            lanes = [weight0]
            for lane in range(1, _LANES):
                other = self._mixture(self._rows(theta_i, si.wavelengths[lane]), k)
                lanes.append(dr.select(mixed > 0.0, other / mixed * mixture_total, 0.0))
            weight = mi.Spectrum(*lanes)
        else:
            weight = mi.Spectrum(weight0)
        return bs, dr.select(ok, weight, mi.Spectrum(0.0))

    def traverse(self, callback) -> None:
        pass

    def parameters_changed(self, keys) -> None:
        pass

    def to_string(self) -> str:
        n_wavelength, n_theta_i, n_theta_o, n_phi_o = self.table.shape
        return (f"Tabulated[wavelengths={n_wavelength}, theta_i={n_theta_i}, bins={n_theta_o}x{n_phi_o}, "
                f"phi_folded={int(self.table.phi_folded)}, sha256={self.table.digest}]")
