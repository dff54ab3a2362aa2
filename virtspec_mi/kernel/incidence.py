"""
The incidence rotation: where the emitter sits for (θi, φi)
===========================================================

Incidence (θi, φi) rotates the emitter about the specimen centre (the specimen's local
frame: centre at the origin, normal +z). A point (x, y) of the emitter disk goes to
``D·ω + x·e_u + y·e_v`` with

    ω   = (sin θ cos φ, sin θ sin φ, cos θ)      (towards the emitter)
    e_u = (cos θ cos φ, cos θ sin φ, −sin θ)
    e_v = (−sin φ, cos φ, 0)

i.e. the point (x, y, D) rotated by θ about y, then by φ about z. The kernel
(:mod:`virtspec_mi.kernel.tracer`) computes each reading's row from it once per call, on
the host; :mod:`virtspec_mi.geometry.disks` describes the bench around it.

References
----------
Baranoski et al. (2001), Sect. 3.2, Fig. 1.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["incidence_frame"]


def incidence_frame(theta_i: float, phi_i: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(ω, e_u, e_v) for incidence angles in degrees (see the module docstring)."""

    t, p = math.radians(theta_i), math.radians(phi_i)
    ct, st, cp, sp = math.cos(t), math.sin(t), math.cos(p), math.sin(p)
    omega = np.array([st * cp, st * sp, ct])
    e_u = np.array([ct * cp, ct * sp, -st])
    e_v = np.array([-sp, cp, 0.0])
    return omega, e_u, e_v
