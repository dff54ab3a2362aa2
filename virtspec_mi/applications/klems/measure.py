"""
Klems matrices measured by the goniophotometer: :func:`klems_measure`
=====================================================================

Measures a specimen on a Klems basis (:mod:`virtspec_mi.exchange.klems_basis`) with
:func:`virtspec_mi.gonio` and returns the certified
:class:`~virtspec_mi.applications.klems.matrices.KlemsMeasurement` (see :mod:`virtspec_mi.applications.klems.matrices`
for the file, its orientation and its certificate):

- one collimated reading per incident patch centre (θ the ring's middle, 0 for the cap),
  with its source at azimuth φ_patch + 180°; readings that share that azimuth are one
  :func:`~virtspec_mi.gonio` call over their θ;
- the outgoing bins are the ring bounds (both hemispheres) × :meth:`KlemsBasis.phi_bins`
  equal φo bins (480 for the full basis), which nest exactly in the patches;
- the back side is the specimen turned over (:mod:`virtspec_mi.plugins.bsdfs.flipped`) or a
  scene of its own;
- rays per incidence N = ⌈ln(2S/δ)/(2ε²)⌉ for the S statements of the file (every patch
  fraction of every matrix, every R and T: Hoeffding + union).

``isotropic=True`` measures one incidence per ring (φ = 0) and rotates its bins onto the
ring's other patches (by whole bins: every Klems azimuth is a multiple of 0.75°) — right
for a specimen invariant under rotation about its normal, 9 readings per side instead of
145.

References
----------
Klems, J.H. (1994). ASHRAE Transactions 100(1), 1065–1072. Hoeffding, W. (1963). JASA 58,
13–30: eq. (2.3). Baranoski, G.V.G., Rokne, J.G., Xu, G. (2001). The Visual Computer 17,
506–518: eq. (23).
"""

from __future__ import annotations

import os
import time
from contextlib import nullcontext
from dataclasses import dataclass
from datetime import datetime, timezone
from pathlib import Path
from typing import Any

import numpy as np

from virtspec_mi.base.version import __version__
from virtspec_mi.exchange.common import derived_seed
from virtspec_mi.base.checks import check_delta, check_rays, real, shown_value
import virtspec_mi.base.interrupts as interrupts
from virtspec_mi.engine.checkpoint import ResultStore, locked
from virtspec_mi.settings import true_or_false, whole_number
from virtspec_mi.engine.readings import check_specimen
from virtspec_mi.applications.klems.matrices import SIDES, KlemsMeasurement, aggregate, check_escaped, check_klems_output
from virtspec_mi.exchange.klems_basis import klems_basis
from virtspec_mi.budgets.binomial import union_hoeffding_rays

__all__ = ["klems_measure", "flipped"]



def flipped(bsdf: Any) -> dict[str, Any]:
    """
    The scene-dict entry of ``bsdf`` (a dict or a loaded BSDF) turned over: the
    ``virtspec_flipped`` plugin (:mod:`virtspec_mi.plugins.bsdfs.flipped`) around it.
    """

    return {"type": "virtspec_flipped", "nested": bsdf}


def klems_measure(
    scene: Any,
    *,
    basis: str = "full",
    back: Any = None,
    wavelengths: Any = 551.0,
    epsilon: float = 0.01,
    delta: float = 0.01,
    rays: int | None = None,
    seed: int = 0,
    isotropic: bool = False,
    out: str | os.PathLike | None = None,
    name: str = "virtspec-mi specimen",
    progress: bool | None = None,
    overwrite: bool = False,
) -> KlemsMeasurement:
    """
    Measure Klems matrices of ``scene``'s specimen (see the module docstring).

    Parameters
    ----------
    scene
        XML path, scene dict or ``mi.Scene`` with ``emitter`` and ``specimen`` disks (as
        for :func:`virtspec_mi.measure`, a :class:`~virtspec_mi.runtime.scene.LoadedScene` too); its
        geometry does not matter (collimated beam). Loaded once (:func:`virtspec_mi.runtime.scene.loaded`):
        every reading of its side takes that loaded scene.
    basis
        ``full`` (145 patches), ``half`` (77, as Radiance reads it) or ``quarter`` (41).
    back
        The back side: ``None`` (default) the specimen turned over
        (:func:`virtspec_mi.plugins.bsdfs.flipped.flipped`), a scene of its own (e.g. a leaf with
        ``side="abaxial"``), or ``False`` for the front matrices only.
    wavelengths
        Wavelength(s) in nm.
    epsilon, delta
        Every patch fraction, R and T within ε at once with probability ≥ 1 − δ
        (0 < ε < 0.5, 0 < δ < 1); sizes N per incidence unless ``rays`` is given.
    rays
        Rays per incidence (the certificate then states what they give).
    seed
        Seed of the run (each reading's seed is derived from it and its incidence).
    isotropic
        Measure one azimuth per ring and rotate it onto the ring's other incidences (a
        specimen invariant under rotation about its normal; 9 readings per side instead
        of 145).
    out
        Klems XML file to write (and its ``.nc`` sidecar).
    name
        The specimen's name in the file.
    progress
        A tqdm bar of the readings (``None``: when stderr is a terminal and it takes > 2 s).
    overwrite
        Let the sidecar ``OUT.nc`` replace a file of that name that is not a Klems sidecar
        (refused otherwise, before anything is measured, as is ``out`` naming the scene file).

    References
    ----------
    Klems (1994); Hoeffding (1963), eq. (2.3); Baranoski et al. (2001), eq. (23).
    """

    from virtspec_mi.runtime.reading import read_result, take
    from virtspec_mi.base.checks import parse_wavelengths
    from virtspec_mi.engine.progress import Progress
    from virtspec_mi.runtime import mitsuba
    from virtspec_mi.runtime.scene import instrument_scene, loaded

    klems = klems_basis(basis)
    epsilon, delta = real("epsilon", epsilon), check_delta(real("delta", delta))  # any real number type, not text
    seed = whole_number("seed", 0, 2**32 - 1, "0 <= seed < 2**32")(seed)
    rays = None if rays is None else check_rays(rays)
    isotropic = true_or_false("isotropic")(isotropic)
    if not 0.0 < epsilon < 0.5:
        raise ValueError(f"epsilon must satisfy 0 < epsilon < 0.5 (got {shown_value(epsilon)})")
    lams = np.array(parse_wavelengths(wavelengths), dtype=np.float64)
    if out is not None:  # before anything is measured: the folder, the scene itself, the sidecar's name
        from virtspec_mi import scenes as shipped

        check_klems_output(out, overwrite=overwrite, inputs=[_resolved(scene, shipped), _resolved(back, shipped)],
                           wavelengths=lams.tolist())
    mi = mitsuba()
    scenes = [loaded(each) for each in [scene] + ([back] if back not in (None, False) else [])]  # each loaded once
    for each in scenes:
        check_specimen(each.bench.bsdf, lams.tolist())  # wavelengths outside its data: before any reading
    if back is None:
        scenes.append(loaded(instrument_scene(flipped(scenes[0].bench.bsdf))))
    n_sides = len(scenes)
    statements = n_sides * len(lams) * klems.size * (2 * klems.size + 2)
    n_rays = union_hoeffding_rays(epsilon, delta, statements) if rays is None else int(rays)
    edges = klems.theta_edges()
    phi_bins = klems.phi_bins()
    width = 360.0 / phi_bins
    started = time.perf_counter()
    counts = np.zeros((n_sides, len(lams), klems.size, 2, klems.size), dtype=np.int64)
    ray_counts = np.zeros((n_sides, len(lams), klems.size), dtype=np.int64)
    refl, trans = np.zeros_like(ray_counts), np.zeros_like(ray_counts)
    # incidences grouped by the source azimuth phi_patch + 180 (one goniophotometer call each)
    groups: dict[float, list[int]] = {}
    for p in range(klems.size):
        if isotropic and klems.index_in_ring[p] != 0:
            continue
        groups.setdefault(round((klems.phi[p] + 180.0) % 360.0, 9), []).append(p)
    identity = {"format": "virtspec-mi klems parts 1", "basis": klems.key, "wavelengths": lams.tolist(),
                "rays": int(n_rays), "seed": int(seed), "isotropic": bool(isotropic), "sides": n_sides,
                "scene": str(scene) if isinstance(scene, (str, os.PathLike)) else None,
                "back": str(back) if isinstance(back, (str, os.PathLike)) else repr(type(back).__name__),
                "version": __version__}
    folder = None if out is None else Path(out).with_name(Path(out).name + ".parts")
    if folder is not None:  # the parts' writer, imported here (a second or more), not between two safe points
        from virtspec_mi.results.io import warm_writer

        warm_writer()
    # signals act at the readings' safe points only (never inside the files' writes); one run at a time on the
    # parts folder (the engine's ResultStore), where each finished group of readings is kept (a re-run reuses them)
    with (nullcontext() if folder is None else locked(folder)), interrupts.deferred():
        parts = ResultStore(folder, identity, "Klems measurement")
        bar = Progress(progress, n_sides * sum(len(v) for v in groups.values()), desc="klems")
        try:
            for s, side_scene in enumerate(scenes):
                for phi_i, patches in sorted(groups.items()):
                    label = f"{SIDES[s]}:{phi_i:.9g}"
                    part = parts.path(label)  # the reading's out: written whole, with its own checkpoint meanwhile
                    reading = parts.load(label, read_result)
                    if reading is None:
                        bar.expect(len(patches))  # the group's kernel chunks move the bar
                        reading = take("gonio", side_scene, theta_i=[float(klems.theta[p]) for p in patches], phi_i=phi_i,
                                        beam="collimated", wavelengths=lams.tolist(), rays=n_rays,
                                        seed=derived_seed(seed, label), theta_o_bins=edges.tolist(),
                                        phi_o_bins=phi_bins, out=part, progress=False if progress is False else None)
                    interrupts.check()  # a safe point: the group is kept in its part
                    patch_counts = aggregate(reading, klems)
                    r = np.asarray(reading.result.reflected)
                    t = np.asarray(reading.result.transmitted)
                    check_escaped(patch_counts, r, t)
                    for column, p in enumerate(patches):
                        targets = [p]
                        if isotropic:
                            ring = klems.ring[p]
                            targets = list(np.nonzero(klems.ring == ring)[0])
                        for q in targets:
                            shift = int(round((klems.phi[q] - klems.phi[p]) / width))
                            counts[s, :, q] = (aggregate(_Single(reading, column, shift), klems)[:, 0] if shift
                                               else patch_counts[:, column])
                            ray_counts[s, :, q] = np.asarray(reading.rays)[:, column]
                            refl[s, :, q], trans[s, :, q] = r[:, column], t[:, column]
                    bar.reach(bar.done + len(patches))
        except interrupts.Interrupted as stop:  # the parts folder is this run's checkpoint (a group's file is not)
            stop.checkpoint = folder if parts.kept() else None
            stop.written = None  # type: ignore[attr-defined]
            raise
        finally:
            bar.close()
        if parts.reused:
            bar.note(f"resumed from {folder}: {parts.reused} finished group(s) of readings reused")
        import mitsuba as _mitsuba_module

        provenance = {"seed": int(seed), "mitsuba": _mitsuba_module.__version__, "variant": mi.variant(),
                      "virtspec_mi": __version__, "scene": str(scene) if isinstance(scene, (str, os.PathLike)) else
                      type(scene).__name__, "back": "turned over (virtspec_flipped)" if back is None else
                      ("none" if back is False else "given scene"), "beam": "collimated at each patch centre",
                      "seconds_wall": round(time.perf_counter() - started, 3),
                      "created": datetime.now(timezone.utc).isoformat(timespec="seconds")}
        measurement = KlemsMeasurement(klems, SIDES[:n_sides], lams, counts, ray_counts, refl, trans, float(epsilon),
                                       float(delta), bool(isotropic), provenance)
        if out is not None:
            interrupts.check()  # the last safe point before the files are written
            measurement.write(out, name=name, overwrite=overwrite)
            parts.remove()  # the file is written: its groups are safe
    return measurement


def _resolved(scene: Any, shipped: Any) -> Any:
    """The file of a scene given by path or shipped name (else ``None``: a dict or a loaded scene)."""

    if not isinstance(scene, (str, os.PathLike)):
        return None
    try:
        return shipped.resolve(scene)
    except Exception:  # the scene's own loading reports a bad name
        return scene


@dataclass(frozen=True)
class _Single:
    """One θi column of a reading, its φ bins rotated by ``shift`` bins (for :func:`_aggregate`)."""

    reading: Any
    column: int
    shift: int

    @property
    def bins(self) -> Any:
        return self.reading.bins

    @property
    def bin_counts(self) -> np.ndarray:
        counts = np.asarray(self.reading.bin_counts)[:, [self.column]]
        return np.roll(counts, self.shift, axis=-1)
