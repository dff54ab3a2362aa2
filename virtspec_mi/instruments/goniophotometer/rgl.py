"""
A goniophotometer reading as an RGL ``.bsdf`` file: Mitsuba's ``measured`` material
===================================================================================

:func:`rgl_export` turns a :class:`~virtspec_mi.instruments.goniophotometer.result.GonioResult`
into the tensor file Mitsuba's ``measured`` plugin loads (the layout of
:mod:`virtspec_mi.exchange.rgl`) — **reflection only** (a transmission file has no place in
that format: transmission stays with the Klems export).

The grid. The plugin looks a direction up by its half vector m = (wi + wo)/|wi + wo|:
u = (√(2θm/π), (φm − φi + π)/2π) ∈ [0, 1]², mapped through the file's VNDF warp onto the
n × n nodes of ``spectra`` (Dupuy & Jakob's warped grid). This export stores a **uniform
VNDF**: the warp is the identity and the nodes are the regular grid u = (i/(n−1), j/(n−1))
(θm = (π/2)·(i/(n−1))², φm − φi = 2π·j/(n−1) − π). It is a valid file of the format; it does not
adapt the nodes to the specimen's lobe as the paper's acquisition does, so a narrow lobe
needs a finer ``resolution``.

What each node stores, and its certificate. The goniophotometer does **not** bin on this
grid: its rays are binned by (θo, φo) (:class:`~virtspec_mi.instruments.goniophotometer.bins.GonioBins`).
A node's outgoing direction wo (the mirror of wi about m) falls in one bin k, and the node
stores f_k · cos θo(wo), where f_k is the bin's BRDF estimate — the average of f over the
bin weighted by projected solid angle (its exact meaning in
:class:`~virtspec_mi.instruments.goniophotometer.result.GonioResult`). Its certified
interval is [f_k⁻ · cos θo, f_k⁺ · cos θo] from the bin's simultaneous Clopper–Pearson
interval (all K bins of a reading at once with probability ≥ 1 − δ; over the file's R
readings, all at once with probability ≥ 1 − R·δ). That is a certificate of the bin's
average times the node's cosine, **not** of f(wi, wo)·cos θo at the node: the two agree
where f is constant over the bin (a Lambertian specimen: f_k = ρ/π exactly), and differ
by f's variation within the bin elsewhere — which no interval here bounds. Nodes whose wo
lies below the horizon (or outside the bins) store 0 and have no certificate; the plugin
never returns them at a node, but interpolates towards them near the horizon. A node on a
bin edge takes the bin above it; the first and last rows (φm − φi = ∓180°, one direction)
store the same values, and so do the nodes of the first column (θm = 0: the mirror
direction, whatever the row). At normal incidence (θi = 0) the plugin has no azimuth of
incidence to read rows by: there every node stores its θo ring's average, f_ring · cos θo,
with f_ring the projected-solid-angle-weighted average of the ring's bins and its interval
the same average of their simultaneous bounds (a Lambertian's f_ring is ρ/π exactly).

Between the nodes, between the measured θi and between the wavelengths the plugin
interpolates linearly: those values carry no certificate. A file is isotropic (one
``phi_i``): the plugin applies the reading's relative azimuth at every φi, which is right
for an isotropic specimen only. The file's ``description`` holds the specimen, the
settings, the certificate, what a node stores, and the version; :class:`RGLExport` holds
the nodes' directions, values and intervals.

References
----------
Dupuy, J. and Jakob, W. (2018), An Adaptive Parameterization for Efficient Material
Acquisition and Rendering, ACM Trans. Graph. 37(6), 274; Mitsuba 3, ``measured`` BSDF
(``src/bsdfs/measured.cpp``: the half-vector parameterization u, the warps, no cosine);
Nicodemus et al. (1977), NBS Monograph 160 (BRDF, projected solid angle).
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from virtspec_mi.exchange.rgl import write_tensor

GonioResult = Any  # the result module imports this one (its to_rgl): annotated by name only, no import back

__all__ = ["RGLExport", "rgl_export", "node_directions", "DEFAULT_RESOLUTION"]

DEFAULT_RESOLUTION = 32
"""Nodes per axis of the grid (n × n per θi and wavelength)."""


@dataclass(frozen=True, eq=False)
class RGLExport:
    """
    What :func:`rgl_export` wrote: the file and, per (θi, node), the outgoing direction
    and, per (wavelength, θi, node), the stored value and its certified interval.

    Attributes
    ----------
    path : Path
    theta_i : ndarray
        Degrees, increasing (the file's ``theta_i`` in radians).
    phi_i : float
        The reading's azimuth of incidence (degrees); the nodes' wo are in that frame.
    wavelengths : ndarray
        nm.
    wo : ndarray
        (θi, n_phi, n_theta, 3) each node's outgoing direction (specimen frame, unit).
    valid : ndarray
        (θi, n_phi, n_theta) the node's wo is a reflected direction inside the bins.
    values, lower, upper : ndarray
        (wavelength, θi, n_phi, n_theta): the stored f_k·cos θo and its certified interval
        (0 and NaN where not ``valid``; NaN bounds where the reading is not certified: its
        ``bins_mu`` is NaN, e.g. weight violations or capped walks).
    """

    path: Path
    theta_i: np.ndarray
    phi_i: float
    wavelengths: np.ndarray
    wo: np.ndarray
    valid: np.ndarray
    values: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    description: str


def node_directions(theta_i: float, phi_i: float, resolution: int) -> np.ndarray:
    """
    (n_phi, n_theta, 3): the outgoing direction of every node of the uniform-warp grid for
    incidence (θi, φi) in degrees (rows: the φm coordinate, columns: the θm coordinate, as
    ``spectra``'s last two axes).
    """

    u = np.arange(resolution) / (resolution - 1)
    theta_m = (np.pi / 2) * u ** 2
    phi_m = math.radians(phi_i) + 2 * np.pi * u - np.pi
    t, p = math.radians(theta_i), math.radians(phi_i)
    wi = np.array([math.sin(t) * math.cos(p), math.sin(t) * math.sin(p), math.cos(t)])
    m = np.stack([np.cos(phi_m)[:, None] * np.sin(theta_m)[None, :],
                  np.sin(phi_m)[:, None] * np.sin(theta_m)[None, :],
                  np.broadcast_to(np.cos(theta_m)[None, :], (resolution, resolution))], axis=-1)
    return 2.0 * (m @ wi)[..., None] * m - wi


def _bin_of(result: "GonioResult", wo: np.ndarray, phi_i: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(θo bin, φo bin, inside) of each direction (reflected hemisphere only)."""

    bins = result.bins
    theta_o = np.degrees(np.arctan2(np.hypot(wo[..., 0], wo[..., 1]), wo[..., 2]))
    phi_o = np.degrees(np.arctan2(wo[..., 1], wo[..., 0])) % 360.0
    if bins.fold_phi:
        relative = (phi_o - phi_i) % 360.0
        phi_o = np.minimum(relative, 360.0 - relative)
    t = np.searchsorted(bins.theta_edges, theta_o, side="right") - 1
    p = np.searchsorted(bins.phi_edges, phi_o, side="right") - 1
    t = np.where(theta_o == bins.theta_edges[-1], len(bins.theta_edges) - 2, t)
    p = np.where(phi_o == bins.phi_edges[-1], len(bins.phi_edges) - 2, p)
    inside = ((wo[..., 2] > 0) & (theta_o < 90.0) & (t >= 0) & (t < bins.shape[0]) & (p >= 0)
              & (p < bins.shape[1]))
    return np.clip(t, 0, bins.shape[0] - 1), np.clip(p, 0, bins.shape[1] - 1), inside


def _ring_average(result: "GonioResult", values: np.ndarray) -> np.ndarray:
    """
    (λ, θo, φo) → the same shape, each θo ring's projected-solid-angle-weighted average over
    its φo bins (the ring's f; of simultaneous bounds, a bound of it).
    """

    weights = result.bins.projected_solid_angles()
    ring = (values * weights).sum(axis=-1, keepdims=True) / weights.sum(axis=-1, keepdims=True)
    return np.broadcast_to(ring, values.shape)


def _description(result: "GonioResult", resolution: int, readings: int) -> str:
    from virtspec_mi.base.version import __version__

    text = {
        "written_by": f"virtspec-mi {__version__}",
        "specimen": result.scene,
        "settings": {key: value for key, value in result.settings.as_dict().items()
                     if isinstance(value, (str, int, float, bool, type(None), list))},
        "certificate": result.certificate(),
        "readings": readings,
        "joint_level": f"all nodes of all {readings} readings at once: probability >= "
                       f"{max(0.0, 1 - readings * result.delta):g} (union bound)",
        "stored": "f_k * cos(theta_o(node)): f_k the goniophotometer bin's BRDF estimate (projected-solid-angle "
                  "average of f over the bin holding the node's outgoing direction), certified within "
                  "[f_k_lower, f_k_upper] * cos(theta_o); a certificate of the bin average, not of f at the node",
        "grid": f"uniform VNDF (identity warp): {resolution} x {resolution} nodes, u = (sqrt(2 theta_m / pi), "
                "(phi_m - phi_i + pi) / 2 pi); isotropic (one phi_i); reflection only",
    }
    return json.dumps(text)


def rgl_export(result: "GonioResult", path: str | os.PathLike, resolution: int = DEFAULT_RESOLUTION) -> RGLExport:
    """Write ``result``'s reflection as an RGL ``.bsdf`` at ``path`` (see the module docstring)."""

    if not isinstance(resolution, (int, np.integer)) or isinstance(resolution, bool) or not 2 <= resolution <= 512:
        raise ValueError(f"resolution must be a whole number, 2 <= resolution <= 512 nodes per axis (got "
                         f"{resolution!r})")
    extra = [dim for dim in result.dims if dim not in ("wavelength", "theta_i", "theta_o", "phi_o")]
    if extra:
        raise ValueError(f"an RGL .bsdf holds one specimen: select one parameter point first (dims {extra})")
    if not (result.bins.theta_edges[0] == 0.0 and result.bins.theta_edges[-1] >= 90.0):
        raise ValueError("an RGL .bsdf holds the reflected hemisphere: the bins must cover theta_o from 0 to 90 "
                         f"degrees (they cover {result.bins.theta_edges[0]:g}-{result.bins.theta_edges[-1]:g})")
    grid = result.as_grid() if hasattr(result, "as_grid") else result
    theta_i = np.atleast_1d(np.asarray(grid.theta_i, dtype=np.float64))
    wavelengths = np.atleast_1d(np.asarray(grid.coords["wavelength"], dtype=np.float64))
    brdf = np.asarray(grid.brdf, dtype=np.float64).reshape(len(wavelengths), len(theta_i), *grid.bins.shape)
    lower = np.asarray(grid.brdf_lower, dtype=np.float64).reshape(brdf.shape)
    upper = np.asarray(grid.brdf_upper, dtype=np.float64).reshape(brdf.shape)
    uncertified = np.isnan(np.asarray(grid.bins_mu, dtype=np.float64).reshape(len(wavelengths), len(theta_i)))
    lower[uncertified], upper[uncertified] = np.nan, np.nan  # a reading that is not certified: no interval
    if np.any(np.diff(theta_i) <= 0):
        raise ValueError(f"an RGL .bsdf needs increasing theta_i (got {theta_i})")
    if np.any(np.diff(wavelengths) <= 0):
        raise ValueError(f"an RGL .bsdf needs increasing wavelengths (got {wavelengths})")
    phi_i = float(grid.settings.phi_i)
    n = int(resolution)
    shape = (len(wavelengths), len(theta_i), n, n)
    values, low, high = np.zeros(shape), np.full(shape, np.nan), np.full(shape, np.nan)
    directions, valid = np.zeros((len(theta_i), n, n, 3)), np.zeros((len(theta_i), n, n), dtype=bool)
    for t, angle in enumerate(theta_i):
        wo = node_directions(float(angle), phi_i, n)
        wo[-1] = wo[0]  # φm − φi = −180° and +180°: one direction, one bin (the plugin may round to either row)
        wo[:, 0] = wo[0, 0]  # θm = 0 (the mirror direction) in every row: one direction, one bin
        k_theta, k_phi, inside = _bin_of(grid, wo, phi_i)
        cosine = np.where(inside, wo[..., 2], 0.0)
        directions[t], valid[t] = wo, inside
        f, f_low, f_high = brdf[:, t], lower[:, t], upper[:, t]
        if angle == 0.0:  # normal incidence: no azimuth of incidence; each θo ring's average (rotation-invariant)
            f, f_low, f_high = (_ring_average(grid, a) for a in (f, f_low, f_high))
        values[:, t] = np.where(inside, f[:, k_theta, k_phi] * cosine, 0.0)
        low[:, t] = np.where(inside, f_low[:, k_theta, k_phi] * cosine, np.nan)
        high[:, t] = np.where(inside, f_high[:, k_theta, k_phi] * cosine, np.nan)
    # φi × θi × λ × n × n: two identical φi slices at −π and π (isotropic: the plugin interpolates between them)
    spectra = np.repeat(np.transpose(values, (1, 0, 2, 3))[None], 2, axis=0).astype(np.float32)
    luminance = spectra.mean(axis=2)
    luminance = luminance + max(float(luminance.max()), 1.0) * 1e-6  # a positive density for the plugin's sampling
    description = _description(grid, n, len(wavelengths) * len(theta_i))
    fields = {
        "description": np.frombuffer(description.encode("utf-8"), dtype=np.uint8),
        "theta_i": np.radians(theta_i).astype(np.float32),
        "phi_i": np.array([-math.pi, math.pi], dtype=np.float32),
        "wavelengths": wavelengths.astype(np.float32),
        "jacobian": np.array([0], dtype=np.uint8),
        "ndf": np.ones((n, n), dtype=np.float32),
        "sigma": np.ones((n, n), dtype=np.float32),
        "vndf": np.ones((2, len(theta_i), n, n), dtype=np.float32),
        "luminance": luminance.astype(np.float32),
        "spectra": spectra,
    }
    written = write_tensor(path, fields)
    return RGLExport(path=Path(written), theta_i=theta_i, phi_i=phi_i, wavelengths=wavelengths, wo=directions,
                     valid=valid, values=values, lower=low, upper=high, description=description)
