"""
Results
=======

What the instruments return, and what is derived from it: one family of result kinds
(:mod:`.base`: labels, ``sel`` / ``isel``, files, spectra) — hemispherical readings
(:mod:`.hemispherical`), goniophotometer readings (:mod:`.goniophotometer`), integrating
sphere readings (:mod:`.sphere`) — read back by their format tags (:mod:`.kinds`,
:mod:`.formats`); files (:mod:`.io`, :mod:`.zarr`), colour-science spectra
(:mod:`.colorimetry`) and plots (:mod:`.plot`, :mod:`.angular_plot`).
"""
