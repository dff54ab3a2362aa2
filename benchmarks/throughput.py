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
   counts) with no Mitsuba BSDF or SurfaceInteraction; chunks of 2²², every
   per-call scalar passed with ``dr.opaque`` so the kernel is compiled once.
   It draws the same random numbers as (1), so its counts should equal (1)'s up
   to float rounding of F.

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

The full run takes 15-30 s on a 2-core machine (the 10⁹-ray reading ~5 s, NumPy
~2-3 s, the rest is repeats and process start-ups); other work on the machine
slows every figure, so the 1-minute load average is printed with the results.
"""

from __future__ import annotations

import argparse
import datetime
import json
import math
import os
import platform
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


def drjit_chunk(first: int, size: int, strata: int) -> tuple[int, int]:
    """
    Counts of rays [first, first + size) of one reading as one bare Dr.Jit kernel.

    Same random numbers as the integrator (dimensions 0–1 emitter, 2–3 specimen,
    4 the Fresnel coin), same jittered polar warp and rotation; no Mitsuba BSDF.
    """

    import drjit as dr
    import virtspec_mi
    from virtspec_mi.geometry import jittered_cell, polar_warp
    from virtspec_mi.rng import chunk_root, dimension_keys, hash32, to_unit

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


def machine() -> dict:
    """CPU model, cores, SIMD flags, Dr.Jit threads, libLLVM, versions and the date (UTC)."""

    import drjit as dr
    import mitsuba

    model, flags = platform.processor() or "unknown", set()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            key, _, value = line.partition(":")
            if key.strip() == "model name":
                model = value.strip()
            elif key.strip() == "flags":
                flags = set(value.split())
    except OSError:
        pass
    return {
        "cpu": model,
        "cores": os.cpu_count(),
        "avx2": "avx2" in flags,
        "avx512": any(flag.startswith("avx512") for flag in flags),
        "threads": dr.thread_count(),
        "llvm": ".".join(map(str, dr.detail.llvm_version())),
        "versions": f"drjit {dr.__version__}, mitsuba {mitsuba.__version__}, numpy {np.__version__}, "
                    f"python {platform.python_version()}",
        "date": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
    }


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


def format_text(rows: list[list[str]], lines: list[str], info: dict) -> str:
    widths = [max(len(row[i]) for row in [HEADER, *rows]) for i in range(len(HEADER))]
    fmt = lambda row: "  ".join(cell.ljust(w) for cell, w in zip(row, widths)).rstrip()  # noqa: E731
    out = [fmt(HEADER), fmt(["-" * w for w in widths]), *map(fmt, rows), ""]
    out += lines
    out += ["", *machine_lines(info)]
    return "\n".join(out)


def format_markdown(rows: list[list[str]], lines: list[str], info: dict) -> str:
    out = ["| " + " | ".join(HEADER) + " |", "|" + "|".join("---" for _ in HEADER) + "|"]
    out += ["| " + " | ".join(row) + " |" for row in rows]
    out += [""] + [f"- {line}" for line in lines] + [""] + [f"- {line}" for line in machine_lines(info)]
    return "\n".join(out)


def machine_lines(info: dict) -> list[str]:
    return [
        f"command: {' '.join(sys.argv)}",
        f"date: {info['date']}",
        f"machine: {info['cpu']}, {info['cores']} cores, AVX2 {'yes' if info['avx2'] else 'no'}, "
        f"AVX-512 {'yes' if info['avx512'] else 'no'}; Dr.Jit threads {info['threads']}; "
        f"libLLVM {info['llvm']}",
        f"versions: {info['versions']}",
        f"load average (1 min): {info['load']}",
    ]


# --- main ---------------------------------------------------------------------------------


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true",
                        help="10^6 / 10^7 rays and no 10^9-ray subprocess (a smoke run)")
    parser.add_argument("--markdown", action="store_true", help="print the results as markdown")
    args = parser.parse_args(argv)
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
