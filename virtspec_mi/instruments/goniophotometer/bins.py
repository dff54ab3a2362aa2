"""
Goniophotometer bins: the outgoing directions a reading tallies
===============================================================

:class:`GonioBins` is the one description of how a goniophotometer reading
(:func:`virtspec_mi.gonio`) bins the rays that escape the specimen by their outgoing
direction in the specimen frame: polar angle θo ∈ [0°, 180°] from the specimen normal
+z (θo < 90°: reflected, upper hemisphere; θo > 90°: transmitted) and azimuth
φo ∈ [0°, 360°) from the specimen's x axis (the frame of φi; the mirror direction of an
incidence (θi, φi) is (θi, φi + 180°)). :func:`make_bins` builds it from what a user
writes (API keywords, ``virtspec gonio`` flags, integrator parameters) and refuses a bad
specification with a ``ValueError`` naming the parameter and its allowed range.

Binnings (``binning``, for a whole number of θo bins per hemisphere):

- ``uniform``: equal widths in θo in each hemisphere, equal widths in φo;
- ``projected``: equal *projected* solid angle ∫ |cos θo| dω — uniform in sin²θo in each
  hemisphere, equal widths in φo — so that every bin of a Lambertian specimen receives
  the same expected share of rays (the share of bin k is ρ·Ω_k/π).

Or ``theta_o_bins`` / ``phi_o_bins`` as explicit edges in degrees (increasing,
contiguous, within [0, 180] and [0, 360]; a θo range that crosses 90° must have 90 as
an edge, so no bin straddles the two hemispheres). Rays escaping outside the covered
range are counted nowhere in the bins (``outside`` = reflected + transmitted − Σ bins).

Isotropic folding (``fold_phi=True``): for a specimen whose BSDF is invariant under
rotation about its normal *and* mirror-symmetric about the plane of incidence, only the
relative azimuth matters; φo is folded to |φo − φi| ∈ [0°, 180°] (wrapped) and the φo
edges cover [0, 180]. A folded bin [a, b] stands for the two real bins [φi + a, φi + b]
and [φi − b, φi − a]: its projected solid angle doubles, so the BRDF estimate f_k is an
average over both halves (unchanged for an isotropic specimen).

Projected solid angle of bin (θ₁, θ₂) × (φ₁, φ₂), per hemisphere part:

    Ω_k = ∫_bin |cos θ| dω = (φ₂ − φ₁) · |sin²θ₂ − sin²θ₁| / 2   (angles in radians)

(× 2 when folded); Σ_k Ω_k = π per hemisphere.

The kernel (:mod:`virtspec_mi.instruments.goniophotometer.hook`, from
:meth:`GonioBins.layout`) finds a ray's bin by searching the float32 *keys* of the θo edges, key(θ) = sin²θ for θ ≤ 90° and 2 − sin²θ beyond (a
monotone map of θ ∈ [0, 180] onto [0, 2] that is exact at the poles and at 90°); the
hemisphere is the ray's fate (reflected or transmitted), so the bins of each
hemisphere add up exactly to the reflected and transmitted counts when they cover it.

References
----------
Nicodemus, F.E. et al. (1977). Geometrical considerations and nomenclature for
reflectance. NBS Monograph 160 (BRDF, projected solid angle).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from virtspec_mi.base.checks import shown_value, value_tokens
from virtspec_mi.instruments.goniophotometer.hook import BinLayout

__all__ = ["BINNINGS", "HEMISPHERES", "MAX_BINS", "GonioBins", "make_bins", "parse_edges"]

BINNINGS: dict[str, str] = {
    "uniform": "equal widths in theta_o (per hemisphere) and phi_o",
    "projected": "equal projected solid angle: uniform in sin^2 theta_o per hemisphere (a Lambertian gets equal "
                 "shares), equal widths in phi_o",
}
"""θo binnings for a whole number of bins per hemisphere, and what each means."""

HEMISPHERES: dict[str, tuple[float, float]] = {
    "both": (0.0, 180.0), "reflection": (0.0, 90.0), "transmission": (90.0, 180.0)}
"""θo ranges (degrees) binned for a whole number of θo bins."""

MAX_BINS: int = 1 << 20
"""Most bins (θo × φo) of one reading: per-reading tallies are int64, 8 MiB at most per reading."""

_MAX_PER_AXIS = 1 << 16

@dataclass(frozen=True, eq=False)
class GonioBins:
    """
    The θo × φo bins of a goniophotometer reading (edges in degrees, float64).

    Attributes
    ----------
    theta_edges : ndarray
        Increasing θo edges in [0, 180]; 90 is an edge when the range crosses it.
    phi_edges : ndarray
        Increasing φo edges in [0, 360] (folded: relative azimuth in [0, 180]).
    fold_phi : bool
        φo folded to the relative azimuth |φo − φi| (isotropic specimens).
    binning : str
        How the θo edges were made: ``uniform``, ``projected`` or ``edges`` (given).
    """

    theta_edges: np.ndarray
    phi_edges: np.ndarray
    fold_phi: bool = False
    binning: str = "uniform"
    hemispheres: str = "both"

    @property
    def regular_theta(self) -> tuple[int, bool, bool] | None:
        """
        (bins per hemisphere, reflection binned, transmission binned) for θo bins made by
        a binning (the kernel then finds the bin arithmetically); ``None`` for given edges.
        """

        if self.binning not in BINNINGS:
            return None
        covered = {"both": (True, True), "reflection": (True, False), "transmission": (False, True)}[self.hemispheres]
        return self.shape[0] // sum(covered), *covered

    @property
    def regular_phi(self) -> bool:
        """True for equal φo bins over the whole range (the kernel finds the bin arithmetically)."""

        top = 180.0 if self.fold_phi else 360.0
        return bool(self.phi_edges[0] == 0.0 and self.phi_edges[-1] == top
                    and np.allclose(np.diff(self.phi_edges), top / (len(self.phi_edges) - 1), rtol=1e-12, atol=0))

    @property
    def shape(self) -> tuple[int, int]:
        """(θo bins, φo bins)."""

        return len(self.theta_edges) - 1, len(self.phi_edges) - 1

    @property
    def size(self) -> int:
        """K: the number of bins."""

        return self.shape[0] * self.shape[1]

    @property
    def theta_centres(self) -> np.ndarray:
        return (self.theta_edges[:-1] + self.theta_edges[1:]) / 2

    @property
    def phi_centres(self) -> np.ndarray:
        return (self.phi_edges[:-1] + self.phi_edges[1:]) / 2

    @property
    def transmitted(self) -> np.ndarray:
        """Per θo bin: True for a transmission bin (θo > 90°)."""

        return self.theta_centres > 90.0

    def projected_solid_angles(self) -> np.ndarray:
        """Ω_k = ∫_bin |cos θo| dωo (sr) of every bin, shape (θo bins, φo bins); doubled when folded."""

        sin2 = np.sin(np.radians(self.theta_edges)) ** 2
        polar = np.abs(np.diff(sin2)) / 2
        azimuth = np.radians(np.diff(self.phi_edges)) * (2.0 if self.fold_phi else 1.0)
        return polar[:, None] * azimuth[None, :]

    def theta_keys(self) -> np.ndarray:
        """The float32 search keys of the θo edges: sin²θ (θ ≤ 90°), 2 − sin²θ beyond (see the module)."""

        return _theta_keys(self.theta_edges)

    def layout(self) -> BinLayout:
        """
        The plain arrays the kernel bins rays with
        (:class:`~virtspec_mi.instruments.goniophotometer.hook.BinLayout`).
        """

        return BinLayout(shape=self.shape, theta_keys=self.theta_keys(), regular_theta=self.regular_theta,
                         projected=self.binning == "projected", phi_edges=self.phi_edges.astype(np.float32),
                         regular_phi=self.regular_phi, fold_phi=self.fold_phi)

    def as_dict(self) -> dict[str, Any]:
        return {"theta_edges": self.theta_edges.tolist(), "phi_edges": self.phi_edges.tolist(),
                "fold_phi": self.fold_phi, "binning": self.binning, "hemispheres": self.hemispheres}

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> "GonioBins":
        binning = str(data.get("binning", "edges"))
        theta = np.asarray(data["theta_edges"], dtype=np.float64)
        phi = np.asarray(data["phi_edges"], dtype=np.float64)
        fold = bool(data["fold_phi"])
        if binning not in BINNINGS:  # given edges: checked as when they were given
            return make_bins(theta, phi, fold_phi=fold)
        _check_edges("theta_o_bins", theta, 0.0, 180.0)
        _check_edges("phi_o_bins", phi, 0.0, 180.0 if fold else 360.0)
        return GonioBins(theta, phi, fold, binning, str(data.get("hemispheres", "both")))


def _theta_keys(edges: np.ndarray) -> np.ndarray:
    sin2 = np.sin(np.radians(edges)) ** 2
    keys = np.where(edges <= 90.0, sin2, 2.0 - sin2)
    keys[edges == 90.0] = 1.0
    keys[edges == 0.0] = 0.0
    keys[edges == 180.0] = 2.0
    return keys.astype(np.float32)


def parse_edges(name: str, value: Any) -> int | np.ndarray:
    """
    A bin specification as written: a whole number of bins (``18``, ``"18"``, ``18.0``) or
    edges in degrees (a sequence, or a string of numbers separated by commas or spaces, or
    a ``start:stop:step`` range with the stop included). Anything else — a fraction, NaN,
    an infinity, a number beyond the float range, a word, an empty list — is a
    ``ValueError`` naming ``name`` and the value as given.
    """

    shape = f"{name} must be a whole number of bins or edges in degrees (numbers, or start:stop:step)"
    if isinstance(value, (bool, np.bool_)):
        raise ValueError(f"{shape} (got {value!r})")
    if isinstance(value, str):
        tokens = value_tokens(name, value)
        if len(tokens) == 1 and ":" in tokens[0]:
            return _edge_range(name, tokens[0], value)
        numbers = [_edge_number(shape, token, value) for token in tokens]
        if len(numbers) == 1:
            return _whole(shape, numbers[0], value)
        if not numbers or ":" in value:
            raise ValueError(f"{shape} (got {value!r})")
        return np.array(numbers)
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        return _whole(shape, float(value), value)
    try:
        edges = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError, OverflowError):
        raise ValueError(f"{shape} (got {value!r})") from None
    if edges.ndim == 0:
        return _whole(shape, float(edges), value)
    return edges


def _edge_number(shape: str, token: str, value: Any) -> float:
    """One number of a written specification (``ValueError`` with the whole value as given)."""

    try:
        return float(token)
    except ValueError:
        raise ValueError(f"{shape} (got {value!r})") from None


def _whole(shape: str, number: float, value: Any) -> int:
    """A number of bins: finite and whole (the range is checked with the layout)."""

    if not (math.isfinite(number) and number.is_integer()):
        raise ValueError(f"{shape} (got {value!r})")
    return int(number)


def _edge_range(name: str, token: str, value: Any) -> np.ndarray:
    """The edges of ``start:stop:step`` (stop included), counted before they are built."""

    parts = token.split(":")
    try:
        start, stop, step = (float(p) for p in parts)
    except ValueError:
        raise ValueError(f"{name} must be start:stop:step in degrees (got {value!r})") from None
    if not all(math.isfinite(v) for v in (start, stop, step)):
        raise ValueError(f"{name} range must be finite numbers of degrees start:stop:step (got {value!r})")
    if not step > 0 or not stop > start:
        raise ValueError(f"{name} range must have stop > start and step > 0 (got {value!r})")
    span = (stop - start) / step  # finite or inf (a tiny step): compared before any list is built
    if not span <= _MAX_PER_AXIS + 0.5 or not np.isclose(start + round(span) * step, stop):
        raise ValueError(f"{name} range must reach its stop in at most {_MAX_PER_AXIS} steps (got {value!r})")
    return start + step * np.arange(round(span) + 1)


def _count(name: str, value: int, limit: int) -> int:
    if not 1 <= value <= limit:
        raise ValueError(f"{name} must be a whole number of bins with 1 <= {name} <= {limit} "
                         f"(got {shown_value(value)})")
    return value


def _check_edges(name: str, edges: np.ndarray, low: float, high: float) -> np.ndarray:
    if edges.ndim != 1 or len(edges) < 2 or len(edges) > _MAX_PER_AXIS + 1:
        raise ValueError(f"{name} edges must be 2 ... {_MAX_PER_AXIS + 1} numbers (got {edges.size})")
    if not np.all(np.isfinite(edges)):
        raise ValueError(f"{name} edges must be finite degrees in [{low:g}, {high:g}] (got {_shown(edges)})")
    if edges.min() < low or edges.max() > high:
        raise ValueError(f"{name} edges must be degrees in [{low:g}, {high:g}] (got "
                         f"{shown_value(float(edges.min()))} ... {shown_value(float(edges.max()))})")
    if np.any(np.diff(edges) <= 0):
        raise ValueError(f"{name} edges must be strictly increasing (got {_shown(edges)})")
    return edges


def make_bins(theta_o_bins: Any = 18, phi_o_bins: Any = 36, binning: str = "uniform", fold_phi: Any = False,
              hemispheres: str = "both") -> GonioBins:
    """
    The :class:`GonioBins` of a specification (see the module docstring).

    Parameters
    ----------
    theta_o_bins
        Whole number of θo bins *per hemisphere* (1 ... 65536), laid out by ``binning``
        over ``hemispheres``, or θo edges in degrees within [0, 180] (90 an edge if crossed).
    phi_o_bins
        Whole number of equal φo bins over [0, 360) (folded: [0, 180]), or φo edges in degrees.
    binning
        ``uniform`` or ``projected`` (:data:`BINNINGS`); ignored for given θo edges.
    fold_phi
        Fold φo to the relative azimuth |φo − φi| ∈ [0, 180] (isotropic specimens).
    hemispheres
        ``both``, ``reflection`` or ``transmission``: what a whole number of θo bins covers.
    """

    if binning not in BINNINGS and binning != "edges":
        raise ValueError(f"binning must be one of {', '.join(BINNINGS)} (got {binning!r})")
    if hemispheres not in HEMISPHERES:
        raise ValueError(f"hemispheres must be one of {', '.join(HEMISPHERES)} (got {hemispheres!r})")
    if isinstance(fold_phi, str) and fold_phi.lower() in ("true", "false"):
        fold_phi = fold_phi.lower() == "true"
    if not isinstance(fold_phi, (bool, int, np.bool_)) or fold_phi not in (0, 1):
        raise ValueError(f"fold_phi must be true or false (got {fold_phi!r})")
    fold_phi = bool(fold_phi)
    theta = parse_edges("theta_o_bins", theta_o_bins)
    phi = parse_edges("phi_o_bins", phi_o_bins)
    if isinstance(theta, int):
        n = _count("theta_o_bins", theta, _MAX_PER_AXIS // 2)
        parts = []
        low, high = HEMISPHERES[hemispheres]
        for start in (0.0, 90.0):
            if start < low or start >= high:
                continue
            if binning == "projected":
                upper = np.degrees(np.arcsin(np.sqrt(np.arange(n + 1) / n)))
            else:
                upper = np.linspace(0.0, 90.0, n + 1)
            part = upper if start == 0.0 else 180.0 - upper[::-1]
            parts.append(part if not parts else part[1:])
        theta = np.concatenate(parts)
        theta[0], theta[-1] = low, high
    else:
        theta = _check_edges("theta_o_bins", theta, 0.0, 180.0)
        if theta[0] < 90.0 < theta[-1] and 90.0 not in theta:
            raise ValueError("theta_o_bins edges that cross 90 degrees must have 90 as an edge (no bin may "
                             f"straddle the reflection and transmission hemispheres; got {_shown(theta)})")
        binning = "edges"
    top = 180.0 if fold_phi else 360.0
    if isinstance(phi, int):
        phi = np.linspace(0.0, top, _count("phi_o_bins", phi, _MAX_PER_AXIS) + 1)
    else:
        phi = _check_edges("phi_o_bins", phi, 0.0, top)
    if (len(theta) - 1) * (len(phi) - 1) > MAX_BINS:
        raise ValueError(f"theta_o_bins x phi_o_bins must be at most {MAX_BINS} bins (got "
                         f"{len(theta) - 1} x {len(phi) - 1} = {(len(theta) - 1) * (len(phi) - 1)})")
    if binning == "edges" and np.any(np.diff(_theta_keys(theta)) <= 0):  # the kernel searches their keys
        raise ValueError("theta_o_bins edges must differ in float32 sin^2 theta_o (edges too close together, or "
                         f"within ~0.02 degrees of 90; got {_shown(theta)})")
    if np.any(np.diff(phi.astype(np.float32)) <= 0):
        raise ValueError(f"phi_o_bins edges must differ in float32 (got {_shown(phi)})")
    return GonioBins(theta_edges=theta, phi_edges=phi, fold_phi=fold_phi, binning=binning,
                     hemispheres=hemispheres if binning in BINNINGS else "both")


def _shown(edges: np.ndarray) -> str:
    """Edges for a message: all of a short list, else the first and last few."""

    values = [f"{v:g}" for v in edges]
    return ", ".join(values) if len(values) <= 8 else ", ".join(values[:4] + ["..."] + values[-3:])
