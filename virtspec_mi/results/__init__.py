"""
Results
=======

What the instruments return, and what is derived from it: one family of result kinds,
each one ``xarray.Dataset`` of exact counts (:mod:`.base`: files, spectra; :mod:`.labels`:
labels, ``sel`` / ``isel``; a kind's tables of what it derives, :mod:`.variables`, and of
its figures, :mod:`.figures`) and the readings result every
counting instrument returns or extends (:mod:`.readings`: reflectance and transmittance
per reading), read back by their format tags (:mod:`.kinds`, :mod:`.formats`); files
(:mod:`.io`, :mod:`.zarr`), colour-science spectra (:mod:`.colorimetry`) and plots
(:mod:`.plot`). An instrument's own result kind lives in its folder
(``virtspec_mi.instruments.<name>.result``) and registers itself in
:data:`~virtspec_mi.results.base.KINDS`; an application's kinds are records
(:mod:`.records`: a result built from its fields, its Dataset on first use), declared in
its row of :data:`virtspec_mi.applications.APPLICATIONS`.
"""
