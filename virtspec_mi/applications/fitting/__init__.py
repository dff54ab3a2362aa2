"""
Fitting: a specimen's parameters from a measured spectrum
=========================================================

:func:`fit` inverts the instrument: the free parameters of a specimen (ABM-B/ABM-U's
pigments, PROSPECT-D's N, Cab, Car, Cw, Cm, a slab's μa and μs, a rough surface's α …)
whose certified forward spectrum matches a measured reflectance and/or transmittance,
with a confidence set and the parameters the data leave unconstrained
(:mod:`.inversion`); the forward readings on common random numbers, kept for resuming
(:mod:`.forward`); the inputs checked (:mod:`.problem`); the result, its files and
figures (:mod:`.result`); the ``virtspec fit`` command (:mod:`.command`).

References
----------
Féret et al. (2017), RSE 193:204–215; Jacquemoud & Baret (1990), RSE 34:75–91.
"""

from virtspec_mi.applications.fitting.inversion import LOSSES, fit
from virtspec_mi.applications.fitting.result import FitResult, read_fit

__all__ = ["fit", "FitResult", "read_fit", "LOSSES"]
