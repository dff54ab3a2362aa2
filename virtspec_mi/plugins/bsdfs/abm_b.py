"""
``abm_b``: the ABM-B bifacial plant leaf (soybean defaults)
===========================================================

The algorithmic BDF model of Baranoski & Rokne (1997) in its ABM-B form (Baranoski
2006) for bifacial (dorsiventral) leaves such as soybean or maple, 400–2500 nm: a
random walk through six interfaces — air | adaxial epidermis | palisade/spongy
mesophyll (the one absorbing slab) | intercellular air | antidermal wall | abaxial
epidermis | air — run inside ``sample()`` (see :mod:`.abm_walk` for the event order
and conventions). Each ray is reflected, transmitted or absorbed with unit weight.

Interface table (NPSG reference C++ ``abmb_interfaces.cpp``; exponents: reflected going down / refracted going
down / reflected going up / refracted going up; ∞ = specular):

==  ===============================  =====  =====  =====  =====  ==============
k   interface                        e_DA   e_DB   e_UB   e_UA   absorbing slab
==  ===============================  =====  =====  =====  =====  ==============
0   air / adaxial epidermis          σ_cu   σ_ep   σ_ep   ∞      –
1   adaxial epidermis / mesophyll    σ_ep   σ_pa   σ_pa   σ_ep   below: d_m
2   mesophyll / air                  σ_pa   σ_sp   σ_sp   σ_pa   above: d_m
3   air / antidermal wall            ∞      ∞      ∞      ∞      –
4   antidermal wall / abaxial epid.  ∞      σ_ep   σ_ep   ∞      –
5   abaxial epidermis / air          σ_ep   ∞      σ_cu   σ_ep   –
==  ===============================  =====  =====  =====  =====  ==============

Parameters
----------
{parameters}

Defaults: soybean, LOPEX93 specimens 0219/0220 (Hosgood et al. 1995), as in the NPSG
reference's ``samples/lopex_0219_0220.json``.

References
----------
Baranoski & Rokne (1997), CGF 16(3):C141–C150; Baranoski (2006), RSE 100:335–347;
Baranoski & Eng (2007), IEEE TGRS 45(8):2593–2599; NPSG reference C++ implementation
(BSD-3), https://github.com/turtlesoupy/ABM-U-and-ABM-B-CPP: ``abmb_interfaces.cpp``, ``samples/lopex_0219_0220.json``;
Hosgood, B. et al. (1995), Leaf Optical Properties EXperiment 93 (LOPEX93), EUR 16095 EN,
European Commission, Joint Research Centre.
"""

from __future__ import annotations

from virtspec_mi.plugins.bsdfs.abm_walk import (AIR, ANTIDERMAL, CUTICLE, MESOPHYLL, ABMLeaf, Interface, leaf_defaults,
                                                leaf_parameters, parameter_docs)

__all__ = ["ABMB", "SOYBEAN"]

SOYBEAN: dict[str, float] = leaf_defaults(0)
"""Soybean (LOPEX 0219/0220) parameters in SI units (NPSG ``samples/lopex_0219_0220.json``)."""

__doc__ = __doc__.replace("{parameters}", parameter_docs(SOYBEAN))  # the rows are written once, in abm_walk

_CU, _EP, _PA, _SP = "cuticle_aspect_ratio", "epidermis_aspect_ratio", "palisade_aspect_ratio", "spongy_aspect_ratio"


class ABMB(ABMLeaf):
    """ABM-B bifacial leaf (see the module docstring)."""

    PLUGIN = "abm_b"
    DEFAULTS = SOYBEAN
    PARAMETERS = leaf_parameters(SOYBEAN)
    INTERFACES = (
        Interface(AIR, CUTICLE, _CU, _EP, _EP, None),
        Interface(CUTICLE, MESOPHYLL, _EP, _PA, _PA, _EP, slab_below=(1.0, 0.0)),
        Interface(MESOPHYLL, AIR, _PA, _SP, _SP, _PA, slab_above=(1.0, 0.0)),
        Interface(AIR, ANTIDERMAL, None, None, None, None),
        Interface(ANTIDERMAL, CUTICLE, None, _EP, _EP, None),
        Interface(CUTICLE, AIR, _EP, None, _CU, _EP),
    )
