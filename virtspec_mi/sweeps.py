"""
Sweeps over wavelength and incidence: :func:`sweep`, :class:`SweepResult`, :func:`fluctuation`
===============================================================================================

A sweep is a grid of certified readings over (wavelength × θi) at one φi — the
paper's Fig. 5 (θi from 0° to 90° in 1° steps) or a spectrum. All its readings go
through :func:`virtspec_mi.tally.take_readings` in batches of about
``settings.chunk_size`` rays, so a sweep costs a few kernel launches, not one per
reading; each reading keeps its own N independent rays and its own certificate
(|m/N − ρ| < μ with probability ≥ 1 − δ, eq. 23).

Random numbers. Reading k of the sweep (k = i_θ·n_λ + i_λ, θi-major) owns the global
ray indices [k·N, k·N + N): its counts depend only on (seed, k), never on which other
readings share a kernel launch. That is what makes a sweep resumable: a re-run that
traces only the unfinished readings reproduces the uninterrupted result exactly.

Wavelength-independent specimens (a BSDF with ``wavelength_independent = True``, e.g.
``simple_dielectric``) are traced once per θi (with the rays of the reading
i_λ = 0) and those counts are reported for every requested wavelength;
:attr:`SweepResult.wavelength_independent` is then ``True``.

Resumable runs. Given ``checkpoint=PATH``, finished readings are written to a JSON
file as the sweep goes (atomically, after each batch); a later call with the same
scene and settings picks them up and traces only the rest. The file records the
settings, the grids, the geometry and a fingerprint of the scene: a mismatch or a
corrupt file raises :class:`CheckpointError` (a ``ValueError``) rather than mixing
results.

References
----------
Baranoski, Rokne & Xu (2001), eq. (23) (rays per reading), eq. (24) (Δ), Figs. 5–6.
"""

from __future__ import annotations

import hashlib
import json
import os
import sys
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any, Sequence

import numpy as np

import virtspec_mi
from virtspec_mi.geometry import InstrumentGeometry
from virtspec_mi.settings import Settings, parse_theta_i
from virtspec_mi.reading import uncertified_lines, warn_if_uncertified
from virtspec_mi.tally import shares_wavelengths, take_readings

__all__ = [
    "QUANTITIES",
    "CheckpointError",
    "SweepResult",
    "sweep",
    "fluctuation",
    "scene_fingerprint",
    "ray_stride",
]

QUANTITIES: tuple[str, ...] = ("reflectance", "transmittance", "absorptance")
"""The quantities a sweep reports (ρ, τ, α)."""

_CHECKPOINT_FORMAT = "virtspec-mi sweep checkpoint 1"
_PROGRESS_AFTER_S = 2.0  # show a progress bar only when the sweep is expected to last longer


class CheckpointError(ValueError):
    """A sweep's checkpoint file is corrupt or belongs to another sweep."""


@dataclass(frozen=True)
class SweepResult:
    """
    Certified readings over a (wavelength × θi) grid.

    Attributes
    ----------
    wavelengths : ndarray, shape (n_λ,)
        Wavelengths in nm, in the order requested.
    theta_i : ndarray, shape (n_θ,)
        Polar incidence angles in degrees, in the order requested.
    reflected, transmitted, weight_violations, capped : ndarray of int64, shape (n_λ, n_θ)
        Exact counts per reading.
    rays : ndarray of int64, shape (n_λ, n_θ)
        Rays N per reading.
    seconds : float
        Wall time spent tracing (summed over interrupted and resumed runs).
    settings : Settings
        μ, δ, bound, beam, sampling, seed, φi and the wavelengths; its ``theta_i`` is the
        first angle of the sweep (the angles are :attr:`theta_i`).
    geometry : InstrumentGeometry
        r₁, r₂ and D of the scene.
    scene : str
        Fingerprint of the scene (see :func:`scene_fingerprint`).
    wavelength_independent : bool
        The specimen declared itself wavelength-independent: each θi was traced once and
        its counts are reported for every wavelength.
    version : str
        virtspec-mi version that made the sweep.
    """

    wavelengths: np.ndarray
    theta_i: np.ndarray
    reflected: np.ndarray
    transmitted: np.ndarray
    weight_violations: np.ndarray
    capped: np.ndarray
    rays: np.ndarray
    seconds: float
    settings: Settings
    geometry: InstrumentGeometry
    scene: str = ""
    wavelength_independent: bool = False
    version: str = field(default=virtspec_mi.__version__)

    @property
    def absorbed(self) -> np.ndarray:
        """Absorbed rays: rays − reflected − transmitted − capped."""

        return self.rays - self.reflected - self.transmitted - self.capped

    @property
    def reflectance(self) -> np.ndarray:
        """ρ = m/N per reading, shape (n_λ, n_θ) (eq. 2)."""

        return self.reflected / self.rays

    @property
    def transmittance(self) -> np.ndarray:
        """τ per reading, shape (n_λ, n_θ)."""

        return self.transmitted / self.rays

    @property
    def absorptance(self) -> np.ndarray:
        """α = absorbed / N per reading, shape (n_λ, n_θ)."""

        return self.absorbed / self.rays

    @property
    def certified_mu(self) -> np.ndarray:
        """
        Tolerance each reading's rays guarantee at δ, shape (n_λ, n_θ): the inverse of
        the sweep's bound (eq. 19 / eq. 14) at N = :attr:`rays`; ≤ μ when N came from
        the bound, larger when fewer rays were asked for (e.g. ``rays=1000``).
        """

        from virtspec_mi.bounds import chebyshev_mu, hoeffding_mu

        inverse = {"hoeffding": hoeffding_mu, "chebyshev": chebyshev_mu}.get(self.settings.bound)
        if inverse is None:  # a bound without a closed-form inverse: its target μ
            return np.full(self.rays.shape, self.settings.mu)
        return np.vectorize(lambda n: inverse(int(n), self.settings.delta), otypes=[float])(self.rays)

    @property
    def interval_delta(self) -> float:
        """δ of each interval: the sweep's δ, or δ/2 with ``joint`` (R and T together at δ)."""

        return self.settings.quantity_delta

    def interval(self, quantity: str = "reflectance") -> tuple[np.ndarray, np.ndarray]:
        """
        Clopper–Pearson interval ``(lower, upper)`` of ``quantity`` per reading at
        :attr:`interval_delta`, each of shape (n_λ, n_θ) (as ``Reading.reflectance_interval``).
        """

        from virtspec_mi.intervals import clopper_pearson

        self.quantity(quantity)  # validates the name
        counts = {"reflectance": self.reflected, "transmittance": self.transmitted, "absorptance": self.absorbed}
        return clopper_pearson(counts[quantity], self.rays, self.interval_delta)

    def quantity(self, name: str) -> np.ndarray:
        """``reflectance``, ``transmittance`` or ``absorptance`` by name."""

        if name not in QUANTITIES:
            raise ValueError(f"quantity must be one of {', '.join(QUANTITIES)} (got {name!r})")
        return getattr(self, name)

    def to_sd(self, quantity: str = "reflectance", theta_i: float | None = None) -> Any:
        """One quantity at one θi as a ``colour.SpectralDistribution`` (see :mod:`virtspec_mi.colorimetry`)."""

        from virtspec_mi.colorimetry import spectral_distribution

        return spectral_distribution(self, quantity, theta_i)

    def to_msds(self, theta_i: float | None = None) -> Any:
        """R, T and A at one θi as a ``colour.MultiSpectralDistributions``."""

        from virtspec_mi.colorimetry import multi_spectral_distributions

        return multi_spectral_distributions(self, theta_i)

    def to_dataset(self) -> Any:
        """An ``xarray.Dataset`` with dims (wavelength, theta_i) (see :mod:`virtspec_mi.results_io`)."""

        from virtspec_mi.results_io import to_dataset

        return to_dataset(self)

    def write(self, path: str | os.PathLike) -> Path:
        """Write to ``.nc`` (NetCDF), ``.csv`` or ``.json`` by suffix."""

        from virtspec_mi.results_io import write_sweep

        return write_sweep(self, path)

    def summary(self) -> str:
        """One paragraph: grid, rays, time, and notes."""

        s = self.settings
        rays = np.unique(self.rays)
        per = f"{int(rays[0]):,}" if len(rays) == 1 else f"{int(rays.min()):,}-{int(rays.max()):,}"
        lines = [
            f"{s.beam} sweep: {len(self.theta_i)} theta_i x {len(self.wavelengths)} wavelengths "
            f"(phi_i = {s.phi_i:g} deg, sampling = {s.sampling}, seed = {s.seed})",
            f"N = {per} rays per reading ({s.bound} bound: |rho - m/N| < {s.mu:g} with probability "
            f">= {1 - s.delta:g}); {self.seconds:.2f} s",
        ]
        if self.wavelength_independent and len(self.wavelengths) > 1:
            lines.append("note: wavelength-independent specimen: traced once per theta_i, "
                         "the same rays for every wavelength")
        lines += uncertified_lines(self.weight_violations, self.capped)
        return "\n".join(lines)


def sweep(
    scene: Any,
    *,
    theta_i: float | Sequence[float] | str,
    wavelengths: float | Sequence[float] | str | None = None,
    phi_i: float | None = None,
    mu: float | None = None,
    delta: float | None = None,
    rays: int | None = None,
    beam: str | None = None,
    sampling: str | None = None,
    seed: int | None = None,
    bound: str | None = None,
    joint: bool | None = None,
    pilot_rays: int | None = None,
    pilot_delta: float | None = None,
    chunk_size: int | None = None,
    checkpoint: str | os.PathLike | None = None,
    progress: bool | None = None,
) -> SweepResult:
    """
    Certified readings of ``scene`` over every (wavelength, θi) pair.

    Parameters
    ----------
    scene
        XML path, scene dict or loaded ``mi.Scene`` (as for :func:`virtspec_mi.measure`).
    theta_i
        Incidence angles in degrees: a number, a sequence or a string such as
        ``"0:90:1"`` (stop included), each in [0, 90], all distinct.
    wavelengths
        nm, same forms (e.g. ``"400:700:10"``), all distinct; default from the scene or 551.
    phi_i, mu, delta, rays, beam, sampling, seed, bound, joint, pilot_rays, pilot_delta, chunk_size
        As for :func:`virtspec_mi.measure` (one value for the whole sweep); with
        ``bound="two-stage"`` each reading is sized by its own pilot, all of them batched.
    checkpoint
        Path of a JSON file recording finished readings as the sweep goes; an existing
        file of the same sweep is resumed (see the module docstring). Removed when the
        sweep completes.
    progress
        ``True``: always a tqdm bar on stderr; ``False``: never; ``None`` (default):
        only when stderr is a terminal and the sweep is expected to last more than ~2 s.

    References
    ----------
    Baranoski et al. (2001), eq. (23), Fig. 5.
    """

    from virtspec_mi.instrument import find_instrument

    angles = np.array(parse_theta_i(theta_i))
    instrument = find_instrument(scene)
    base = instrument.integrator.settings if instrument.integrator is not None else Settings()
    settings = base.updated(
        theta_i=float(angles[0]), phi_i=phi_i, wavelengths=wavelengths, mu=mu, delta=delta, rays=rays,
        beam=beam, sampling=sampling, seed=seed, bound=bound, joint=joint, pilot_rays=pilot_rays,
        pilot_delta=pilot_delta, chunk_size=chunk_size,
    )
    lams = np.array(settings.wavelengths)
    for name, values in (("theta_i", angles), ("wavelengths", lams)):
        if len(np.unique(values)) != len(values):
            raise ValueError(f"{name} of a sweep must be distinct (got repeated values)")
    n_lam, n_theta = len(lams), len(angles)
    n = ray_stride(settings)
    shared = shares_wavelengths(instrument)
    fingerprint = scene_fingerprint(scene, instrument)
    identity = _identity(settings, angles, instrument.geometry, fingerprint, shared)

    # Flat reading index k = i_theta * n_lam + i_lam; work units are traced together.
    flat_theta = np.repeat(angles, n_lam)
    flat_lam = np.tile(lams, n_theta)
    if shared:
        units = [np.arange(i * n_lam, (i + 1) * n_lam) for i in range(n_theta)]
    else:
        units = [np.array([k]) for k in range(n_lam * n_theta)]
    per_batch = max(1, settings.chunk_size // n)
    batches = [np.concatenate(units[i:i + per_batch]) for i in range(0, len(units), per_batch)]

    state = _State.open(checkpoint, identity, n_lam * n_theta)
    todo = [b[~state.done[b]] for b in batches]
    todo = [b for b in todo if len(b)]
    bar = _Progress(progress, total=sum(len(b) for b in todo) // (n_lam if shared else 1))
    try:
        for batch in todo:
            start = time.perf_counter()
            tallies = take_readings(
                instrument,
                [(flat_lam[k], flat_theta[k], settings.phi_i) for k in batch],
                settings,
                offsets=batch.astype(np.int64) * n,
            )
            state.record(batch, tallies, time.perf_counter() - start)
            bar.update(len(batch) // (n_lam if shared else 1), time.perf_counter() - start)
    finally:
        bar.close()
    state.finish()
    warn_if_uncertified(state.counts[2], state.counts[3])

    def grid(values: np.ndarray) -> np.ndarray:
        return values.reshape(n_theta, n_lam).T.copy()

    return SweepResult(
        wavelengths=lams,
        theta_i=angles,
        reflected=grid(state.counts[0]),
        transmitted=grid(state.counts[1]),
        weight_violations=grid(state.counts[2]),
        capped=grid(state.counts[3]),
        rays=grid(state.counts[4]),
        seconds=state.seconds,
        settings=settings,
        geometry=instrument.geometry,
        scene=fingerprint,
        wavelength_independent=shared,
    )


def ray_stride(settings: Settings) -> int:
    """
    Global ray indices reserved per reading of a sweep: reading k owns [k·stride, k·stride + rays_k).
    It must be at least the most rays any reading may use (``take_readings`` refuses
    overlapping ranges): ``settings.rays_per_reading`` for a fixed budget; for
    ``two-stage``, the larger of the pilot n₁ and the Hoeffding N at the second stage's
    δ − δ₁ (per quantity), which no second batch exceeds (the exact rule over any interval
    of ρ needs at most the rays of eq. (23) at the same δ).
    """

    if not settings.adaptive:
        return settings.rays_per_reading
    from virtspec_mi.bounds import hoeffding_rays

    share = 2 if settings.joint else 1
    stage_two = hoeffding_rays(settings.mu, (settings.delta - settings.pilot_delta_value) / share)
    return max(settings.pilot_rays_per_reading, stage_two)


def fluctuation(a: SweepResult | np.ndarray, b: SweepResult | np.ndarray, quantity: str = "reflectance") -> float:
    """
    Average magnitude of the fluctuations between two sweeps, eq. (24):

        Δ = Σᵢ |ρᵢ^(N_j) − ρᵢ^(N_{j−1})| / n

    over the n readings of the sweeps (all their (wavelength, θi) pairs), for
    ``quantity`` (reflectance by default). ``a`` and ``b`` are sweeps over the same grid
    (typically at successive ray densities N_{j−1} and N_j), or arrays of one shape.

    References
    ----------
    Baranoski et al. (2001), eq. (24), Fig. 6a.
    """

    if isinstance(a, SweepResult) and isinstance(b, SweepResult):
        for name in ("wavelengths", "theta_i"):
            if not np.array_equal(getattr(a, name), getattr(b, name)):
                raise ValueError(f"fluctuation needs sweeps over the same {name} (they differ)")
        a, b = a.quantity(quantity), b.quantity(quantity)
    a, b = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    if a.shape != b.shape or a.size == 0:
        raise ValueError(f"fluctuation needs two non-empty arrays of one shape (got {a.shape} and {b.shape})")
    return float(np.mean(np.abs(a - b)))


def scene_fingerprint(scene: Any, instrument: Any) -> str:
    """
    A short fingerprint of a scene for result files and checkpoints: SHA-256 over the
    XML file's bytes (or the dict's ``repr``), the specimen BSDF's description, the
    specimen frame and the geometry.
    """

    digest = hashlib.sha256()
    if isinstance(scene, (str, os.PathLike)):
        digest.update(Path(scene).read_bytes())
    elif isinstance(scene, dict):
        digest.update(repr(sorted(scene.items(), key=lambda item: str(item[0]))).encode())
    digest.update(str(instrument.bsdf).encode())
    digest.update(np.asarray(instrument.to_world, dtype=np.float64).round(9).tobytes())
    digest.update(repr(asdict(instrument.geometry)).encode())
    return f"sha256:{digest.hexdigest()[:16]}"


# -- internals -------------------------------------------------------------------------


def _identity(settings: Settings, angles: np.ndarray, geometry: InstrumentGeometry, fingerprint: str,
              shared: bool) -> dict[str, Any]:
    """Everything that decides a sweep's counts (chunk size and version do not)."""

    common = {k: v for k, v in settings.as_dict().items() if k != "theta_i"}
    return {
        **common,
        "theta_i": [float(t) for t in angles],
        "geometry": asdict(geometry),
        "scene": fingerprint,
        "wavelength_independent": shared,
    }


class _State:
    """Finished readings of a sweep, optionally mirrored in a checkpoint file."""

    def __init__(self, path: Path | None, identity: dict[str, Any], size: int) -> None:
        self.path, self.identity = path, identity
        self.done = np.zeros(size, dtype=bool)
        self.counts = np.zeros((5, size), dtype=np.int64)  # reflected, transmitted, violations, capped, rays
        self.seconds = 0.0

    @classmethod
    def open(cls, path: str | os.PathLike | None, identity: dict[str, Any], size: int) -> "_State":
        state = cls(Path(path) if path is not None else None, identity, size)
        if state.path is not None and state.path.exists():
            state._load()
        return state

    def _load(self) -> None:
        path = self.path
        try:
            data = json.loads(path.read_text())
            if not isinstance(data, dict) or data.get("format") != _CHECKPOINT_FORMAT:
                raise CheckpointError(f"checkpoint {path} is not a virtspec-mi sweep checkpoint")
            done = np.array(data["done"], dtype=np.int64)
            counts = np.array(data["counts"], dtype=np.int64)
            seconds = float(data["seconds"])
            stored = data["identity"]
        except CheckpointError:
            raise
        except (OSError, ValueError, KeyError, TypeError) as error:
            raise CheckpointError(
                f"checkpoint {path} is corrupt ({type(error).__name__}: {error}); delete it to start the sweep over"
            ) from None
        if stored != json.loads(json.dumps(self.identity)):
            keys = sorted(k for k in set(stored) | set(self.identity)
                          if stored.get(k) != json.loads(json.dumps(self.identity.get(k))))
            raise CheckpointError(
                f"checkpoint {path} belongs to a different sweep (differs in: {', '.join(keys)}); "
                "re-run with the same scene and settings, or delete it to start over"
            )
        size = self.done.size
        if counts.shape != (5, len(done)) or (len(done) and (done.min() < 0 or done.max() >= size)):
            raise CheckpointError(f"checkpoint {path} is corrupt (counts do not match the sweep); delete it")
        self.done[done] = True
        self.counts[:, done] = counts
        self.seconds = seconds

    def record(self, batch: np.ndarray, tallies: Any, seconds: float) -> None:
        self.counts[:, batch] = np.stack([
            tallies.reflected, tallies.transmitted, tallies.weight_violations, tallies.capped, tallies.rays,
        ])
        self.done[batch] = True
        self.seconds += seconds
        if self.path is not None:
            self._save()

    def _save(self) -> None:
        done = np.flatnonzero(self.done)
        data = {
            "format": _CHECKPOINT_FORMAT,
            "version": virtspec_mi.__version__,
            "identity": self.identity,
            "seconds": self.seconds,
            "done": done.tolist(),
            "counts": self.counts[:, done].tolist(),
        }
        temporary = self.path.with_name(self.path.name + ".tmp")
        temporary.write_text(json.dumps(data))
        os.replace(temporary, self.path)  # atomic: an interruption leaves the old or the new file

    def finish(self) -> None:
        if self.path is not None and self.path.exists():
            self.path.unlink()


class _Progress:
    """A tqdm bar on stderr, shown per the ``progress`` rule of :func:`sweep`."""

    def __init__(self, progress: bool | None, total: int) -> None:
        self.mode, self.total, self.bar, self.done = progress, total, None, 0
        self.elapsed = 0.0
        if progress:
            self._open()

    def _open(self) -> None:
        from tqdm import tqdm

        self.bar = tqdm(total=self.total, initial=self.done, unit="reading", file=sys.stderr, leave=False,
                        desc="sweep")

    def update(self, count: int, seconds: float) -> None:
        self.done += count
        self.elapsed += seconds
        if self.bar is None and self.mode is None and self.done < self.total and sys.stderr.isatty():
            expected = self.elapsed / self.done * self.total
            if expected > _PROGRESS_AFTER_S:
                self._open()
                return
        if self.bar is not None:
            self.bar.update(count)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()

