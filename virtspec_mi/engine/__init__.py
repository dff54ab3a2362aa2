"""
The engine
==========

From a plan to exact tallies, one path for every instrument: the plan of a run
(:mod:`.plan`), its tallies (:mod:`.tally`), readings budgeted by their rule and traced in
keyed batches through the kernel (:mod:`.readings`), keyed runs resumed from checkpoints
(:mod:`.checkpoint`), progress bars (:mod:`.progress`), specimen parameter points
(:mod:`.parameters`) and the emitter and specimen disks read from a loaded scene
(:mod:`.bench`).
"""
