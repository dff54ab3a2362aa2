"""
Independent references
======================

Code that checks the instrument, kept apart from the code it checks: NumPy quadrature
of Fresnel and microfacet models (:mod:`.quadrature`), the slab walk and exact clear
slabs (:mod:`.slab`), BSDF tables of known models (:mod:`.analytic_tables`), and the
integrating-sphere theory (:mod:`.sphere_theory`, with its inputs from a sphere
description: :mod:`.sphere_model`). None of it traces a ray through the instrument.
"""
