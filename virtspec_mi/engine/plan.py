"""
The plan of a run: every reading an instrument traces, and how
==============================================================

A :class:`Plan` is everything :func:`virtspec_mi.engine.readings.run` needs besides the
bench: the common :class:`~virtspec_mi.settings.Settings`, the θi grid, the specimen
parameter points (a :class:`~virtspec_mi.engine.parameters.ParameterSpace`, or none), the
reading *groups* (the sphere's ``("sample", "standard")``; one unnamed group by default),
one kernel exit hook per group (:mod:`virtspec_mi.kernel.hooks`, or none) and the
:class:`Columns` a two-stage pilot sizes N₂ from. It holds plain values only, so it
pickles (a Dask worker receives it).

Readings are numbered flat, the wavelength fastest:

    k = ((g·n_p + i_p)·n_θ + i_θ)·n_λ + i_λ

(g the group, i_p the parameter point, i_θ the angle, i_λ the wavelength; without
groups and parameters k = i_θ·n_λ + i_λ, as every sweep has always numbered them). The
**ray key** of reading k is k mod (n_p·n_θ·n_λ) — groups share their rays (the sphere's
two configurations see the same rays) — and reading k traces the global ray indices
[key·stride, key·stride + N_k), stride = :attr:`Plan.stride`, the most rays one reading
may trace. Its counts thus depend on (seed, key) only.

References
----------
Baranoski et al. (2001), eq. (23) (rays per reading).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field, is_dataclass
from typing import Any

import numpy as np

from virtspec_mi.budgets import rules, twostage
from virtspec_mi.base.checks import check_rays_needed, shown_value
from virtspec_mi.engine.parameters import ParameterSpace
from virtspec_mi.kernel.counts import Counts
from virtspec_mi.kernel.hooks import ExitHook
from virtspec_mi.settings import Settings

__all__ = ["Columns", "Plan", "kernel_options"]


def kernel_options(settings: Settings) -> dict[str, Any]:
    """The settings the kernel takes as plain values: ``seed``, ``chunk_size``, ``beam``, ``sampling``."""

    return {"seed": settings.seed, "chunk_size": settings.chunk_size, "beam": settings.beam,
            "sampling": settings.sampling}


@dataclass(frozen=True)
class Columns:
    """
    What a two-stage pilot certifies of each reading: the **columns**, each a count out of
    the reading's rays whose fraction is held within μ, from which N₂ is sized
    (:func:`virtspec_mi.budgets.twostage.stage_two_rays`). The rule table says what the
    columns are and how δ is shared among them (``budget``, a
    :class:`virtspec_mi.budgets.rules.Columns`: :func:`~virtspec_mi.budgets.rules.quantity_columns`,
    :meth:`~virtspec_mi.budgets.rules.Guarantee.stage_two`,
    :data:`~virtspec_mi.budgets.rules.DETECTOR_COLUMNS`); the instrument says where each
    column is in a reading's tallies.

    Parameters
    ----------
    budget : virtspec_mi.budgets.rules.Columns
        The columns in words and ``share``: δ is split over that many statements made
        together (1: each column at δ on its own).
    counts : tuple of str
        Fate counts by name (:class:`~virtspec_mi.kernel.counts.Counts`, ``absorbed``
        included): the hemispherical reading's R, T (and A).
    bins : str, tuple or None
        ``"each"``: every bin of the hook a column (the goniophotometer's bin fractions);
        a tuple of tuples of bin codes: each a column, the sum of those bins (the sphere's
        detector fraction); ``None``: no bins.
    """

    budget: rules.Columns
    counts: tuple[str, ...] = ()
    bins: str | tuple[tuple[int, ...], ...] | None = None

    @classmethod
    def fates(cls, joint: bool) -> "Columns":
        """The hemispherical reading's: R, T and A at δ each, or R and T together at δ (``joint``)."""

        return cls(rules.quantity_columns(joint), counts=("reflected", "transmitted") + (() if joint else ("absorbed",)))

    def of(self, counts: Counts, bins: np.ndarray | None) -> np.ndarray:
        """The columns of every reading, shape (readings, columns), from its counts and bins."""

        parts = [getattr(counts, name)[:, None] for name in self.counts]
        if self.bins == "each":
            parts.append(bins)
        elif self.bins is not None:
            parts += [bins[:, list(codes)].sum(axis=1)[:, None] for codes in self.bins]
        return np.concatenate([np.asarray(p, dtype=np.int64) for p in parts], axis=1)

    def stage_two_rays(self, pilot: np.ndarray, settings: Settings) -> np.ndarray:
        """
        N₂ of every reading from its pilot's columns (``pilot``, shape (readings, columns)):
        each column at δ (share 1), all of them together at δ/share each (share = the
        number of columns: the joint sizing), else each at δ/share.
        """

        share, width = self.budget.share, pilot.shape[1]
        delta, pilot_delta = settings.delta, settings.pilot_delta_value
        if share not in (1, width):
            delta, pilot_delta = delta / share, pilot_delta / share
        return twostage.stage_two_rays(pilot, settings.pilot_rays_per_reading, settings.mu, delta, pilot_delta,
                                       joint=share == width and share > 1)

    def most_second_rays(self, settings: Settings) -> int:
        """The most rays a second batch can take (:func:`virtspec_mi.budgets.twostage.most_second_rays`)."""

        return twostage.most_second_rays(settings.mu, settings.delta, settings.pilot_delta_value, self.budget.share)


@dataclass(frozen=True, eq=False)
class Plan:
    """
    Everything a run traces (see the module docstring).

    Parameters
    ----------
    settings : Settings
        The common settings; a fixed budget's N per reading is ``settings.rays`` or the
        rule's (an instrument that sizes N itself puts it in ``settings.rays``).
    theta_i : sequence of float
        The incidence angles, degrees.
    parameters : ParameterSpace or None
        The specimen parameter points.
    groups : tuple of str
        Names of the reading groups (they share rays); one unnamed group by default.
    hooks : tuple or None
        One kernel exit hook (or ``None``) per group, all of one size K and one set of sums.
    columns : Columns or None
        What two-stage certifies; ``None``: a two-stage rule is refused (``refusal`` says why).
    scene : str
        The scene's fingerprint (a checkpoint's identity).
    instrument : str
        The instrument's name (messages, a checkpoint's identity).
    options : dict
        The instrument's options that decide the counts, as plain data (a checkpoint's identity).
    refusal : str
        Why a two-stage rule cannot size this instrument's readings (with ``columns=None``).
    """

    settings: Settings
    theta_i: tuple[float, ...]
    parameters: ParameterSpace | None = None
    groups: tuple[str, ...] = ("",)
    hooks: tuple[ExitHook | None, ...] | None = None
    columns: Columns | None = None
    scene: str = ""
    instrument: str = ""
    options: dict[str, Any] = field(default_factory=dict)
    refusal: str = ""

    def __post_init__(self) -> None:
        object.__setattr__(self, "theta_i", tuple(float(t) for t in np.atleast_1d(self.theta_i)))
        object.__setattr__(self, "groups", tuple(self.groups))
        if self.hooks is not None:  # the one check of a plan's shape (an instrument's contract, not user input)
            object.__setattr__(self, "hooks", tuple(self.hooks))
            if (len(self.hooks) != len(self.groups) or any(h is None for h in self.hooks)
                    or len({(h.size, tuple(h.sums)) for h in self.hooks}) != 1):
                raise ValueError(f"a plan's hooks must be one per group ({len(self.groups)}), all of one size K and "
                                 "one set of sums")

    # -- the flat reading index -------------------------------------------------------

    @property
    def wavelengths(self) -> np.ndarray:
        return np.asarray(self.settings.wavelengths, dtype=np.float64)

    @property
    def shape(self) -> tuple[int, int, int, int]:
        """(groups, parameter points, θi, wavelengths)."""

        points = 1 if self.parameters is None else self.parameters.size
        return len(self.groups), points, len(self.theta_i), len(self.settings.wavelengths)

    @property
    def size(self) -> int:
        """The number of readings."""

        return int(np.prod(self.shape))

    @property
    def keys(self) -> int:
        """The number of ray keys (readings of one group)."""

        return self.size // len(self.groups)

    def split(self, readings: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(group, parameter point, θi index, wavelength index) of flat readings ``readings``."""

        return np.unravel_index(np.asarray(readings, dtype=np.int64), self.shape)

    def hook(self, group: int) -> ExitHook | None:
        """The exit hook of group ``group`` (``None``: fates only)."""

        return None if self.hooks is None else self.hooks[group]

    @property
    def bins(self) -> int | None:
        """K, the bins of every reading, or ``None`` without hooks."""

        hook = self.hook(0)
        return None if hook is None else hook.size

    @property
    def sums(self) -> tuple[str, ...]:
        """The per-reading sums every reading has."""

        hook = self.hook(0)
        return () if hook is None else tuple(hook.sums)

    @property
    def spectral(self) -> bool:
        """True when a hook depends on the wavelength (the readings never share rays across wavelengths)."""

        return any(h is not None and h.spectral for h in (self.hooks or ()))

    # -- rays ---------------------------------------------------------------------------

    @property
    def adaptive(self) -> bool:
        """True when each reading is sized by its own pilot (refused without :attr:`columns`)."""

        if not self.settings.adaptive:
            return False
        if self.columns is None:
            reason = self.refusal or f"the {self.instrument or 'planned'} instrument does not say what it would certify"
            raise ValueError(f"bound={self.settings.bound!r} cannot size these readings: {reason}; use a fixed "
                             "budget (hoeffding, chebyshev, exact) or give rays")
        return True

    @property
    def stride(self) -> int:
        """The most rays one reading may trace in one batch: its key range (≤ 2³² − 1)."""

        settings = self.settings
        if not self.adaptive:
            return settings.rays_per_reading
        if self.columns == Columns.fates(settings.joint):  # the hemispherical reading's: the settings' own
            return settings.most_rays_per_reading
        most = self.columns.most_second_rays(settings)
        rule = (f"the {settings.bound} bound for mu = {shown_value(settings.mu)}, delta = "
                f"{shown_value(settings.delta)} over {self.columns.budget.what}")
        return max(settings.pilot_rays_per_reading, check_rays_needed(most, rule))

    @property
    def most_rays_spent(self) -> int:
        """The most rays one reading traces in all, a two-stage pilot included."""

        return self.settings.pilot_rays_per_reading + self.stride if self.adaptive else self.stride

    def identity(self, bench: Any, shared: bool) -> dict[str, Any]:
        """Everything that decides a keyed run's counts (chunk size and version do not): a checkpoint's identity."""

        common = {k: v for k, v in self.settings.as_dict().items() if k != "theta_i"}
        identity = {
            **common,
            "theta_i": list(self.theta_i),
            "geometry": asdict(bench.geometry),
            "scene": self.scene,
            "wavelength_independent": shared,
        }
        if self.parameters is not None:
            identity["parameters"] = self.parameters.as_dict()
        if self.options or self.hooks is not None or self.groups != ("",):  # beyond the fates of one group
            identity.update(instrument=self.instrument, groups=list(self.groups), options=_plain(self.options),
                            hooks=[_plain(h) for h in self.hooks or ()], columns=_plain(self.columns))
        return identity


def _plain(value: Any) -> Any:
    """``value`` as JSON data: dataclasses as dicts, arrays and tuples as lists, NumPy scalars as numbers."""

    if is_dataclass(value) and not isinstance(value, type):
        return {"kind": type(value).__name__, **{k: _plain(v) for k, v in vars(value).items()}}
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, np.ndarray):
        return _plain(value.tolist())
    if isinstance(value, np.generic):
        return value.item()
    return value
