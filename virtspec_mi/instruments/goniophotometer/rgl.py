"""
A goniophotometer reading on the RGL grid as a ``.bsdf`` file: Mitsuba's ``measured`` material
==============================================================================================

:func:`rgl_export` turns an :class:`~virtspec_mi.instruments.goniophotometer.rgl_reading.RGLReading`
— a goniophotometer reading binned on the file's own grid (``binning="rgl"``) — into the
tensor file Mitsuba's ``measured`` plugin loads (the layout of :mod:`virtspec_mi.exchange.rgl`),
**reflection only** (transmission has no place in that format: it stays with the Klems export).

The grid. The plugin looks a direction up by its half vector m = (wi + wo)/|wi + wo|:
u = (√(2θm/π), (φm − φi + π)/2π) ∈ [0, 1]², mapped through the file's VNDF warp onto the
n × n nodes of ``spectra`` and interpolated bilinearly. This export writes a **uniform
VNDF** (the identity warp): the nodes are the regular grid u = (i/(n−1), j/(n−1)). It does
not adapt the nodes to the specimen's lobe as Dupuy & Jakob's acquisition does, so a
narrow lobe needs a finer ``rgl_resolution``.

What each node stores, and its certificate. The reading binned every reflected ray in the
**cell** of the node nearest to its lookup position, |u − u_node| ≤ h/2 per axis, h = 1/(n−1)
(:mod:`virtspec_mi.instruments.goniophotometer.warped`: the rows φm − φi = ±180° are one cell,
the column θm = 0 is one cell, and at θi = 0 each column is one ring). Each node stores its
cell's **solid-angle mean of f·cos θo**,

    v_k = (1/Ω_k) ∫_cell f(wi, wo) cos θo dωo,   estimated by m_k/(N Ω_k),

with Ω_k the solid angle of the cell's reflected directions, and its certified interval is
the cell's simultaneous Clopper–Pearson interval divided by Ω_k (all K cells of a reading at
once with probability ≥ 1 − δ; all R readings of the file at once with ≥ 1 − R·δ). That is
a certificate of the cell mean, **not** of f·cos θo at the node's own direction: the two
agree where f·cos θo is constant over the cell, and differ by its variation within the cell
(smaller on a finer grid), which no interval here bounds. Nodes whose cell holds no
reflected direction (Ω_k = 0: the half vectors beyond the horizon) store 0 and have no
certificate. A node whose own direction lies below the horizon but whose cell reaches above
it stores its cell's mean: the plugin never returns it there (it returns 0 below the
horizon) but interpolates towards it near the horizon. A reading that is not certified (its
``bins_mu`` NaN) has no interval.

Between the nodes, between the measured θi and between the wavelengths the plugin
interpolates linearly: those values carry no certificate. A file is isotropic (one
``phi_i``): the plugin applies the reading's relative azimuth at every φi, which is right
for an isotropic specimen only. The file's ``description`` holds the specimen, the
settings, the certificate, what a node stores and the version; :class:`RGLExport` holds the
nodes' directions, cells, values and intervals.

References
----------
Dupuy, J. and Jakob, W. (2018), An Adaptive Parameterization for Efficient Material
Acquisition and Rendering, ACM Trans. Graph. 37(6), 274; Mitsuba 3, ``measured`` BSDF
(``src/bsdfs/measured.cpp``: the half-vector parameterization u, the warps, no cosine);
Clopper, C.J. and Pearson, E.S. (1934), Biometrika 26, 404–413.
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

RGLReading = Any  # the reading's module imports this one (its to_rgl): annotated by name only, no import back

__all__ = ["RGLExport", "rgl_export"]


@dataclass(frozen=True, eq=False)
class RGLExport:
    """
    What :func:`rgl_export` wrote: the file and, per (θi, node), the outgoing direction
    and cell and, per (wavelength, θi, node), the stored value and its certified interval.

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
        (θi, n, n, 3) each node's outgoing direction (specimen frame, unit; rows: the φm
        axis, columns: the θm axis, as ``spectra``'s last two axes).
    cells : ndarray
        (θi, n, n) the cell each node stores.
    valid : ndarray
        (θi, n, n) the node's cell holds reflected directions (Ω_k > 0).
    visible : ndarray
        (θi, n, n) ``valid`` and the node's own direction is above the horizon (wo_z > 0): where
        the plugin returns the node's value (below it the plugin returns 0, but interpolates
        towards the node's value near the horizon).
    values, lower, upper : ndarray
        (wavelength, θi, n, n): the stored cell mean of f·cos θo and its certified interval
        (0 and NaN where not ``valid``; NaN bounds where the reading is not certified).
    description : str
        The file's ``description`` (JSON).
    """

    path: Path
    theta_i: np.ndarray
    phi_i: float
    wavelengths: np.ndarray
    wo: np.ndarray
    cells: np.ndarray
    valid: np.ndarray
    visible: np.ndarray
    values: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    description: str


def _description(reading: "RGLReading", readings: int) -> str:
    from virtspec_mi.base.version import __version__

    n = reading.resolution
    text = {
        "written_by": f"virtspec-mi {__version__}",
        "specimen": reading.scene,
        "settings": {key: value for key, value in reading.settings.as_dict().items()
                     if isinstance(value, (str, int, float, bool, type(None), list))},
        "certificate": reading.certificate(),
        "readings": readings,
        "joint_level": f"all nodes of all {readings} readings at once: probability >= "
                       f"{max(0.0, 1 - readings * reading.delta):g} (union bound)",
        "stored": "each node: its cell's solid-angle mean of f * cos(theta_o), (1/Omega_k) * integral over the cell "
                  "of f cos(theta_o) d omega_o, estimated by m_k / (N Omega_k); the cell: the reflected directions "
                  "whose lookup position u is within h/2 = 1/(2(n-1)) of the node on each axis (rows phi_m - phi_i "
                  "= -180 and +180 deg one cell, column theta_m = 0 one cell, at theta_i = 0 each column one ring); "
                  "certified within the cell's simultaneous Clopper-Pearson interval / Omega_k (each cell at "
                  "delta/K); a certificate of the cell mean, not of f cos(theta_o) at the node's own direction",
        "grid": f"uniform VNDF (identity warp): {n} x {n} nodes, u = (sqrt(2 theta_m / pi), "
                "(phi_m - phi_i + pi) / 2 pi); isotropic (one phi_i); reflection only; the goniophotometer binned "
                "its rays on these cells (binning rgl)",
    }
    return json.dumps(text)


def rgl_export(reading: "RGLReading", path: str | os.PathLike) -> RGLExport:
    """Write ``reading`` (binned on the RGL grid) as an RGL ``.bsdf`` at ``path`` (see the module docstring)."""

    if not hasattr(reading, "cell_counts"):
        raise ValueError("an RGL .bsdf stores certified cell means only of a reading binned on its grid: measure with "
                         "binning='rgl' (and beam='collimated'; virtspec gonio --rgl FILE does)")
    extra = [dim for dim in reading.dims if dim not in ("wavelength", "theta_i", "cell")]
    if extra:
        raise ValueError(f"an RGL .bsdf holds one specimen: select one parameter point first (dims {extra})")
    grid_reading = reading.as_grid()
    grid = grid_reading.grid
    theta_i = np.atleast_1d(np.asarray(grid_reading.coords["theta_i"], dtype=np.float64))
    wavelengths = np.atleast_1d(np.asarray(grid_reading.coords["wavelength"], dtype=np.float64))
    if np.any(np.diff(theta_i) <= 0):
        raise ValueError(f"an RGL .bsdf needs increasing theta_i (got {theta_i})")
    if np.any(np.diff(wavelengths) <= 0):
        raise ValueError(f"an RGL .bsdf needs increasing wavelengths (got {wavelengths})")
    shape = (len(wavelengths), len(theta_i), grid.size)
    mean = np.asarray(grid_reading.cell_mean, dtype=np.float64).reshape(shape)
    low_cells = np.asarray(grid_reading.cell_mean_lower, dtype=np.float64).reshape(shape)
    high_cells = np.asarray(grid_reading.cell_mean_upper, dtype=np.float64).reshape(shape)
    phi_i = float(grid_reading.settings.phi_i)
    n = grid.resolution
    values = np.zeros((len(wavelengths), len(theta_i), n, n))
    low, high = np.full(values.shape, np.nan), np.full(values.shape, np.nan)
    directions = np.zeros((len(theta_i), n, n, 3))
    cells, valid = np.zeros((len(theta_i), n, n), dtype=np.int64), np.zeros((len(theta_i), n, n), dtype=bool)
    for t, angle in enumerate(theta_i):
        cells[t] = grid.node_cells(float(angle))
        directions[t] = grid.node_directions(float(angle), phi_i)
        omega = np.asarray(grid_reading.solid_angles, dtype=np.float64).reshape(*shape)[0, t]
        valid[t] = omega[cells[t]] > 0
        values[:, t] = np.where(valid[t], np.nan_to_num(mean[:, t][:, cells[t]]), 0.0)
        low[:, t] = np.where(valid[t], low_cells[:, t][:, cells[t]], np.nan)
        high[:, t] = np.where(valid[t], high_cells[:, t][:, cells[t]], np.nan)
    # φi × θi × λ × n × n: two identical φi slices at −π and π (isotropic: the plugin interpolates between them)
    spectra = np.repeat(np.transpose(values, (1, 0, 2, 3))[None], 2, axis=0).astype(np.float32)
    luminance = spectra.mean(axis=2)
    luminance = luminance + max(float(luminance.max()), 1.0) * 1e-6  # a positive density for the plugin's sampling
    description = _description(grid_reading, len(wavelengths) * len(theta_i))
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
                     cells=cells, valid=valid, visible=valid & (directions[..., 2] > 0), values=values, lower=low,
                     upper=high, description=description)
