"""
The base layer: what every other layer may use, importing nothing of the package
================================================================================

- :mod:`~virtspec_mi.base.checks` — the checks of values at the boundary (a parameter, its
  allowed range, one message);
- :mod:`~virtspec_mi.base.files` — atomic writes, NetCDF, output paths;
- :mod:`~virtspec_mi.base.llvm` — a libLLVM that Dr.Jit 1.5 can use;
- :mod:`~virtspec_mi.base.interrupts` — SIGINT and SIGTERM at safe points;
- :mod:`~virtspec_mi.base.version` — the package's version.
"""
