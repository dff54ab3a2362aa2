"""
Results
=======

What the instruments return, and what is derived from it: hemispherical readings
(:mod:`.hemispherical`), goniophotometer readings (:mod:`.goniophotometer`), integrating
sphere readings (:mod:`.sphere`); files (:mod:`.io`, :mod:`.zarr`), colour-science spectra
(:mod:`.colorimetry`) and plots (:mod:`.plot`, :mod:`.angular_plot`).
"""
