"""
Colour: colorimetry of spectra and certified colours
====================================================

- :mod:`~virtspec_mi.colorimetry.cie` — CIE XYZ, L*a*b* and sRGB of a spectrum through
  colour-science;
- :mod:`~virtspec_mi.colorimetry.certified` — the colour of certified counts: tristimulus
  weights, XYZ as linear functionals, the certified L*a*b* box;
- :mod:`~virtspec_mi.colorimetry.delta_e` — ΔE*ab and a rigorous ΔE₀₀ enclosure over boxes.
"""
