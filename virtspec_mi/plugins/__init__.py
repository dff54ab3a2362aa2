"""
virtspec-mi's Mitsuba plugins: the specimens
============================================

One plugin per file: ``bsdfs/`` holds the specimens, each a Mitsuba BSDF implementing
the specimen protocol (:class:`~virtspec_mi.plugins.specimen.Specimen`: one wavelength
range, one wavelength-independence flag, one list of parameters with their bounds and
units). :data:`SPECIMENS` names them (name in scenes → ``"module:Class"``), and an outside
package adds a leaf model without editing this one, as xarray's backends do: an entry
point of the group :data:`ENTRY_POINTS` (``virtspec_mi.specimens``) whose value is its
BSDF class, e.g. in its ``pyproject.toml``::

    [project.entry-points."virtspec_mi.specimens"]
    grey_leaf = "grey_leaf:GreyLeaf"

:func:`specimen_rows` gives both, by name; they are registered with Mitsuba under the
current variant by :func:`virtspec_mi.runtime.mitsuba` (with the plugins of
:data:`virtspec_mi.runtime.PLUGINS` and the instruments' integrators), listed by
``vm.specimens()`` and fitted by name (``vm.fit(..., specimen="grey_leaf")``,
``virtspec fit --specimen grey_leaf``). Nothing here imports Mitsuba.

References
----------
Python Packaging User Guide, "Entry points specification"; xarray, "How to add a new
backend" (the ``xarray.backends`` entry-point group).
"""

from __future__ import annotations

import functools
import importlib
import warnings
from importlib.metadata import entry_points

__all__ = ["SPECIMENS", "ENTRY_POINTS", "specimen_rows", "discovered_specimens", "load_specimen"]

SPECIMENS: dict[str, str] = {
    "simple_dielectric": "virtspec_mi.plugins.bsdfs.simple_dielectric:SimpleDielectric",
    "turbid_slab": "virtspec_mi.plugins.bsdfs.turbid_slab:TurbidSlab",
    "abm_b": "virtspec_mi.plugins.bsdfs.abm_b:ABMB",
    "abm_u": "virtspec_mi.plugins.bsdfs.abm_u:ABMU",
    "tabulated": "virtspec_mi.plugins.bsdfs.tabulated:Tabulated",
    "microfacet": "virtspec_mi.plugins.bsdfs.microfacet:Microfacet",
    "prospect_d": "virtspec_mi.plugins.bsdfs.prospect_d:ProspectD",
}
"""The project's specimen plugins: name in scenes → ``"module:Class"``."""

ENTRY_POINTS = "virtspec_mi.specimens"
"""The entry-point group of outside specimens (a leaf model, a measured material …)."""


def specimen_rows() -> dict[str, str]:
    """
    The specimens by name: :data:`SPECIMENS`, then each entry point of
    :data:`ENTRY_POINTS` of the installed packages (``"module:Class"``, not yet imported).
    An entry point that takes a name already taken is left out with a ``RuntimeWarning``.
    The installed packages are read once per process (as the instruments' entry points
    are: reading them costs some 20 ms); :func:`discovered_specimens` ``.cache_clear()``
    reads them again.
    """

    return dict(discovered_specimens())


@functools.lru_cache(maxsize=None)
def discovered_specimens() -> dict[str, str]:
    """:func:`specimen_rows`, read from the installed packages (once: cached)."""

    rows = dict(SPECIMENS)
    for point in entry_points(group=ENTRY_POINTS):
        if point.name in rows:
            warnings.warn(f"specimen entry point {point.name!r} ({point.value}) takes the name {point.name!r}, "
                          "already taken: left out", RuntimeWarning, stacklevel=2)
        else:
            rows[point.name] = point.value
    return rows


def load_specimen(name: str, row: str) -> type:
    """
    The class of the specimen row ``name`` = ``"module:Class"`` (Mitsuba's variant set:
    a BSDF module builds on ``mi.BSDF``); ``TypeError`` when it is no BSDF class or
    declares no member of :class:`~virtspec_mi.plugins.specimen.Specimen` (naming them).
    """

    import mitsuba as mi

    from virtspec_mi.plugins.specimen import missing

    module, _, attribute = row.partition(":")
    plugin = getattr(importlib.import_module(module), attribute)
    if not (isinstance(plugin, type) and issubclass(plugin, mi.BSDF)):
        raise TypeError(f"specimen {name!r} ({row}) is not a Mitsuba BSDF class (a subclass of mi.BSDF)")
    lacking = missing(plugin)
    if lacking:
        raise TypeError(f"specimen {name!r} ({row}) does not implement the specimen protocol "
                        f"(virtspec_mi.plugins.specimen.Specimen): it declares no {', '.join(lacking)}")
    return plugin
