"""
Exchange formats: the grids, files and bases that renderers and simulation tools read
=======================================================================================

The formats themselves, below every layer that measures (the applications that fill them:
:mod:`virtspec_mi.applications.tables` and :mod:`virtspec_mi.applications.klems`):

- :mod:`~virtspec_mi.exchange.conventions` — the grids, parameterisations and memory
  orders of the albedo tables of Cycles, Filament and Unreal;
- :mod:`~virtspec_mi.exchange.engine_models` — each engine's own microfacet model;
- :mod:`~virtspec_mi.exchange.header` — C/C++ headers of tables, and published ones read back;
- :mod:`~virtspec_mi.exchange.klems_basis` — the Klems angle bases of WINDOW / Radiance files;
- :mod:`~virtspec_mi.exchange.common` — companion files and derived seeds.

Files are written by :mod:`virtspec_mi.base.files`. This package's ``__init__`` imports nothing.
"""
