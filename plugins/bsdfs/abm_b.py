"""
``abm_b``: the ABM-B bifacial plant leaf (soybean defaults)
===========================================================

The algorithmic BDF model of Baranoski & Rokne (1997) in its ABM-B form (Baranoski
2006) for bifacial (dorsiventral) leaves such as soybean or maple, 400–2500 nm: a
random walk through six interfaces — air | adaxial epidermis | palisade/spongy
mesophyll (the one absorbing slab) | intercellular air | antidermal wall | abaxial
epidermis | air — run inside ``sample()`` (see :mod:`.abm_walk` for the event order
and conventions). Each ray is reflected, transmitted or absorbed with unit weight.

Interface table (abm.md §1.4; exponents: reflected going down / refracted going
down / reflected going up / refracted going up; ∞ = specular):

==  ==============================  =====  =====  =====  =====  ==============
k   interface                       e_DA   e_DB   e_UB   e_UA   absorbing slab
==  ==============================  =====  =====  =====  =====  ==============
0   air / adaxial epidermis         σ_cu   σ_ep   σ_ep   ∞      –
1   adaxial epidermis / mesophyll   σ_ep   σ_pa   σ_pa   σ_ep   below: d_m
2   mesophyll / air                 σ_pa   σ_sp   σ_sp   σ_pa   above: d_m
3   air / antidermal wall           ∞      ∞      ∞      ∞      –
4   antidermal wall / abaxial epid. ∞      σ_ep   σ_ep   ∞      –
5   abaxial epidermis / air         σ_ep   ∞      σ_cu   σ_ep   –
==  ==============================  =====  =====  =====  =====  ==============

Parameters
----------
thickness : float, default 1.66e-4
    Whole-leaf thickness h in m (> 0).
mesophyll_fraction : float, default 0.5
    Fraction f_m of the leaf thickness that is mesophyll, 0 < f_m ≤ 1; d_m = f_m · h.
chlorophyll_a, chlorophyll_b : float, default 3.9775, 1.1613
    Chlorophyll a and b per unit mesophyll volume, kg m⁻³ (= 1000 × the NPSG form's
    g cm⁻³), ≥ 0. They share one specific absorption coefficient.
carotenoids : float, default 1.1323
    Carotenoids, kg m⁻³, ≥ 0.
protein : float, default 78.7059
    Protein, kg m⁻³, ≥ 0 (the NPSG online form's 0.078059 g cm⁻³ is a typo, abm.md §1.10).
cellulose, lignin : float, default 37.7565, 10.7441
    Cellulose and lignin, kg m⁻³, ≥ 0 (lignin uses the cellulose coefficient).
cuticle_aspect_ratio : float, default 5
    σ_cu, cuticle undulations (lobe exponent; lower = more diffuse), > 0 (NPSG: 1–50).
epidermis_aspect_ratio : float, default 5
    σ_ep, epidermal cell caps, > 0.
palisade_aspect_ratio : float, default 1
    σ_pa, palisade cell caps, > 0.
spongy_aspect_ratio : float, default 5
    σ_sp, spongy cell caps, > 0.
sieve_detour : boolean, default true
    Sieve and detour effects (Baranoski & Eng 2007; the NPSG default): the absorption
    test uses the path t / cos(cos θ); false = plain Beer–Lambert, t / cos θ.
side : string, default "adaxial"
    Leaf surface facing the specimen's upper side (+z), where the instrument's light
    arrives: ``adaxial`` or ``abaxial`` (the leaf turned over). Reflectance is always
    the light leaving on the lit side.
lookup : string, default "step"
    Spectral lookup on the 5 nm data grid: ``step`` = ⌊(λ − 400)/5⌋ as the NPSG C++
    reference (551 nm reads the 550 nm data), ``linear`` = interpolation (NPSG MATLAB).
data_dir : string, default ""
    Directory of the NPSG data files; empty = the environment variable
    ``VIRTSPEC_LEAF_DATA`` (see :mod:`virtspec_mi.leaf_data`).
max_steps : integer, default 100000
    Cap on interface events per walk; a walk reaching it is counted in
    ``Result.capped`` (never in R, T or A). The longest soybean walks are ≈ 200 events.

Defaults: soybean, LOPEX 0219/0220 (NPSG online ABM-B model, abm.md §2).

References
----------
Baranoski & Rokne (1997), CGF 16(3):C141–C150; Baranoski (2006), RSE 100:335–347;
Baranoski & Eng (2007), IEEE TGRS 45(8):2593–2599; NPSG reference C++
``abmb_interfaces.cpp`` (abm.md §1.4, §2).
"""

from __future__ import annotations

from virtspec_mi.plugins.bsdfs.abm_walk import AIR, ANTIDERMAL, CUTICLE, MESOPHYLL, ABMLeaf, Interface

__all__ = ["ABMB", "SOYBEAN"]

SOYBEAN: dict[str, float] = {
    "thickness": 1.66e-4,
    "mesophyll_fraction": 0.5,
    "chlorophyll_a": 3.9775,
    "chlorophyll_b": 1.1613,
    "carotenoids": 1.1323,
    "protein": 78.7059,
    "cellulose": 37.7565,
    "lignin": 10.7441,
    "cuticle_aspect_ratio": 5.0,
    "epidermis_aspect_ratio": 5.0,
    "palisade_aspect_ratio": 1.0,
    "spongy_aspect_ratio": 5.0,
}
"""Soybean (LOPEX 0219/0220) parameters in SI units (abm.md §2)."""

_CU, _EP, _PA, _SP = "cuticle_aspect_ratio", "epidermis_aspect_ratio", "palisade_aspect_ratio", "spongy_aspect_ratio"


class ABMB(ABMLeaf):
    """ABM-B bifacial leaf (see the module docstring)."""

    PLUGIN = "abm_b"
    DEFAULTS = SOYBEAN
    INTERFACES = (
        Interface(AIR, CUTICLE, _CU, _EP, _EP, None),
        Interface(CUTICLE, MESOPHYLL, _EP, _PA, _PA, _EP, slab_below=(1.0, 0.0)),
        Interface(MESOPHYLL, AIR, _PA, _SP, _SP, _PA, slab_above=(1.0, 0.0)),
        Interface(AIR, ANTIDERMAL, None, None, None, None),
        Interface(ANTIDERMAL, CUTICLE, None, _EP, _EP, None),
        Interface(CUTICLE, AIR, _EP, None, _CU, _EP),
    )
