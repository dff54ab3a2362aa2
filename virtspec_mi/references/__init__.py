"""
Independent references
======================

Code that checks the instrument, kept apart from the code it checks: NumPy quadrature
of Fresnel and microfacet models (:mod:`.quadrature`), the slab walk and exact clear
slabs (:mod:`.slab`) and BSDF tables of known models (:mod:`.analytic_tables`). None of
it traces a ray through the instrument. An instrument's own physics references live in
its folder (the integrating sphere's theory: :mod:`virtspec_mi.instruments.sphere.theory`).
"""
