"""
virtspec-mi's Mitsuba plugins
=============================

One plugin per file: ``bsdfs/`` holds specimens, ``integrators/`` the instruments'
Mitsuba entry (``mi.render``). They are registered under the current Mitsuba variant by
:func:`virtspec_mi.runtime.mitsuba` (the table :data:`virtspec_mi.runtime.PLUGINS`).
"""
