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

Interface table (NPSG reference C++ ``abmu_interfaces.cpp``; exponents: reflected going down / refracted going
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
{parameters}

Defaults: corn, LOPEX93 specimens 0141/0142 (Hosgood et al. 1995), as in the NPSG
reference's ``samples/lopex_0141_0142.json``.

References
----------
Baranoski & Rokne (1997), CGF 16(3):C141–C150; Baranoski (2006), RSE 100:335–347;
Baranoski & Eng (2007), IEEE TGRS 45(8):2593–2599; NPSG reference C++ implementation
(BSD-3), https://github.com/turtlesoupy/ABM-U-and-ABM-B-CPP: ``abmu_interfaces.cpp``, ``samples/lopex_0141_0142.json``;
Hosgood, B. et al. (1995), Leaf Optical Properties EXperiment 93 (LOPEX93), EUR 16095 EN,
European Commission, Joint Research Centre.
"""

from __future__ import annotations

from virtspec_mi.plugins.bsdfs.abm_walk import (AIR, CUTICLE, MESOPHYLL, ABMLeaf, Interface, leaf_defaults,
                                                leaf_parameters, parameter_docs)

__all__ = ["ABMU", "CORN"]

CORN: dict[str, float] = leaf_defaults(1)
"""Corn (LOPEX 0141/0142) parameters in SI units (NPSG ``samples/lopex_0141_0142.json``)."""

__doc__ = __doc__.replace("{parameters}", parameter_docs(CORN))  # the rows are written once, in abm_walk

_CU, _EP, _SP = "cuticle_aspect_ratio", "epidermis_aspect_ratio", "spongy_aspect_ratio"


class ABMU(ABMLeaf):
    """ABM-U unifacial leaf (see the module docstring)."""

    PLUGIN = "abm_u"
    DEFAULTS = CORN
    PARAMETERS = leaf_parameters(CORN)
    INTERFACES = (
        Interface(AIR, CUTICLE, _CU, _EP, _EP, None),
        Interface(CUTICLE, MESOPHYLL, _EP, _SP, _SP, _EP, slab_below=(0.0, 1.0)),
        Interface(MESOPHYLL, AIR, _SP, _SP, _SP, _SP, slab_above=(0.0, 1.0)),
        Interface(AIR, MESOPHYLL, _SP, _SP, _SP, _SP, slab_below=(1.0, -1.0)),
        Interface(MESOPHYLL, CUTICLE, _SP, _EP, _EP, _SP, slab_above=(1.0, -1.0)),
        Interface(CUTICLE, AIR, _SP, None, _CU, _SP),
    )
