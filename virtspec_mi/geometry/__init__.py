"""
Geometry descriptions
=====================

Plain descriptions, checked when built and computed on the host with NumPy: the
emitter and specimen disks and the incidence frame (:mod:`.disks`), the
goniophotometer's bins of outgoing directions (:mod:`.bins`) and the integrating
sphere with its ports and baffle (:mod:`.sphere`). The kernel receives arrays derived
from them.
"""
