"""
Certified directional-albedo tables of microfacet BSDFs
=======================================================

Renderers compensate the energy that single-scattering microfacet BSDFs lose
(Kulla & Conty 2017) with precomputed tables of the directional albedo

    E(μ, α) = ∫ f(ω_i, ω_o) cos θ_o dω_o,   μ = cos θ_i,

and of its cosine-weighted average E_avg(α) = 2 ∫₀¹ E(μ) μ dμ. The instrument's
directional-hemispherical reading of a specimen lit by a collimated beam at
θ_i = arccos μ *is* E(μ): each ray leaves the specimen (reflected or transmitted) or is
lost, with probability exactly E(μ) of leaving, and its fate is an exact count. A
reading under the cosine-weighted diffuse beam (``beam="diffuse"``) *is* E_avg: its
incidence cosines are drawn with density 2μ, so one Bernoulli trial per ray has mean
2 ∫ E(μ) μ dμ — no quadrature, no quadrature error; that is why E_avg is measured that
way here rather than integrated from the certified cells (a quadrature of the cells
would add an error term that cannot be bounded without a smoothness assumption on E
near grazing incidence, where E changes fastest).

:func:`albedo_table` measures, on the user's grid or on an engine's
(:mod:`virtspec_mi.exchange.conventions`):

- ``model="conductor"``: the project's ``microfacet`` plugin
  (:mod:`virtspec_mi.plugins.bsdfs.microfacet`), ``distribution`` ``ggx`` or
  ``beckmann``, ``shadowing`` ``separable`` / ``height_correlated`` / ``unreal``, Beckmann
  ``g1`` ``exact`` or ``walter``, ``fresnel`` ``one`` (E) or a split-sum half
  (:mod:`virtspec_mi.exchange.engine_models`: each engine's own model is the default on
  its grid): E = reflected. Its sampler and its evaluation use the same G, so the count
  *is* ∫ f cos (Mitsuba's ``roughconductor`` with Beckmann counts
  G₁,exact(ω_i)/G₁,fit(ω_i) × ∫ f cos instead, which is why it is not used);
- ``model="glass"``: Mitsuba's ``roughdielectric``: E = reflected + transmitted (the
  energy *not lost* by single scattering — for a smooth dielectric nothing is lost, but
  the masking term of a rough one loses energy), for light from outside (relative index
  η) and from inside (1/η, the swept ``eta`` of the BSDF; Cycles' ``_inv_`` tables), with
  E_R and E_T alongside (certified too with ``parts=True``).

**The certificate.** Every cell of the table (and every E_avg value) is within ε of the
model's true value *at once* with probability ≥ 1 − δ: the union bound over the C cells
and the |Q| certified quantities of each. ``bound="hoeffding"`` gives every cell
N = ⌈ln(2C|Q|/δ)/(2ε²)⌉ rays (δ split evenly); ``bound="two-stage"`` (default) spends a
pilot per cell (δ/10 split evenly over the pilots) and sizes a fresh second batch by the
binomial tail bounds of Zubkov & Serov (2013) over the pilot's interval, the other 9δ/10
shared among the cells in proportion to the variance their pilot allows
(:mod:`virtspec_mi.budgets.binomial`); cells near 0 or 1 (low roughness: E ≈ 1) then need
a small fraction of Hoeffding's rays. A BSDF weight rounded into [0, 1] adds its largest bias to the cell's
tolerance (``certified_epsilon``: Mitsuba's Beckmann G₁ overshoots 1 by 6·10⁻⁵);
weight violations or invalid directions leave a cell uncertified (NaN).

**Between the cells.** Linear interpolation between certified cells carries an error
that the rays do not bound: it depends on E″, which no finite set of readings
certifies without a smoothness assumption. :meth:`AlbedoTable.interpolation_estimate`
states h²|E″|/8 with |E″| estimated from the certified second divided differences
(|Δ²Ê| + 4ε bounds |Δ²E| for certain, the step from Δ² to E″ is the assumption);
:meth:`AlbedoTable.interpolate` with :meth:`AlbedoTable.compare` checks an interpolated
table against a certified table of the midpoints, which *is* a certified statement at
those points.

Runs: the cells are traced by :func:`virtspec_mi.sweep` calls (parameter sweeps over
α — and η — at each θ_i), grouped by the number of rays they need. With
``checkpoint=DIR`` (or ``out=FILE``: ``FILE.parts``) every finished group is written
there and a re-run traces only the missing ones (the same counts as an uninterrupted
run: every group's seed is derived from ``seed`` and the group's identity).

References
----------
Kulla, C., Conty, A. (2017). Revisiting physically based shading at Imageworks. SIGGRAPH
course *Physically Based Shading in Theory and Practice*: E(μ), E_avg, energy compensation.
Walter, B. et al. (2007). Microfacet models for refraction through rough surfaces. EGSR.
Hoeffding, W. (1963). JASA 58, 13–30: Theorem 1, eq. (2.3).
Zubkov, A.M., Serov, A.A. (2013). Theory of Probability and its Applications 57(3),
539–544: Theorem 1.
Baranoski, G.V.G., Rokne, J.G., Xu, G. (2001). The Visual Computer 17, 506–518: eqs. (2), (23).
"""

from __future__ import annotations

import os
import time
import warnings
from contextlib import nullcontext
from dataclasses import dataclass
from datetime import datetime, timezone
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from virtspec_mi.base.version import __version__
from virtspec_mi.base.checks import check_delta, real, shown_value
from virtspec_mi.base.files import WriteError, check_distinct
from virtspec_mi.base.surface import spoken
import virtspec_mi.base.interrupts as interrupts
from virtspec_mi.engine.checkpoint import ResultStore, locked
from virtspec_mi.settings import true_or_false, whole_number
from virtspec_mi.exchange.common import derived_seed
from virtspec_mi.exchange.conventions import Convention, convention
from virtspec_mi.budgets.binomial import (binomial_rays, pilot_intervals, stage_two_classes, stage_two_shares,
                                         table_pilot_rays, union_hoeffding_rays)
from virtspec_mi.applications.tables.table import BOUNDS, DISTRIBUTIONS, MODELS, AlbedoTable, _FORMAT, _check_output

__all__ = ["albedo_table"]


def _resumes(directory: Path | None, kept: str) -> str:
    """Where a table whose file could not be written is kept, and how it resumes (a :class:`WriteError`'s ``kept``)."""

    if directory is None:
        return "the table is not kept (no checkpoint): give checkpoint= (--checkpoint) to keep its groups"
    return (f"{kept} are kept in {directory}: free some space and run the same command again, it resumes from "
            "them")


def _check_epsilon(epsilon: Any) -> float:
    """ε of a table: a real number, 0 < ε < 0.5 (as μ: :func:`virtspec_mi.base.checks.check_mu`, named ``epsilon``)."""

    value = real("epsilon", epsilon)
    if not 0.0 < value < 0.5:
        raise ValueError(f"epsilon must satisfy 0 < epsilon < 0.5 (got {shown_value(epsilon)})")
    return value


def _whole(name: str, value: Any, low: int, high: int) -> int:
    """A whole number given as a number (a string or a boolean refused), ``low`` <= value <= ``high``."""

    if isinstance(value, str):
        raise ValueError(f"{name} must be a whole number, not a string (got {value!r})")
    return whole_number(name, low, high, f"{low} <= {name} <= {high}")(value)


@dataclass(frozen=True)
class _Grid:
    model: str
    distribution: str
    mu: np.ndarray
    alpha: np.ndarray
    eta: np.ndarray | None
    roughness: np.ndarray | None
    engine: str
    order: tuple[str, ...]

    @property
    def points(self) -> np.ndarray:
        """Parameter points (α[, relative η]) of the canonical cells, shape (P, 1 or 2)."""

        if self.model == "conductor":
            return self.alpha[:, None]
        sides = np.concatenate([self.eta, 1.0 / self.eta])  # (side, eta) flattened
        a, e = np.meshgrid(self.alpha, sides, indexing="ij")  # (alpha, side·eta)
        return np.stack([a.ravel(), e.ravel()], axis=-1)

    def canonical(self, values: np.ndarray) -> np.ndarray:
        """(μ, P) cell values → canonical dims of E."""

        if self.model == "conductor":
            return values
        n_a, n_e = len(self.alpha), len(self.eta)
        v = values.reshape(len(self.mu), n_a, 2, n_e)
        return np.transpose(v, (2, 3, 0, 1))

    def canonical_average(self, values: np.ndarray) -> np.ndarray:
        """(P,) E_avg values → canonical dims of E_avg."""

        if self.model == "conductor":
            return values
        v = values.reshape(len(self.alpha), 2, len(self.eta))
        return np.transpose(v, (1, 2, 0))


def _check_nodes(name: str, values: Any, low: float, high: float, open_low: bool = False) -> np.ndarray:
    if any(isinstance(value, (bool, np.bool_, str)) for value in np.ravel(np.asarray(values, dtype=object))):
        raise ValueError(f"{name} must be a sequence of numbers (got {values!r})")
    try:
        array = np.atleast_1d(np.asarray(values, dtype=np.float64))
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a sequence of numbers (got {values!r})") from None
    if array.ndim != 1 or array.size == 0:
        raise ValueError(f"{name} must be a non-empty one-dimensional sequence of numbers")
    bad = ~np.isfinite(array) | (array > high) | ((array <= low) if open_low else (array < low))
    if np.any(bad):
        rule = f"{low:g} < {name} <= {high:g}" if open_low else f"{low:g} <= {name} <= {high:g}"
        raise ValueError(f"{name} must satisfy {rule} (got {array[bad][0]!r})")
    if len(np.unique(array)) != len(array):
        raise ValueError(f"{name} nodes must be distinct (got repeated values)")
    return array


def _grid(model: str, distribution: str, engine: str | None, mu: Any, alpha: Any, roughness: Any,
          eta: Any) -> _Grid:
    if model not in MODELS:
        raise ValueError(f"model must be one of {', '.join(MODELS)} (got {model!r})")
    if distribution not in DISTRIBUTIONS:
        raise ValueError(f"distribution must be one of {', '.join(DISTRIBUTIONS)} (got {distribution!r})")
    if alpha is not None and roughness is not None:
        raise ValueError("give alpha or roughness (alpha = roughness^2), not both")
    given = mu is not None or alpha is not None or roughness is not None or eta is not None
    if engine is not None and given:
        raise ValueError(spoken(f"engine={engine!r} fixes the grid: give engine=None with mu, alpha (or roughness)"
                                + (" and eta" if model == "glass" else ""),
                                f"--engine {engine} fixes the grid: give --engine none with --cosines, --alpha (or "
                                "--roughness)" + (" and --eta" if model == "glass" else "")))
    if engine is not None:
        conv: Convention = convention(engine, model)
        return _Grid(model, distribution, conv.mu, conv.alpha, conv.eta, conv.roughness, conv.name, conv.order)
    if mu is None or (alpha is None and roughness is None) or (model == "glass" and eta is None):
        raise ValueError("give engine (cycles, filament, unreal) or the grid: mu and alpha (or roughness)"
                         + (" and eta" if model == "glass" else ""))
    mu = _check_nodes("mu", mu, 0.0, 1.0)
    rough = None
    if roughness is not None:
        rough = _check_nodes("roughness", roughness, 0.0, 10.0, open_low=True)
        alpha = rough * rough
    alpha = _check_nodes("alpha", alpha, 0.0, 10.0, open_low=True)
    etas = None
    if model == "glass":
        etas = _check_nodes("eta", eta, 0.0, 1e6, open_low=True)
        if np.any(etas < 1.0):
            raise ValueError("eta must satisfy eta >= 1 (the outside index; the inside side uses 1/eta)")
    elif eta is not None:
        raise ValueError("eta is a glass parameter (model='glass')")
    order = ("eta", "mu", "alpha") if model == "glass" else ("mu", "alpha")
    return _Grid(model, distribution, mu, alpha, etas, rough, "grid", order)


def _scene(grid: _Grid, model: dict[str, str]) -> dict[str, Any]:
    from virtspec_mi.runtime.scene import instrument_scene

    if grid.model == "conductor":
        bsdf = {"type": "microfacet", "distribution": grid.distribution, "alpha": 0.5, **model}
    else:
        bsdf = {"type": "roughdielectric", "distribution": grid.distribution, "alpha": 0.5, "int_ior": 1.5,
                "ext_ior": 1.0}
    return instrument_scene(bsdf)



_KEYS = ("reflected", "transmitted", "rounded_weights", "weight_violations", "invalid_directions", "capped")


def albedo_table(
    model: str = "conductor",
    *,
    distribution: str = "ggx",
    engine: str | None = "cycles",
    shadowing: str | None = None,
    g1: str = "exact",
    fresnel: str = "one",
    mu: Sequence[float] | None = None,
    alpha: Sequence[float] | None = None,
    roughness: Sequence[float] | None = None,
    eta: Sequence[float] | None = None,
    epsilon: float = 1e-3,
    delta: float = 0.01,
    bound: str = "two-stage",
    average: bool = True,
    parts: bool = False,
    pilot_rays: int | None = None,
    seed: int = 0,
    wavelength: float = 551.0,
    checkpoint: str | os.PathLike | None = None,
    out: str | os.PathLike | Sequence[str | os.PathLike] | None = None,
    progress: bool | None = None,
    chunk_size: int | None = None,
    overwrite: bool = False,
) -> AlbedoTable:
    """
    Measure a certified albedo table (see the module docstring).

    Parameters
    ----------
    model
        ``conductor`` (``roughconductor``, Fresnel = 1) or ``glass`` (``roughdielectric``).
    distribution
        ``ggx`` or ``beckmann``.
    shadowing, g1, fresnel
        Conductor: the ``microfacet`` plugin's G₂ (``separable``, ``height_correlated``,
        ``unreal``; default: the engine's own, :data:`~virtspec_mi.exchange.engine_models.ENGINE_SHADOWING`,
        ``separable`` on a user grid), Beckmann's G₁ (``exact`` or ``walter``) and F
        (``one``, ``fc``, ``one_minus_fc``). Glass (Mitsuba's ``roughdielectric``) takes
        none of them and only ``ggx``.
    engine
        ``cycles`` (default), ``filament`` or ``unreal``: that engine's grid and memory
        order (:mod:`virtspec_mi.exchange.conventions`); ``None`` with ``mu`` and ``alpha``
        (or ``roughness``, α = roughness²), and ``eta`` (≥ 1) for glass.
    mu, alpha, roughness, eta
        A user grid (0 ≤ μ ≤ 1; α > 0; η ≥ 1, the inside side uses 1/η).
    epsilon, delta
        Every value within ε, the whole table at once with probability ≥ 1 − δ
        (0 < ε < 0.5, 0 < δ < 1).
    bound
        ``two-stage`` or ``hoeffding`` (:data:`BOUNDS`).
    average
        Also measure E_avg (diffuse beam) per α (and η, side).
    parts
        Glass, or a conductor with ``fresnel="split"``: certify E_R and E_T too (three
        quantities per cell, on the same rays; split: E_R = ∫ F_c f cos, E_T = ∫ (1 − F_c) f cos).
    pilot_rays
        Two-stage pilot per cell (default ⌈10/ε⌉).
    seed
        Seed of the run (each group's seed is derived from it).
    wavelength
        The wavelength traced (nm); the models are grey, the value only labels the rays.
    checkpoint
        Directory keeping the finished groups (resume); default with ``out``:
        ``OUT.parts`` (removed once the outputs are written).
    out
        File(s) to write when done: ``.nc``, ``.npy``, ``.h`` (:meth:`AlbedoTable.write`).
    progress
        tqdm bar on stderr: ``True`` always, ``False`` never, ``None`` when stderr is a
        terminal and the run is expected to last more than ~2 s.
    chunk_size
        Rays per kernel launch (memory only; the counts do not depend on it).
    overwrite
        Let a ``.npy`` output's companions (``NAME.json``, ``NAME_avg.npy``) replace files of those names that
        this table's format did not write (refused otherwise, before anything is traced).

    Returns
    -------
    AlbedoTable

    References
    ----------
    Kulla & Conty (2017); Hoeffding (1963), Theorem 1; Baranoski et al. (2001), eq. (23).
    """

    from virtspec_mi.runtime.reading import read_result, take
    from virtspec_mi.engine.progress import Progress
    from virtspec_mi.runtime import mitsuba
    from virtspec_mi.runtime.scene import loaded

    from virtspec_mi.exchange.engine_models import bsdf_model

    grid = _grid(model, distribution, engine, mu, alpha, roughness, eta)
    bsdf_parameters, model_words, count_scale = bsdf_model(model, distribution, grid.engine, shadowing, g1, fresnel)
    epsilon, delta = _check_epsilon(epsilon), check_delta(real("delta", delta))  # any real number type, not text
    average, parts = true_or_false("average")(average), true_or_false("parts")(parts)
    seed = _whole("seed", seed, 0, 2**32 - 1)
    wavelength = real("wavelength", wavelength)
    if not 0.0 < wavelength < float("inf"):
        raise ValueError(f"wavelength must be a finite number of nm > 0 (got {shown_value(wavelength)})")
    if bound not in BOUNDS:
        raise ValueError(f"bound must be one of {', '.join(BOUNDS)} (got {bound!r})")
    if parts and model != "glass" and fresnel != "split":
        raise ValueError(spoken("parts=True certifies E_R and E_T of a glass table (model='glass') or of a conductor "
                                "with fresnel='split'", "--parts certifies E_R and E_T of a glass table (--model "
                                "glass) or of a conductor with --fresnel split"))
    epsilon, delta = float(epsilon), float(delta)
    sized = epsilon / count_scale  # the counts estimate E/c: held to ε/c, the values c × count/N to ε
    n1 = table_pilot_rays(epsilon) if pilot_rays is None else _whole("pilot_rays", pilot_rays, 1, 2**32 - 1)
    outs = [] if out is None else [Path(out)] if isinstance(out, (str, os.PathLike)) else [Path(p) for p in out]
    for path in outs:
        if path.suffix.lower() not in (".nc", ".npy", ".h", ".hpp"):
            raise ValueError(f"out must end in .nc, .npy, .h or .hpp (got {path.name!r})")
        if not path.parent.exists():
            raise ValueError(f"out {path}: the directory {path.parent} does not exist")
        _check_output(path, bool(average), bool(overwrite))
    check_distinct([*(("out", path) for path in outs), ("checkpoint", checkpoint)])  # one output never over another
    if checkpoint is None and outs:
        checkpoint = outs[0].with_name(outs[0].name + ".parts")
    quantities = ("E", "E_R", "E_T") if parts else ("E",)
    q = len(quantities)

    mi = mitsuba()
    points = grid.points
    n_mu, n_p = len(grid.mu), len(points)
    n_cells = n_mu * n_p + (n_p if average else 0)
    theta = np.degrees(np.arccos(grid.mu))
    names = ["specimen.alpha"] + (["specimen.eta"] if model == "glass" else [])
    identity = {"format": _FORMAT, "model": model, "distribution": distribution, "mu": grid.mu.tolist(),
                "alpha": grid.alpha.tolist(), "eta": None if grid.eta is None else grid.eta.tolist(),
                "epsilon": epsilon, "delta": delta, "bound": bound, "average": bool(average), "parts": bool(parts),
                "pilot_rays": n1, "seed": int(seed), "wavelength": float(wavelength), "version": __version__,
                "bsdf": bsdf_parameters}
    # One run at a time on a checkpoint (a second refuses; it never touches the first's groups), and signals
    # acted on at safe points only: never inside a write (a KeyboardInterrupt inside xarray's file lock hung
    # the process, and left a temporary file)
    if checkpoint is not None:  # the parts' writer, imported here (a second or more), not between two safe points
        from virtspec_mi.results.io import warm_writer

        warm_writer()
    with (nullcontext() if checkpoint is None else locked(Path(checkpoint))), interrupts.deferred():
            store = ResultStore(None if checkpoint is None else Path(checkpoint), identity, "table")
            scene = loaded(_scene(grid, bsdf_parameters))  # once: every group's sweep takes it
            started = time.perf_counter()
            traced_seconds = 0.0
            groups = 0
            adaptive = BOUNDS[bound].adaptive
            bar = Progress(progress, n_cells * (2 if adaptive else 1), desc="albedo table")

            def run(label: str, beam: str, angles: Sequence[float], pts: np.ndarray, rays: int) -> Any:
                nonlocal traced_seconds, groups
                groups += 1
                result = store.load(label, read_result)
                if result is None:
                    bar.expect(len(angles) * len(pts))  # the group's kernel chunks move the table's bar
                    with warnings.catch_warnings():  # a group's uncertified readings are reported once, for the table
                        warnings.simplefilter("ignore", RuntimeWarning)
                        result = take("sweep", scene, theta_i=list(angles), beam=beam, rays=int(rays), wavelengths=[wavelength],
                                       parameters={n: pts[:, k].tolist() for k, n in enumerate(names)}, points=True,
                                       seed=derived_seed(seed, label), sampling="random", progress=False,
                                       **({} if chunk_size is None else {"chunk_size": chunk_size}))
                    try:
                        store.save(label, result)
                    except WriteError as error:  # a full disk: the table resumes from its parts, no group offered
                        raise error.keeping(_resumes(store.directory, "the groups finished before it")) from None
                    interrupts.check()  # a safe point: the group is saved, none is being written
                traced_seconds += result.seconds
                bar.reach(bar.done + len(angles) * len(pts))
                return result

            def counts_of(result: Any) -> dict[str, np.ndarray]:  # (θ, point) arrays of one wavelength
                return {k: np.asarray(getattr(result, k))[0] for k in ("rays",) + _KEYS}

            beams = [("collimated", theta, n_mu)] + ([("diffuse", np.array([0.0]), 1)] if average else [])
            assembled: dict[str, dict[str, np.ndarray]] = {}
            try:  # an interrupt: at a kernel chunk of a group's sweep or between two groups, the finished ones kept
                pilots = {}
                for beam, angles, rows in beams:
                    shape = (rows, n_p)
                    totals = {k: np.zeros(shape, dtype=np.int64) for k in ("rays",) + _KEYS}
                    totals["pilot_rays"] = np.zeros(shape, dtype=np.int64)
                    totals["pilot_violations"] = np.zeros(shape, dtype=np.int64)
                    totals["interval_delta"] = np.full(shape, delta / (n_cells * q))
                    if not adaptive:
                        rays = union_hoeffding_rays(sized, delta, n_cells * q)
                        found = counts_of(run(f"hoeffding:{beam}", beam, angles, points, rays))
                        for k in found:
                            totals[k][:] = found[k]
                    else:
                        pilot = counts_of(run(f"pilot:{beam}", beam, angles, points, n1))
                        totals["pilot_rays"][:] = pilot["rays"]
                        totals["pilot_violations"][:] = (pilot["weight_violations"] + pilot["invalid_directions"]
                                                         + pilot["capped"])
                        hits = [pilot["reflected"] + pilot["transmitted"]]
                        if parts:
                            hits += [pilot["reflected"], pilot["transmitted"]]
                        pilots[beam] = [pilot_intervals(h, n1, delta / 10.0 / (n_cells * q)) for h in hits]
                    assembled[beam] = totals
                if adaptive:
                    shares = stage_two_shares({beam: intervals for beam, intervals in pilots.items()}, delta * 0.9)
                    for beam, angles, rows in beams:
                        totals = assembled[beam]
                        share = shares[beam]  # δ of each quantity's second batch, per cell
                        totals["interval_delta"] = share
                        need = np.max([binomial_rays(lo, hi, sized, share) for lo, hi in pilots[beam]], axis=0)
                        classes = stage_two_classes(need, sized, share)  # few classes: one sweep each
                        for rays in np.unique(classes):
                            rows_in, cols_in = np.nonzero(classes == rays)
                            if len(np.unique(rows_in)) <= len(np.unique(cols_in)):  # fewer sweeps: one per θ row …
                                for row in np.unique(rows_in):
                                    members = cols_in[rows_in == row]
                                    label = f"stage2:{beam}:{int(rays)}:row{row}:" + ",".join(map(str, members.tolist()))
                                    found = counts_of(run(label, beam, [angles[row]], points[members], int(rays)))
                                    for k in found:
                                        totals[k][row, members] = found[k][0]
                            else:  # … or one per parameter point (a column of θ rows)
                                for col in np.unique(cols_in):
                                    members = rows_in[cols_in == col]
                                    label = f"stage2:{beam}:{int(rays)}:col{col}:" + ",".join(map(str, members.tolist()))
                                    found = counts_of(run(label, beam, angles[members], points[[col]], int(rays)))
                                    for k in found:
                                        totals[k][members, col] = found[k][:, 0]
            except interrupts.Interrupted as stop:
                stop.checkpoint = store.directory if store.directory is not None and store.saved else None
                raise
            finally:
                bar.close()
            if store.reused:
                bar.note(f"resumed from {store.directory}: {store.reused} finished group(s) reused")

            import mitsuba as _mitsuba_module

            collimated = {k: grid.canonical(v) for k, v in assembled["collimated"].items()}
            averaged = None
            if average:
                averaged = {k: grid.canonical_average(v[0]) for k, v in assembled["diffuse"].items()}
            provenance = {"seed": int(seed), "wavelength_nm": float(wavelength), "mitsuba": _mitsuba_module.__version__,
                          "variant": mi.variant(), "virtspec_mi": __version__, "pilot_rays": n1 if adaptive else 0,
                          "seconds_wall": round(time.perf_counter() - started, 3), "seconds_traced": round(traced_seconds, 3),
                          "groups": groups,
                          "created": datetime.now(timezone.utc).isoformat(timespec="seconds"),
                          "bsdf": "microfacet" if model == "conductor" else "roughdielectric",
                          "bsdf_model": model_words,
                          "beam": "collimated (E), diffuse cosine-weighted (E_avg)",
                          "alpha_clamp": ("none: GGX visible normals are sampled for any alpha > 0"
                                          if model == "conductor" and distribution == "ggx" else
                                          "Mitsuba clamps alpha >= 1e-4 (MicrofacetDistribution::configure)")}
            table = AlbedoTable(model, distribution, grid.mu, grid.alpha, grid.eta, grid.roughness, grid.engine, grid.order,
                                collimated, averaged, epsilon, delta, bound, quantities, provenance,
                                bsdf_parameters if model == "conductor" else {}, count_scale)
            if not table.certified:
                warnings.warn(f"albedo table: {table.statement()}", RuntimeWarning, stacklevel=2)
            interrupts.check()  # the last safe point before the outputs are written
            try:
                for path in outs:
                    table.write(path, overwrite=overwrite)
            except WriteError as error:  # every group is kept: the same call writes the table without tracing
                raise error.keeping(_resumes(store.directory, "every group of the table"), table) from None
            store.remove()  # the table is returned (and written to every out): its groups are safe
            return table

