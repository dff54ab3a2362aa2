"""
``abm_u``: the ABM-U unifacial plant leaf (corn defaults)
=========================================================

The algorithmic BDF model of Baranoski & Rokne (1997) in its ABM-U form (Baranoski
2006) for unifacial leaves such as corn or sugar cane, 400–2500 nm: a random walk
through six interfaces — air | adaxial epidermis | mesophyll | air | mesophyll |
abaxial epidermis | air — where the mesophyll (thickness d_m) is split at a random
depth u·d_m, u ~ U(0, 1) drawn once per ray. The walk runs inside ``sample()`` (see
:mod:`.abm_walk` for the event order and conventions); each ray is reflected,
transmitted or absorbed with unit weight.

Interface table (abm.md §1.4; exponents: reflected going down / refracted going
down / reflected going up / refracted going up; ∞ = specular):

==  ==============================  =====  =====  =====  =====  ==================
k   interface                       e_DA   e_DB   e_UB   e_UA   absorbing slab
==  ==============================  =====  =====  =====  =====  ==================
0   air / adaxial epidermis         σ_cu   σ_ep   σ_ep   ∞      –
1   adaxial epidermis / mesophyll   σ_ep   σ_sp   σ_sp   σ_ep   below: u·d_m
2   mesophyll / air                 σ_sp   σ_sp   σ_sp   σ_sp   above: u·d_m
3   air / mesophyll                 σ_sp   σ_sp   σ_sp   σ_sp   below: (1−u)·d_m
4   mesophyll / abaxial epidermis   σ_sp   σ_ep   σ_ep   σ_sp   above: (1−u)·d_m
5   abaxial epidermis / air         σ_sp   ∞      σ_cu   σ_sp   –
==  ==============================  =====  =====  =====  =====  ==================

(k = 5 follows the NPSG C++ code, σ_sp; JMIST uses σ_ep — equal at the defaults.)

Parameters
----------
thickness : float, default 2.04e-4
    Whole-leaf thickness h in m (> 0).
mesophyll_fraction : float, default 0.8
    Fraction f_m of the leaf thickness that is mesophyll, 0 < f_m ≤ 1; d_m = f_m · h.
chlorophyll_a, chlorophyll_b : float, default 2.895146, 0.79866
    Chlorophyll a and b per unit mesophyll volume, kg m⁻³ (= 1000 × the NPSG form's
    g cm⁻³), ≥ 0. They share one specific absorption coefficient.
carotenoids : float, default 0.658895
    Carotenoids, kg m⁻³, ≥ 0.
protein : float, default 53.08714
    Protein, kg m⁻³, ≥ 0.
cellulose, lignin : float, default 53.18709, 6.05853
    Cellulose and lignin, kg m⁻³, ≥ 0 (the NPSG online form's split; the sample file
    has 0 + 59.245619, the same sum; lignin uses the cellulose coefficient).
cuticle_aspect_ratio : float, default 10
    σ_cu, cuticle undulations (lobe exponent; lower = more diffuse), > 0 (NPSG: 1–50).
epidermis_aspect_ratio : float, default 5
    σ_ep, epidermal cell caps, > 0.
spongy_aspect_ratio : float, default 5
    σ_sp, mesophyll cell caps, > 0.
sieve_detour : boolean, default true
    Sieve and detour effects (Baranoski & Eng 2007; the NPSG default): the absorption
    test uses the path t / cos(cos θ); false = plain Beer–Lambert, t / cos θ.
side : string, default "adaxial"
    Leaf surface facing the specimen's upper side (+z), where the instrument's light
    arrives: ``adaxial`` or ``abaxial`` (the leaf turned over). Reflectance is always
    the light leaving on the lit side.
lookup : string, default "step"
    Spectral lookup on the 5 nm data grid: ``step`` = ⌊(λ − 400)/5⌋ as the NPSG C++
    reference, ``linear`` = interpolation (NPSG MATLAB).
data_dir : string, default ""
    Directory of the NPSG data files; empty = the environment variable
    ``VIRTSPEC_LEAF_DATA`` (see :mod:`virtspec_mi.leaf_data`).
max_steps : integer, default 100000
    Cap on interface events per walk; a walk reaching it is counted in
    ``Result.capped`` (never in R, T or A).

Defaults: corn, LOPEX 0141/0142 (NPSG online ABM-U model, abm.md §2).

References
----------
Baranoski & Rokne (1997), CGF 16(3):C141–C150; Baranoski (2006), RSE 100:335–347;
Baranoski & Eng (2007), IEEE TGRS 45(8):2593–2599; NPSG reference C++
``abmu_interfaces.cpp`` (abm.md §1.4, §2).
"""

from __future__ import annotations

from virtspec_mi.plugins.bsdfs.abm_walk import AIR, CUTICLE, MESOPHYLL, ABMLeaf, Interface

__all__ = ["ABMU", "CORN"]

CORN: dict[str, float] = {
    "thickness": 2.04e-4,
    "mesophyll_fraction": 0.8,
    "chlorophyll_a": 2.895146,
    "chlorophyll_b": 0.79866,
    "carotenoids": 0.658895,
    "protein": 53.08714,
    "cellulose": 53.18709,
    "lignin": 6.05853,
    "cuticle_aspect_ratio": 10.0,
    "epidermis_aspect_ratio": 5.0,
    "spongy_aspect_ratio": 5.0,
}
"""Corn (LOPEX 0141/0142) parameters in SI units (abm.md §2)."""

_CU, _EP, _SP = "cuticle_aspect_ratio", "epidermis_aspect_ratio", "spongy_aspect_ratio"


class ABMU(ABMLeaf):
    """ABM-U unifacial leaf (see the module docstring)."""

    PLUGIN = "abm_u"
    DEFAULTS = CORN
    INTERFACES = (
        Interface(AIR, CUTICLE, _CU, _EP, _EP, None),
        Interface(CUTICLE, MESOPHYLL, _EP, _SP, _SP, _EP, slab_below=(0.0, 1.0)),
        Interface(MESOPHYLL, AIR, _SP, _SP, _SP, _SP, slab_above=(0.0, 1.0)),
        Interface(AIR, MESOPHYLL, _SP, _SP, _SP, _SP, slab_below=(1.0, -1.0)),
        Interface(MESOPHYLL, CUTICLE, _SP, _EP, _EP, _SP, slab_above=(1.0, -1.0)),
        Interface(CUTICLE, AIR, _SP, None, _CU, _SP),
    )
