"""
Simulated against measured spectra: :func:`compare`
===================================================

The paper's first application: a virtual measurement of a material model set against
a real measurement of the material. :func:`compare` takes a result of any kind (or a
result file) and a measured spectrum and reports, over their common wavelengths:

- the residuals (simulated − measured), their RMSE, mean and largest absolute value;
- how many points lie within the **combined tolerance**: the result's
  certified tolerance μ' (each simulated point is within μ' of the model's true value
  with probability ≥ 1 − δ: a reading's ``certified_mu``; for a sphere reading the
  half-width covering its certified interval) plus the measurement's own uncertainty
  when known. If
  the model is the measured material, each point is within its tolerance with
  probability ≥ 1 − δ (less the measurement's own risk); a share well below that
  flags a model that differs from the measured material;
- ΔE2000 between the colours of both spectra under an illuminant (CIE D65 by
  default), through :func:`virtspec_mi.colorimetry.cie.colorimetry` on the common
  wavelengths (refused, with the reason, when they cover too little of the
  colour-matching weight, e.g. a sparse spectrum).

What is compared is one quantity of the result over wavelength at one θi
(:meth:`~virtspec_mi.results.base.ResultBase.spectrum`): a hemispherical reading's or a
goniophotometer reading's reflectance, transmittance or absorptance; a sphere reading's
``reading`` (default), ``corrected`` or ``hemispherical`` value, against a measured
spectrum of what it measures (its reflectance or transmittance column). A result with
parameter dims is compared at one parameter point (select it first:
:meth:`~virtspec_mi.results.labels.Labelled.sel`).

The measured spectrum is linearly interpolated onto the result's wavelengths inside
the measured range only; result wavelengths outside it are left out (and listed),
never extrapolated. :func:`read_measured` reads it from

- a colour-science CSV spectral file (a header ``wavelength,<name>,…``; the column
  named after the quantity, e.g. ``reflectance``, else the only one);
- a plain CSV (or whitespace-separated ``.txt``) of ``wavelength,value`` rows, with an
  optional third column of per-point measurement uncertainty (with a header, an
  uncertainty column is named ``uncertainty`` or ``<quantity>_uncertainty``);
- a NetCDF (xarray) file with a variable named after the quantity (or its only
  variable) over one wavelength dimension, and optionally ``<quantity>_uncertainty``;
- a virtspec-mi result file of any kind (another simulation: its certified tolerance
  is the uncertainty);
- an instrument's or a library's file of one or many spectra — ASD ``.asd``, SVC ``.sig``,
  PSR ``.sed``, JCAMP-DX, ENVI ``.sli``, CSV tables of many samples, and the formats of
  outside packages (:data:`virtspec_mi.exchange.measured.FORMATS`): read by
  :func:`~virtspec_mi.exchange.measured.read_samples`, one sample chosen with a
  :class:`~virtspec_mi.exchange.measured.base.MeasuredFile`.

Wavelengths are in nm (values below 100 are refused with the hint "micrometres? multiply by
1000") and values fractions in [0, 1] (percentages are refused with a hint). A measured
value outside [0, 1] by more than its own measurement uncertainty (none given: at all) is
refused, naming the file, the column and the wavelength: a reflectance below 0 or above 1
is no reflectance, and compared as one it would count against (or for) the model.

References
----------
Baranoski et al. (2001), Sect. 5 (comparisons with measured data), eq. (23);
CIE 142-2001 / CIE 015:2018 (CIEDE2000); colour-science ``colour.delta_E``.
"""


from __future__ import annotations

from virtspec_mi.applications.comparison.measured import MEASURED_SUFFIXES, MeasuredSpectrum, read_measured
from virtspec_mi.applications.comparison.command import ComparisonApplication
from virtspec_mi.applications.comparison.result import Comparison, compare

__all__ = ["MeasuredSpectrum", "Comparison", "read_measured", "compare", "MEASURED_SUFFIXES",
           "ComparisonApplication"]
