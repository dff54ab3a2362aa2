"""
Throughput of a conical diamond reading (issue 2)
=================================================

Measures, side by side in one run, the same conical-hemispherical reading of the
paper's diamond (``simple_dielectric``, η = 2.419; r₁ = 8, r₂ = 12.5, D = 100;
θi = 70°, φi = 0; one wavelength, 551 nm; seed 0) done three ways:

1. **Mitsuba** — the project's reading, ``virtspec_mi.measure(instrument_scene(
   {"type": "simple_dielectric"}), theta_i=70, rays=N)`` (jittered sampling, the
   BSDF plugin called through ``mi.BSDF.sample``), warm: one small call compiles
   the kernel first; best of 3 at 10⁷ rays, best of 2 at 10⁸.
2. **NumPy** — a plain float64 NumPy version of the same instrument written here:
   chunks of 2²⁰ rays, *plain uniform* (unstratified) emitter points by the polar
   warp (2πu₁, r₁√u₂), rotated to θi about y as in ``geometry.incidence_frame``,
   uniform specimen targets, unpolarised Fresnel reflectance, reflected if u < F.
   One run at 10⁷ rays (~4 Mray/s). Its reflectance must agree with (1) within
   a few 10⁻⁴ (statistically: a few combined standard deviations).
3. **bare Dr.Jit** — the hardware ceiling: one Dr.Jit kernel of the same maths
   (the project's counter-based RNG and keys, jittered polar warp, rotation,
   normalize, a hand-written Fresnel coin flip, one ``dr.sum`` over packed UInt64
   counts) with no Mitsuba BSDF or SurfaceInteraction; self-contained (the RNG and
   warps copied bit for bit, only ``virtspec_mi.mitsuba()`` imported); chunks of
   2²², every per-call scalar passed with ``dr.opaque`` so the kernel is compiled once.
   It draws the same random numbers as (1), so its counts should equal (1)'s up
   to float rounding of F.

With ``--against REV`` it measures instead only (1) and (3), for the working tree and
for the git revision REV side by side, to show that a change kept the Mitsuba reading
at no less than its previous ratio to the bare kernel (the machine's speed cancels
out of the ratio; see ``--against`` below).

It also measures the peak memory (max RSS) and time of one 10⁹-ray reading in a
fresh subprocess, a warm certified reading at the default budget (105,967 rays;
median and min of 20 calls), the wall time of a cold ``virtspec measure`` process
(median of 3; a fresh process, but Dr.Jit's on-disk kernel cache is warm by then),
and records the machine (CPU, AVX-512 or not, Dr.Jit threads,
libLLVM) and the date. The issue's targets are printed next to the figures.
Absolute rays/s depend on the machine (and it is noisy); the ratios
Mitsuba / bare and Mitsuba / NumPy are the figures to compare across machines.

Run::

    make bench                                      # = .venv/bin/python benchmarks/throughput.py
    .venv/bin/python benchmarks/throughput.py --quick      # 10⁶ / 10⁷ rays, no 10⁹ run
    .venv/bin/python benchmarks/throughput.py --markdown   # results as a markdown block
    .venv/bin/python benchmarks/throughput.py --against HEAD~1          # 10⁸ rays, 7 rounds
    .venv/bin/python benchmarks/throughput.py --against ebc84c5 --quick # 10⁷ rays, 10 rounds
    .venv/bin/python benchmarks/throughput.py --against main --rounds 15 --markdown

The full run takes 15-30 s on a 2-core machine (the 10⁹-ray reading ~5 s, NumPy
~2-3 s, the rest is repeats and process start-ups); other work on the machine
slows every figure, so the 1-minute load average is printed with the results.

``--against REV``
-----------------

The older revision is checked out into a throwaway directory (``git worktree add
--detach``, removed afterwards with ``git worktree remove --force``; the checkout's
own index and branch are never touched), with the symlink ``virtspec_mi/plugins ->
../plugins`` that a plain ``PYTHONPATH`` import needs (the package maps
``virtspec_mi.plugins`` to the top-level ``plugins/``; see ``benchmarks/revisions.py``).
Each side — the working tree as it is, uncommitted changes included, and REV — is
measured by a worker process of this script with ``PYTHONPATH`` at its checkout; the
worker reports ``virtspec_mi.__file__`` and the script stops unless every loaded
``virtspec_mi`` module comes from that checkout (not from the editable install). The
workers use only public API found in old revisions too (``virtspec_mi.measure``,
``instrument_scene``, ``mitsuba``; ``reading.reflected``, ``reading.rays``), and the
bare kernel is this file's own self-contained code, identical for both sides.

Both workers warm up (compile, one untimed call at full size), then the revisions
take turns, A B A B …: per round and revision, one Mitsuba reading then one bare
kernel run, 10⁸ rays each (10⁷ with ``--quick``), 7 rounds (10 with ``--quick``;
``--rounds K``). Printed per revision: Mray/s of each (best of the rounds), the ratio
Mitsuba / bare of those bests and the median (min – max) of the per-round ratios; then
the ratio of ratios working tree / REV with a verdict against the round-to-round
spread, whether the two revisions' Mitsuba counts are identical, bare − Mitsuba
counts, the SIMD width (AVX-512 or AVX2), the machine and the 1-minute load average.
``--against HEAD`` runs the same code on both sides: its ratio of ratios shows the
noise (on a shared 2-core machine, ±5-10 % at ``--quick`` sizes).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import resource
import statistics
import subprocess
import sys
import time
from dataclasses import dataclass
from functools import partial
from pathlib import Path
from typing import Any, Callable

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import revisions  # noqa: E402  (machine description, git revisions)
from revisions import machine, machine_lines  # noqa: E402,F401  (also imported from here by others)

ROOT = Path(__file__).resolve().parents[1]
VIRTSPEC = ROOT / ".venv" / "bin" / "virtspec"
COLD_COMMAND = [str(VIRTSPEC), "measure", "scenes/diamond_conical.xml", "--theta-i", "70"]

# The reading under test (the paper's instrument and specimen).
ETA = 2.419
THETA_I = 70.0
PHI_I = 0.0
EMITTER_RADIUS = 8.0
SPECIMEN_RADIUS = 12.5
DISTANCE = 100.0
SEED = 0
BSDF = {"type": "simple_dielectric"}

NUMPY_CHUNK = 1 << 20
DRJIT_CHUNK = 1 << 22
WORD = 1 << 32

# Targets from the issue.
TARGET_MRAYS = 300.0          # Mitsuba-based reading, Mray/s
TARGET_PEAK_GIB = 1.0         # max RSS of a 10⁹-ray reading
TARGET_WARM_MS = 20.0         # warm certified reading
TARGET_COLD_S = 2.0           # cold `virtspec measure` process
ISSUE_BARE_MRAYS = 780.0      # the issue's bare kernel "on this machine class"
ISSUE_NUMPY_MRAYS = 4.0       # the issue's NumPy figure


@dataclass
class Run:
    """One throughput figure: a method at a ray count, its best time and its counts."""

    method: str
    rays: int
    seconds: float
    reflected: int
    transmitted: int
    repeats: int

    @property
    def mrays(self) -> float:
        return self.rays / self.seconds / 1e6

    @property
    def reflectance(self) -> float:
        return self.reflected / self.rays


def best_of(repeats: int, call: Callable[[], tuple[int, int]]) -> tuple[float, int, int]:
    """Shortest wall time of ``repeats`` calls of ``call`` and the counts of the last one."""

    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        reflected, transmitted = call()
        times.append(time.perf_counter() - start)
    return min(times), reflected, transmitted


# --- (1) the Mitsuba-based reading --------------------------------------------------------


def mitsuba_counts(scene: dict, rays: int) -> tuple[int, int]:
    """Reflected and transmitted counts of one ``virtspec_mi.measure`` reading."""

    import virtspec_mi

    reading = virtspec_mi.measure(scene, theta_i=THETA_I, phi_i=PHI_I, rays=rays, seed=SEED)
    return int(reading.reflected[0]), int(reading.transmitted[0])


# --- (2) plain NumPy float64 --------------------------------------------------------------


def fresnel_unpolarised(cos_i: np.ndarray, eta: float) -> np.ndarray:
    """Unpolarised Fresnel reflectance of a dielectric (η = n_inside / n_outside)."""

    eta_i = np.where(cos_i >= 0.0, eta, 1.0 / eta)  # a ray from below sees 1/η
    c = np.abs(cos_i)
    sin2_t = (1.0 - c * c) / (eta_i * eta_i)
    cos_t = np.sqrt(np.maximum(1.0 - sin2_t, 0.0))
    r_s = (c - eta_i * cos_t) / (c + eta_i * cos_t)
    r_p = (eta_i * c - cos_t) / (eta_i * c + cos_t)
    return np.where(sin2_t >= 1.0, 1.0, 0.5 * (r_s * r_s + r_p * r_p))


def incidence_basis(theta_i: float, phi_i: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(ω, e_u, e_v): the emitter disk (x, y, D) rotated by θ about y, then φ about z."""

    t, p = math.radians(theta_i), math.radians(phi_i)
    omega = np.array([math.sin(t) * math.cos(p), math.sin(t) * math.sin(p), math.cos(t)])
    e_u = np.array([math.cos(t) * math.cos(p), math.cos(t) * math.sin(p), -math.sin(t)])
    e_v = np.array([-math.sin(p), math.cos(p), 0.0])
    return omega, e_u, e_v


def numpy_chunk(generator: np.random.Generator, size: int) -> tuple[int, int]:
    """Reflected and transmitted counts of ``size`` conical rays in float64 NumPy."""

    u = generator.random((5, size))
    omega, e_u, e_v = incidence_basis(THETA_I, PHI_I)
    # Emitter point: polar warp of plain uniforms, then rotated to the incidence.
    angle, radius = 2.0 * np.pi * u[0], EMITTER_RADIUS * np.sqrt(u[1])
    x, y = radius * np.cos(angle), radius * np.sin(angle)
    origin = DISTANCE * omega[:, None] + x * e_u[:, None] + y * e_v[:, None]
    # Target: uniform on the specimen disk (z = 0).
    angle, radius = 2.0 * np.pi * u[2], SPECIMEN_RADIUS * np.sqrt(u[3])
    target = np.stack([radius * np.cos(angle), radius * np.sin(angle), np.zeros(size)])
    wi = origin - target
    wi /= np.sqrt(np.sum(wi * wi, axis=0))
    reflect = u[4] < fresnel_unpolarised(wi[2], ETA)
    # Fates in the specimen frame: reflect(wi) keeps the sign of wi.z, refraction flips it.
    upper = np.where(reflect, wi[2] >= 0.0, wi[2] < 0.0)
    reflected = int(np.count_nonzero(upper))
    return reflected, size - reflected


def numpy_counts(rays: int) -> tuple[int, int]:
    """Counts of a ``rays``-ray NumPy reading, in chunks of ``NUMPY_CHUNK``."""

    generator = np.random.default_rng(SEED)
    reflected = transmitted = 0
    for first in range(0, rays, NUMPY_CHUNK):
        r, t = numpy_chunk(generator, min(NUMPY_CHUNK, rays - first))
        reflected, transmitted = reflected + r, transmitted + t
    return reflected, transmitted


# --- (3) bare Dr.Jit kernel ---------------------------------------------------------------
#
# The kernel uses the project's own counter-based RNG and disk warps (in virtspec_mi.kernel
# since the core was reshaped, at the package's top level before), so each revision's bare
# kernel draws the same random numbers as its Mitsuba reading: the check "counts bare
# Dr.Jit - Mitsuba" shows any difference.

import virtspec_mi  # noqa: E402  (the revision on PYTHONPATH, or the working tree)

if (Path(virtspec_mi.__file__).parent / "kernel").is_dir():
    from virtspec_mi.kernel.disk import jittered_cell, polar_warp
    from virtspec_mi.kernel.rng import chunk_root, dimension_keys, hash32, to_unit
else:  # a revision before virtspec_mi.kernel (the editable install would supply the new one)
    from virtspec_mi.geometry import jittered_cell, polar_warp
    from virtspec_mi.kernel.rng import chunk_root, dimension_keys, hash32, to_unit


def drjit_chunk(first: int, size: int, strata: int) -> tuple[int, int]:
    """
    Counts of rays [first, first + size) of one reading as one bare Dr.Jit kernel.

    Same random numbers as the integrator (dimensions 0–1 emitter, 2–3 specimen,
    4 the Fresnel coin), same jittered polar warp and rotation; no Mitsuba BSDF.
    """

    import drjit as dr
    import virtspec_mi

    mi = virtspec_mi.mitsuba()
    keys = [dr.opaque(mi.UInt32, k) for k in dimension_keys(chunk_root(SEED, first // WORD), 5)]
    ray = dr.arange(mi.UInt32, size) + dr.opaque(mi.UInt32, first % WORD)

    def uniform(dimension: int) -> Any:
        return to_unit(hash32(ray ^ keys[dimension]), mi.Float)

    def vector(values: np.ndarray) -> Any:
        return mi.Vector3f(*(dr.opaque(mi.Float, float(v)) for v in values))

    omega, e_u, e_v = incidence_basis(THETA_I, PHI_I)
    u0, u1 = jittered_cell(mi, uniform(0), uniform(1), ray, dr.opaque(mi.UInt32, strata))
    emitter = polar_warp(mi, u0, u1, dr.opaque(mi.Float, EMITTER_RADIUS))
    target = polar_warp(mi, uniform(2), uniform(3), dr.opaque(mi.Float, SPECIMEN_RADIUS))
    origin = vector(DISTANCE * omega) + emitter.x * vector(e_u) + emitter.y * vector(e_v)
    wi = dr.normalize(origin - mi.Vector3f(target.x, target.y, 0.0))

    # Hand-written unpolarised Fresnel (as fresnel_unpolarised, in float32).
    eta = dr.opaque(mi.Float, ETA)
    eta = dr.select(wi.z >= 0.0, eta, dr.rcp(eta))
    c = dr.abs(wi.z)
    sin2_t = (1.0 - c * c) * dr.rcp(eta * eta)
    cos_t = dr.sqrt(dr.maximum(1.0 - sin2_t, 0.0))
    r_s = (c - eta * cos_t) / (c + eta * cos_t)
    r_p = (eta * c - cos_t) / (eta * c + cos_t)
    fresnel = dr.select(sin2_t >= 1.0, 1.0, 0.5 * (r_s * r_s + r_p * r_p))
    reflect = uniform(4) < fresnel
    upper = dr.select(reflect, wi.z >= 0.0, wi.z < 0.0)

    code = dr.select(upper, mi.UInt64(1), mi.UInt64(WORD))  # low word reflected, high transmitted
    dr.eval(code)  # the one fused ray kernel
    packed = int(dr.sum(code).numpy()[0])
    return packed & (WORD - 1), packed >> 32


def drjit_counts(rays: int) -> tuple[int, int]:
    """Counts of a ``rays``-ray reading by the bare kernel, in chunks of ``DRJIT_CHUNK``."""

    strata = math.isqrt(rays)  # the jittered grid of the reading, as in the integrator
    reflected = transmitted = 0
    first = 0
    while first < rays:
        size = min(DRJIT_CHUNK, rays - first, WORD - first % WORD)
        r, t = drjit_chunk(first, size, strata)
        reflected, transmitted = reflected + r, transmitted + t
        first += size
    return reflected, transmitted


# --- memory, latency and start-up ---------------------------------------------------------

_BIG_READING = """
import json, time, virtspec_mi
scene = virtspec_mi.instrument_scene({bsdf!r})
start = time.perf_counter()
reading = virtspec_mi.measure(scene, theta_i={theta}, phi_i={phi}, rays={rays}, seed={seed})
print(json.dumps({{"seconds": reading.seconds, "wall": time.perf_counter() - start,
                  "reflectance": float(reading.reflectance[0])}}))
"""


def big_reading(rays: int) -> dict:
    """
    One ``rays``-ray reading in a fresh Python process: its seconds, reflectance and
    peak RSS (``getrusage(RUSAGE_CHILDREN)``, in bytes).

    Call it before any other subprocess and before this process imports Mitsuba:
    RUSAGE_CHILDREN is the largest of all waited-for children, and a child's
    max RSS also counts the parent's memory it was spawned from.
    """

    code = _BIG_READING.format(bsdf=BSDF, theta=THETA_I, phi=PHI_I, rays=rays, seed=SEED)
    done = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True)
    if done.returncode != 0:
        raise RuntimeError(f"the {rays:.0e}-ray reading failed:\n{done.stderr}")
    result = json.loads(done.stdout.strip().splitlines()[-1])
    result["peak_rss"] = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss * 1024  # KiB on Linux
    result["rays"] = rays
    return result


def warm_reading(repeats: int = 20) -> dict:
    """Median and min wall time (ms) of a default certified reading, after one warm-up call."""

    import virtspec_mi

    scene = virtspec_mi.instrument_scene(BSDF)
    virtspec_mi.measure(scene, theta_i=THETA_I)
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        reading = virtspec_mi.measure(scene, theta_i=THETA_I)
        times.append(time.perf_counter() - start)
    return {"rays": int(reading.rays[0]), "median_ms": 1e3 * statistics.median(times),
            "min_ms": 1e3 * min(times), "repeats": repeats}


def cold_process(repeats: int = 3) -> dict:
    """Median wall time (s) of a fresh ``virtspec measure`` process (and each run's)."""

    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        subprocess.run(COLD_COMMAND, cwd=ROOT, check=True, capture_output=True)
        times.append(time.perf_counter() - start)
    return {"median_s": statistics.median(times), "runs_s": times}


# --- --against REV: the Mitsuba / bare ratio of two revisions, side by side ----------------
#
# Each revision is measured by a worker process of this very script (``--worker ROOT``):
# PYTHONPATH = ROOT puts ROOT's virtspec_mi ahead of the editable install, so the
# Mitsuba reading is ROOT's code while the bare kernel (self-contained, above) is the same
# on both sides. A worker compiles both kernels, runs each once at full size, then answers
# one JSON line per request on stdin ({"method", "rays"}) with one JSON line on its own
# stdout ({"seconds", "reflected"}); whatever else writes to stdout goes to its stderr.
# Workers use public API only (measure, instrument_scene, mitsuba; reading.reflected and
# reading.rays), which older revisions have too.

AGAINST_METHODS = ("Mitsuba", "bare Dr.Jit")


def mitsuba_reflected(scene: dict, rays: int) -> int:
    """Reflected count of one ``virtspec_mi.measure`` reading (public API only)."""

    import virtspec_mi

    reading = virtspec_mi.measure(scene, theta_i=THETA_I, phi_i=PHI_I, rays=rays, seed=SEED)
    if int(reading.rays[0]) != rays:
        raise RuntimeError(f"asked for {rays} rays, the reading traced {int(reading.rays[0])}")
    return int(reading.reflected[0])


def worker(root: Path, rays: int) -> int:
    """``--worker ROOT``: measure on request with ROOT's virtspec_mi (see the section comment)."""

    import virtspec_mi

    calls: dict = {}

    def warm() -> dict:
        scene = virtspec_mi.instrument_scene(BSDF)
        calls.update({"Mitsuba": partial(mitsuba_reflected, scene), "bare Dr.Jit": lambda n: drjit_counts(n)[0]})
        for call in calls.values():
            call(1000)  # compile
            call(rays)  # and one untimed call at full size
        return {"runtime": revisions.runtime()}

    def answer(request: dict) -> dict:
        start = time.perf_counter()
        reflected = calls[request["method"]](request["rays"])
        return {"seconds": time.perf_counter() - start, "reflected": reflected}

    revisions.serve(root, answer, warm)
    return 0


def against(revision: str, rays: int, rounds: int, markdown: bool) -> int:
    """Mitsuba and bare rays/s of the working tree and of ``revision``, interleaved; the ratios."""

    load_before = revisions.load_average()
    commit = revisions.resolve(revision)
    current = f"working tree ({revisions.describe_worktree()})"
    older = f"{revision} ({commit[:7]})"
    seconds: dict[tuple[str, str], list[float]] = {}
    reflected: dict[tuple[str, str], set[int]] = {}
    with revisions.worktree(commit) as checkout:
        sides: list[revisions.Worker] = []
        try:
            arguments = ("--rays", str(rays))
            sides += [revisions.Worker(current, ROOT, Path(__file__).resolve(), arguments),
                      revisions.Worker(older, checkout, Path(__file__).resolve(), arguments)]  # both warm up at once
            for side in sides:
                side.start()
            for _ in range(rounds):  # A B A B ...: a slow spell of the machine hits both revisions
                for side in sides:
                    for method in AGAINST_METHODS:
                        reply = side.ask(method=method, rays=rays)
                        seconds.setdefault((side.label, method), []).append(reply["seconds"])
                        reflected.setdefault((side.label, method), set()).add(reply["reflected"])
        finally:
            for side in sides:
                side.close()
    load_after = revisions.load_average()

    labels = [current, older]
    best = {key: rays / min(values) / 1e6 for key, values in seconds.items()}  # Mray/s
    ratio = {label: best[label, "Mitsuba"] / best[label, "bare Dr.Jit"] for label in labels}
    per_round = {label: [b / m for m, b in zip(seconds[label, "Mitsuba"], seconds[label, "bare Dr.Jit"])]
                 for label in labels}
    median = {label: statistics.median(values) for label, values in per_round.items()}
    rows = [[label, f"{best[label, 'Mitsuba']:.1f}", f"{best[label, 'bare Dr.Jit']:.1f}", f"{ratio[label]:.3f}",
             f"{median[label]:.3f} ({min(per_round[label]):.3f} - {max(per_round[label]):.3f})"]
            for label in labels]

    change, change_median = ratio[current] / ratio[older], median[current] / median[older]
    spread = max((max(values) - min(values)) / statistics.median(values) for values in per_round.values())
    if change >= 1.0:
        verdict_line = "the Mitsuba reading is at no less than its previous ratio to the bare kernel" + (
            "" if change > 1.0 + spread else " (a gain within the round-to-round spread)")
    elif change >= 1.0 - spread:
        verdict_line = ("below its previous ratio, by less than the round-to-round spread: not resolved at "
                        "this noise (more rays or --rounds)")
    else:
        verdict_line = "BELOW its previous ratio to the bare kernel, by more than the round-to-round spread"
    single = {key: next(iter(values)) if len(values) == 1 else None for key, values in reflected.items()}
    same = single[current, "Mitsuba"] is not None and single[current, "Mitsuba"] == single[older, "Mitsuba"]

    def bare_minus_mitsuba(label: str) -> str:
        bare, mitsuba = single[label, "bare Dr.Jit"], single[label, "Mitsuba"]
        return f"{label}: " + ("counts vary between rounds" if None in (bare, mitsuba) else f"{bare - mitsuba:+d}")

    info = {**revisions.cpu(), **sides[0].hello["runtime"], "date": revisions.now(),
            "load": f"{load_before:.2f} before the run, {load_after:.2f} after"}
    lines = [
        f"{rays:.0e} rays per reading (conical diamond, theta_i = {THETA_I:g}, one wavelength, seed {SEED}), warm; "
        f"{rounds} interleaved rounds (A B A B ...; per revision a Mitsuba reading, then the bare kernel); "
        f"Mray/s best of {rounds}; one worker process per revision; the bare kernel is the same code in both",
        f"ratio of ratios, working tree / {older}: {change:.3f} (of the per-round medians: {change_median:.3f}) "
        f"-> {verdict_line}; per-round ratios spread up to {100 * spread:.0f}%",
        "Mitsuba counts " + (f"identical in both revisions ({single[current, 'Mitsuba']:,} reflected of {rays:,})"
                             if same else "DIFFER between the revisions: " + "; ".join(
                                 f"{label}: {sorted(reflected[label, 'Mitsuba'])}" for label in labels)),
        "reflected, bare Dr.Jit - Mitsuba (same random numbers): " + ", ".join(map(bare_minus_mitsuba, labels)),
    ]
    lines += [f"{side.label}: virtspec_mi imported from {side.hello['virtspec_mi']} "
              f"(all {side.hello['modules']} loaded virtspec_mi modules under {side.root})" for side in sides]
    if sides[1].hello["runtime"] != sides[0].hello["runtime"]:
        lines.append(f"{older} ran with {sides[1].hello['runtime']}")
    lines.append(f"SIMD width: {revisions.simd(info)} (/proc/cpuinfo flags); 1-minute load average: {info['load']}")
    header = ["revision", "Mitsuba Mray/s", "bare Dr.Jit Mray/s", "Mitsuba / bare",
              "per-round ratios: median (min - max)"]
    print(format_markdown(rows, lines, info, header) if markdown else format_text(rows, lines, info, header))
    return 0


# --- report -------------------------------------------------------------------------------


def verdict(met: bool) -> str:
    return "met" if met else "NOT met"


def report_rows(runs: dict[tuple[str, int], Run], big: dict | None, warm: dict, cold: dict,
                small: int, large: int) -> tuple[list[list[str]], list[str]]:
    """The throughput table (rows of cells) and the lines of ratios, checks and targets."""

    rows = []
    for run in runs.values():
        rows.append([run.method, f"{run.rays:.0e}", f"{run.seconds:.3f}", f"{run.mrays:.1f}",
                     f"{run.reflectance:.6f}", f"best of {run.repeats}"])
    if big is not None:
        rows.append(["Mitsuba, fresh process", f"{big['rays']:.0e}", f"{big['seconds']:.3f}",
                     f"{big['rays'] / big['seconds'] / 1e6:.1f}", f"{big['reflectance']:.6f}",
                     f"peak RSS {big['peak_rss'] / 2**20:.0f} MiB"])

    mitsuba_small, mitsuba_large = runs["Mitsuba", small], runs["Mitsuba", large]
    bare_small, bare_large = runs["bare Dr.Jit", small], runs["bare Dr.Jit", large]
    numpy_run = runs["NumPy float64", small]
    r_m, r_n = mitsuba_small.reflectance, numpy_run.reflectance
    sigma = math.sqrt(r_m * (1 - r_m) * (1 / mitsuba_small.rays + 1 / numpy_run.rays))
    lines = [
        f"ratio Mitsuba / bare Dr.Jit: {mitsuba_small.mrays / bare_small.mrays:.2f} at {small:.0e}, "
        f"{mitsuba_large.mrays / bare_large.mrays:.2f} at {large:.0e} "
        f"(the issue: 300 vs 780 Mray/s = {TARGET_MRAYS / ISSUE_BARE_MRAYS:.2f})",
        f"ratio Mitsuba / NumPy: {mitsuba_small.mrays / numpy_run.mrays:.0f} at {small:.0e} "
        f"(the issue: 300 vs 4 Mray/s = {TARGET_MRAYS / ISSUE_NUMPY_MRAYS:.0f})",
        f"reflectance NumPy - Mitsuba at {small:.0e}: {r_n - r_m:+.2e} "
        f"({abs(r_n - r_m) / sigma:.1f} combined sigma, sigma = {sigma:.1e})",
        f"counts bare Dr.Jit - Mitsuba (same random numbers): reflected "
        f"{bare_small.reflected - mitsuba_small.reflected:+d} at {small:.0e}, "
        f"{bare_large.reflected - mitsuba_large.reflected:+d} at {large:.0e}",
        f"target >= {TARGET_MRAYS:.0f} Mray/s (Mitsuba reading): "
        f"{verdict(mitsuba_large.mrays >= TARGET_MRAYS)} ({mitsuba_large.mrays:.1f} Mray/s at {large:.0e}, "
        f"{mitsuba_small.mrays:.1f} at {small:.0e})",
    ]
    if big is not None:
        gib = big["peak_rss"] / 2**30
        lines.append(f"target <= {TARGET_PEAK_GIB:g} GiB peak RSS at {big['rays']:.0e} rays: "
                     f"{verdict(gib <= TARGET_PEAK_GIB)} ({gib:.3f} GiB = {big['peak_rss'] / 2**20:.0f} MiB, "
                     f"{big['seconds']:.2f} s, {big['rays'] / big['seconds'] / 1e6:.1f} Mray/s)")
    else:
        lines.append("target <= 1 GiB peak RSS at 1e9 rays: not measured (--quick)")
    lines += [
        f"target <= {TARGET_WARM_MS:g} ms warm certified reading ({warm['rays']:,} rays): "
        f"{verdict(warm['median_ms'] <= TARGET_WARM_MS)} (median {warm['median_ms']:.2f} ms, "
        f"min {warm['min_ms']:.2f} ms of {warm['repeats']})",
        f"target <= {TARGET_COLD_S:g} s cold process: {verdict(cold['median_s'] <= TARGET_COLD_S)} "
        f"(median {cold['median_s']:.2f} s; runs " + ", ".join(f"{t:.2f}" for t in cold["runs_s"]) + " s)",
    ]
    return rows, lines


HEADER = ["method", "rays", "seconds", "Mray/s", "reflectance", "note"]


def format_text(rows: list[list[str]], lines: list[str], info: dict, header: list[str] = HEADER) -> str:
    widths = [max(len(row[i]) for row in [header, *rows]) for i in range(len(header))]
    fmt = lambda row: "  ".join(cell.ljust(w) for cell, w in zip(row, widths)).rstrip()  # noqa: E731
    out = [fmt(header), fmt(["-" * w for w in widths]), *map(fmt, rows), ""]
    out += lines
    out += ["", *machine_lines(info)]
    return "\n".join(out)


def format_markdown(rows: list[list[str]], lines: list[str], info: dict, header: list[str] = HEADER) -> str:
    out = ["| " + " | ".join(header) + " |", "|" + "|".join("---" for _ in header) + "|"]
    out += ["| " + " | ".join(row) + " |" for row in rows]
    out += [""] + [f"- {line}" for line in lines] + [""] + [f"- {line}" for line in machine_lines(info)]
    return "\n".join(out)


# --- main ---------------------------------------------------------------------------------


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true",
                        help="10^6 / 10^7 rays and no 10^9-ray subprocess (a smoke run)")
    parser.add_argument("--markdown", action="store_true", help="print the results as markdown")
    parser.add_argument("--against", metavar="REV",
                        help="only compare the Mitsuba / bare Dr.Jit ratio of the working tree with that of "
                             "git revision REV, side by side (10^8 rays, 10^7 with --quick)")
    parser.add_argument("--rounds", type=int, help="interleaved rounds of --against (default 7; 10 with --quick)")
    parser.add_argument("--worker", metavar="ROOT", type=Path, help=argparse.SUPPRESS)
    parser.add_argument("--rays", type=int, help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.worker is not None:
        return worker(args.worker, args.rays)
    if args.against is not None:
        rounds = args.rounds or (10 if args.quick else 7)
        return against(args.against, 10**7 if args.quick else 10**8, max(rounds, 1), args.markdown)
    small, large = (10**6, 10**7) if args.quick else (10**7, 10**8)
    load_before = os.getloadavg()[0]  # other work on the machine skews every figure

    # First, while this process is small and has spawned nothing (see big_reading).
    big = None if args.quick else big_reading(10**9)

    import virtspec_mi

    virtspec_mi.mitsuba()
    scene = virtspec_mi.instrument_scene(BSDF)
    mitsuba_counts(scene, 1000)  # compile the reading's kernel
    drjit_counts(1000)  # and the bare one
    numpy_counts(1000)  # and warm NumPy up too
    methods = {"Mitsuba": partial(mitsuba_counts, scene), "bare Dr.Jit": drjit_counts,
               "NumPy float64": numpy_counts}
    runs: dict[tuple[str, int], Run] = {}
    for method, count, repeats in [("Mitsuba", small, 3), ("Mitsuba", large, 2),
                                   ("bare Dr.Jit", small, 3), ("bare Dr.Jit", large, 2),
                                   ("NumPy float64", small, 1)]:
        seconds, reflected, transmitted = best_of(repeats, partial(methods[method], count))
        runs[method, count] = Run(method, count, seconds, reflected, transmitted, repeats)
    warm = warm_reading()
    cold = cold_process()

    rows, lines = report_rows(runs, big, warm, cold, small, large)
    info = machine()
    info["load"] = f"{load_before:.2f} before the run, {os.getloadavg()[0]:.2f} after"
    print(format_markdown(rows, lines, info) if args.markdown else format_text(rows, lines, info))
    return 0


if __name__ == "__main__":
    sys.exit(main())
