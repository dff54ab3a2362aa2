"""
Geometry descriptions
=====================

Plain descriptions, checked when built and computed on the host with NumPy: the
emitter and specimen disks and the incidence frame (:mod:`.disks`), which every
instrument shares. An instrument's own geometry lives in its folder (the
goniophotometer's bins: :mod:`virtspec_mi.instruments.goniophotometer.bins`; the
integrating sphere: :mod:`virtspec_mi.instruments.sphere.geometry`). The kernel receives
arrays derived from them.
"""
