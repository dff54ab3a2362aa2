"""
Spectral indices of bands, with exact intervals from certified band boxes
=========================================================================

Every index here is a normalised difference of two bands, I = (A − B)/(A + B), which
rises with A and falls with B wherever A, B ≥ 0 (∂I/∂A = 2B/(A + B)², ∂I/∂B =
−2A/(A + B)²). Its interval over a certified box of the bands — each band within its
interval, both clipped to [0, 1] where reflectances lie — is therefore exact at two
corners: [I(A_lo, B_hi), I(A_hi, B_lo)] (interval arithmetic on a monotone map).

:data:`INDICES` names the bands of each index (Sentinel-2 rectangular bands,
:data:`~virtspec_mi.applications.targets.bands.SENTINEL_2`, or narrow rectangles): the
formulas follow the Awesome Spectral Indices catalogue (Montero et al. 2023), written
out here rather than taken from the ``spyndex`` package, whose dependencies (Earth
Engine clients) are heavy for four normalised differences.

References
----------
Rouse, J. W. et al. (1974). Monitoring vegetation systems in the Great Plains with ERTS.
NASA SP-351, 309–317 (NDVI).
Gamon, J. A., Peñuelas, J. & Field, C. B. (1992). A narrow-waveband spectral index that
tracks diurnal changes in photosynthetic efficiency. *Remote Sens. Environ.* 41, 35–44 (PRI).
Gitelson, A. A., Kaufman, Y. J. & Merzlyak, M. N. (1996). Use of a green channel in remote
sensing of global vegetation from EOS-MODIS. *Remote Sens. Environ.* 58, 289–298 (GNDVI).
Gitelson, A. & Merzlyak, M. N. (1994). Spectral reflectance changes associated with autumn
senescence of *Aesculus hippocastanum* L. and *Acer platanoides* L. leaves. *J. Plant
Physiol.* 143, 286–292 (NDRE, red edge).
Montero, D. et al. (2023). A standardized catalogue of spectral indices to advance the use
of remote sensing in Earth system research. *Scientific Data* 10, 197.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

__all__ = ["Index", "INDICES", "index_definition"]


@dataclass(frozen=True)
class Index:
    """I = (A − B)/(A + B) of bands ``plus`` (A) and ``minus`` (B); ``long_name``; ``reference``."""

    name: str
    plus: Any
    minus: Any
    long_name: str
    reference: str

    @staticmethod
    def value(a: float, b: float) -> float:
        if a + b <= 0:
            raise ValueError("a normalised difference needs A + B > 0 (both bands dark)")
        return (a - b) / (a + b)

    def interval(self, a: tuple[float, float], b: tuple[float, float]) -> tuple[float, float]:
        """The exact range of I over A in ``a``, B in ``b`` (each clipped to [0, 1])."""

        a_lo, a_hi = max(a[0], 0.0), min(a[1], 1.0)
        b_lo, b_hi = max(b[0], 0.0), min(b[1], 1.0)
        if a_lo + b_hi <= 0 or a_hi + b_lo <= 0:
            raise ValueError(f"{self.name}: the bands' intervals reach A + B = 0: no interval (measure tighter)")
        return self.value(a_lo, b_hi), self.value(a_hi, b_lo)

    def gradient(self, a: float, b: float) -> tuple[float, float]:
        """(∂I/∂A, ∂I/∂B) at (a, b)."""

        total = max(a + b, 1e-12) ** 2
        return 2 * b / total, -2 * a / total


INDICES: dict[str, Index] = {
    "NDVI": Index("NDVI", "B08", "B04", "normalized difference vegetation index", "Rouse et al. (1974)"),
    "GNDVI": Index("GNDVI", "B08", "B03", "green normalized difference vegetation index", "Gitelson et al. (1996)"),
    "NDRE": Index("NDRE", "B8A", "B05", "normalized difference red edge index", "Gitelson & Merzlyak (1994)"),
    "PRI": Index("PRI", (526.0, 536.0), (565.0, 575.0), "photochemical reflectance index (531 and 570 nm, 10 nm wide)",
                 "Gamon et al. (1992)"),
}
"""The indices by name: their bands (a Sentinel-2 name or rectangular edges in nm)."""


def index_definition(name: str, bands: dict[str, Any] | None = None) -> Index:
    """The :class:`Index` ``name`` (case-insensitive), its bands replaced by ``bands`` ({"plus": .., "minus": ..})."""

    key = str(name).upper()
    if key not in INDICES:
        raise ValueError(f"index must be one of {', '.join(INDICES)} (got {name!r})")
    found = INDICES[key]
    if bands:
        unknown = set(bands) - {"plus", "minus"}
        if unknown:
            raise ValueError(f"bands of an index are 'plus' (A) and 'minus' (B) of (A - B)/(A + B) "
                             f"(got {sorted(unknown)})")
        found = Index(found.name, bands.get("plus", found.plus), bands.get("minus", found.minus), found.long_name,
                      found.reference)
    return found
