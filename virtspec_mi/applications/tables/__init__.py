"""
Certified albedo tables of renderers, each engine's own tables and their audit
==============================================================================

- :mod:`~virtspec_mi.applications.tables.albedo` — :func:`albedo_table`: E(μ, α) and E_avg;
- :mod:`~virtspec_mi.applications.tables.table` — :class:`AlbedoTable`, its files and its
  comparison with a published table;
- :mod:`~virtspec_mi.applications.tables.engine_tables` — each engine's channels in its own files;
- :mod:`~virtspec_mi.applications.tables.audit` — an engine's published table held to a
  certified one.
"""
