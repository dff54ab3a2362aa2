"""
Grids and parameterisations of the engines' albedo tables
=========================================================

Renderers precompute the directional albedo E(μ, α) of their microfacet models on
grids of their own; a certified table meant to replace one must use the same grid,
parameterisation and memory order. :data:`ENGINES` describes the three read for this
module (their generators, not their documentation, were read):

``cycles`` — Blender Cycles, ``intern/cycles/app/cycles_precompute.cpp``
    GGX ``ggx_E`` 32 × 32, ``ggx_Eavg`` 32; ``ggx_glass_E`` / ``ggx_glass_inv_E``
    16 × 16 × 16, ``ggx_glass_Eavg`` / ``ggx_glass_inv_Eavg`` 16 × 16. Index x (fastest)
    is the roughness r = clamp(x/(n_x − 1), 10⁻⁴, 1) and **α = r²**; y is the cosine
    μ = clamp(y/(n_y − 1), 10⁻⁴, 1) (grid *nodes*, end points included); z the index of
    refraction, s = clamp(z/(n_z − 1), 10⁻⁴, 0.99), F₀ = s⁴, η = (1 + √F₀)/(1 − √F₀) =
    (1 + s²)/(1 − s²) (so η runs from 1 to 99.5, dense near 1–2). Memory order
    ``table[z][y][x]`` = [η][μ][roughness]; the ``_inv_`` tables use 1/η (light arriving
    from inside the glass). E_avg = ∫₀¹ 2μ E(μ) dμ (μ drawn uniformly per sample).
    Printed with six decimals, clamped to [0, 1].
``filament`` — Google Filament, ``libs/ibl/src/CubemapIBL.cpp`` (``CubemapIBL::DFG``)
    128 × 128 DFG texture: column x is μ = (x + ½)/128 (texel *centres*), row y is
    α = c² with c = min(1, (128 − y + ½)/128) (Filament calls α the "linear roughness";
    the top row is the roughest). Memory order ``table[y][x]`` = [roughness][μ]. It stores
    the split Fresnel terms; with F = 1 the albedo is DFG.x + DFG.y (DFG.y alone in the
    multiscatter variant). GGX with the height-correlated Smith visibility.
``unreal`` — Unreal Engine 4, ``Engine/Source/Runtime/Renderer/Private/SystemTextures.cpp``
    (``PreintegratedGF``) 128 × 32 texture: column x is μ = (x + ½)/128, row y the
    roughness r = (y + ½)/32 (texel centres), **α = r²**. Memory order
    ``table[y][x]`` = [roughness][μ]; 16-bit unorm channels; GGX with the
    ``Vis_SmithJointApprox`` visibility. (The issue that asked for this module quotes a 32² table with 2¹⁴
    samples per texel for Unreal; that generator was not available to read, so it is
    not reproduced here: give ``mu`` and ``roughness`` for it.)

On an engine's grid a conductor table measures the engine's own model by default
(:mod:`virtspec_mi.exchange.engine_models`: the ``microfacet`` plugin with the engine's
G₂, height-correlated for Cycles and Filament); glass tables measure Mitsuba's
``roughdielectric`` (separable), which is not Cycles' glass model. GGX visible normals
are sampled for any α > 0, so Cycles' first roughness column (α = 10⁻⁸) is measured as
such; Mitsuba clamps α ≥ 10⁻⁴ in its own samplers (Beckmann, glass).

References
----------
Kulla, C., Conty, A. (2017). Revisiting physically based shading at Imageworks. SIGGRAPH
course *Physically Based Shading in Theory and Practice* (E(μ), E_avg tables).
Karis, B. (2013). Real shading in Unreal Engine 4. SIGGRAPH course *Physically Based
Shading in Theory and Practice* (the pre-integrated (μ, roughness) texture).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

__all__ = ["ENGINES", "Convention", "convention", "cycles_roughness", "cycles_mu", "cycles_ior", "texel_centres"]


def cycles_roughness(count: int) -> np.ndarray:
    """Cycles' roughness nodes r = clamp(x/(n − 1), 10⁻⁴, 1) (α = r²)."""

    return np.clip(np.arange(count) / (count - 1), 1e-4, 1.0)


def cycles_mu(count: int) -> np.ndarray:
    """Cycles' cosine nodes μ = clamp(y/(n − 1), 10⁻⁴, 1)."""

    return np.clip(np.arange(count) / (count - 1), 1e-4, 1.0)


def cycles_ior(count: int) -> np.ndarray:
    """Cycles' index nodes η = (1 + s²)/(1 − s²), s = clamp(z/(n − 1), 10⁻⁴, 0.99) (F₀ = s⁴)."""

    s = np.clip(np.arange(count) / (count - 1), 1e-4, 0.99)
    return (1.0 + s * s) / (1.0 - s * s)


def texel_centres(count: int) -> np.ndarray:
    """(i + ½)/n for i = 0 … n − 1: the centres of n texels over [0, 1]."""

    return (np.arange(count) + 0.5) / count


@dataclass(frozen=True)
class Convention:
    """
    One engine's table layout (see the module docstring).

    Attributes
    ----------
    name : str
        ``cycles``, ``filament``, ``unreal``, or ``grid`` (user-given nodes).
    mu : ndarray
        Cosines μ of the table's columns/rows, in table order.
    alpha : ndarray
        Roughness α of the microfacet distribution, in table order.
    roughness : ndarray or None
        The engine's own roughness coordinate when α = roughness² (else ``None``).
    eta : ndarray or None
        Relative indices (glass tables).
    order : tuple of str
        Memory order of the table, slowest first, in the names ``eta``, ``mu``,
        ``alpha`` (the C header and ``.npy`` files use it).
    source : str
        The file the convention was read from.
    notes : str
        What else a user of the engine's table needs to know.
    """

    name: str
    mu: np.ndarray
    alpha: np.ndarray
    roughness: np.ndarray | None = None
    eta: np.ndarray | None = None
    order: tuple[str, ...] = ("mu", "alpha")
    source: str = ""
    notes: str = ""
    extra: dict[str, Any] = field(default_factory=dict)


ENGINES: dict[str, str] = {
    "cycles": "Blender Cycles: intern/cycles/app/cycles_precompute.cpp (32 x 32 GGX E, nodes, alpha = roughness^2; "
              "glass 16 x 16 x 16)",
    "filament": "Google Filament: libs/ibl/src/CubemapIBL.cpp DFG (128 x 128, texel centres, alpha = c^2, "
                "roughest row first)",
    "unreal": "Unreal Engine 4: SystemTextures.cpp PreintegratedGF (128 mu x 32 roughness, texel centres, "
              "alpha = roughness^2)",
}
"""Engines whose table layout :func:`convention` reproduces, and where each was read."""


def convention(engine: str, model: str = "conductor") -> Convention:
    """
    The grid and memory order of ``engine``'s table for ``model`` (``conductor`` or ``glass``).

    Raises
    ------
    ValueError
        For an unknown engine, or a glass table of an engine that has none.
    """

    if engine not in ENGINES:
        raise ValueError(f"engine must be one of {', '.join(ENGINES)} (got {engine!r})")
    if model not in ("conductor", "glass"):
        raise ValueError(f"model must be 'conductor' or 'glass' (got {model!r})")
    if engine == "cycles":
        size = 16 if model == "glass" else 32
        rough = cycles_roughness(size)
        return Convention(
            "cycles", cycles_mu(size), rough * rough, rough,
            cycles_ior(16) if model == "glass" else None,
            ("eta", "mu", "alpha") if model == "glass" else ("mu", "alpha"),
            "intern/cycles/app/cycles_precompute.cpp",
            "table[z][y][x]: z = index of refraction, y = mu, x = roughness (alpha = roughness^2); nodes with "
            "clamped ends (mu, roughness >= 1e-4); E_avg = int 2 mu E dmu per roughness",
            {"eavg_order": ("eta", "alpha") if model == "glass" else ("alpha",)})
    if model == "glass":
        raise ValueError(f"engine {engine!r} has no glass table (give mu, alpha and eta for one)")
    if engine == "filament":
        coord = np.minimum(1.0, (128 - np.arange(128) + 0.5) / 128)
        return Convention("filament", texel_centres(128), coord * coord, coord, None, ("alpha", "mu"),
                          "libs/ibl/src/CubemapIBL.cpp (CubemapIBL::DFG)",
                          "table[y][x]: y = roughness row, roughest first (alpha = c^2, c = min(1, (128 - y + 1/2)/128)), "
                          "x = mu = (x + 1/2)/128; with F = 1 the engine's value is DFG.x + DFG.y")
    rough = texel_centres(32)
    return Convention("unreal", texel_centres(128), rough * rough, rough, None, ("alpha", "mu"),
                      "Engine/Source/Runtime/Renderer/Private/SystemTextures.cpp (PreintegratedGF)",
                      "table[y][x]: y = roughness (y + 1/2)/32 (alpha = roughness^2), x = mu = (x + 1/2)/128; with F = 1 "
                      "the engine's value is A + B")
