"""
The engine
==========

From planned readings to exact counts: readings budgeted by their rule and traced in
chunks through the kernel (:mod:`.readings`), keyed runs resumed from checkpoints
(:mod:`.checkpoint`), progress bars (:mod:`.progress`), specimen parameter points
(:mod:`.parameters`) and the emitter and specimen disks read from a loaded scene
(:mod:`.bench`).
"""
