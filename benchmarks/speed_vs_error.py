"""
Speed versus error of the four ray budgets (issue 5).

For each bound (hoeffding, chebyshev, exact, two-stage) and each specimen of exactly
known reflectance rho, take K independent readings in one batched trace_readings call
(virtspec_mi.applications.coverage.coverage) at mu = 0.005, delta = 0.01 and report: rays per
reading (behind the estimate, and spent, pilot included), seconds, |error| against
rho, the observed miss rate |m/N - rho| >= mu with its 95 % Clopper-Pearson interval,
the exact miss probability q and the two-sided binomial test of the miss count.
Writes a Markdown table and a PNG plot; prints the issue's targets beside the figures.

    .venv/bin/python benchmarks/speed_vs_error.py            # K = 400 readings per cell
    .venv/bin/python benchmarks/speed_vs_error.py --quick    # K = 100

``run_cells``, ``markdown_table`` and ``plot`` are also used by notebooks/07_speed_vs_error.ipynb.
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np

import virtspec_mi
from virtspec_mi.applications import coverage as validation
from virtspec_mi.budgets import bounds
from virtspec_mi.references.quadrature import fresnel_reflectance
from virtspec_mi.budgets.twostage import two_stage_law

BOUNDS = ("hoeffding", "chebyshev", "exact", "two-stage")
HERE = Path(__file__).resolve().parent


def specimens() -> list[validation.Specimen]:
    def diffuse(albedo: float) -> validation.Specimen:
        return validation.Specimen(f"diffuse {albedo:g}", {"type": "diffuse", "reflectance": albedo}, 30.0,
                                   "collimated", albedo, "absorbed")

    def diamond(theta: float) -> validation.Specimen:
        return validation.Specimen(f"diamond {theta:g} deg", {"type": "simple_dielectric", "eta": 2.419}, theta,
                                   "collimated", float(fresnel_reflectance(theta, 2.419)), "transmitted")

    return [diffuse(0.05), diamond(0.0), diffuse(0.2), diamond(80.0), diffuse(0.5),
            validation.Specimen("absorber", {"type": "diffuse", "reflectance": 0.0}, 30.0, "collimated", 0.0,
                                "absorbed")]


def machine() -> str:
    model = next((line.split(":", 1)[1].strip() for line in open("/proc/cpuinfo") if line.startswith("model name")),
                 platform.processor())
    return f"{model}, {os.cpu_count()} cores, Python {platform.python_version()}"


def run_cells(cells: list[validation.Specimen], k: int, mu: float, delta: float, seed: int,
              budgets: tuple[str, ...] = BOUNDS, log=sys.stderr) -> list[tuple[validation.Specimen, validation.Coverage]]:
    """K readings of every (specimen, bound) cell through ``validation.coverage`` (kernels warmed first)."""

    rows = []
    for specimen in cells:
        # warm the specimen's kernels (JIT compilation is not part of a reading's cost)
        validation.coverage(specimen, "hoeffding", mu=mu, delta=delta, readings=4, seed=1)
        for bound in budgets:
            result = validation.coverage(specimen, bound, mu=mu, delta=delta, readings=k, seed=seed)
            rows.append((specimen, result))
            if log is not None:
                print(f"{specimen.name:>14} {bound:>10}: {result.rays_spent:>11,.0f} rays/reading, "
                      f"{result.seconds:6.2f} s, misses {result.misses}/{k} "
                      f"(q K = {result.miss_probability * k:.2f})", file=log, flush=True)
    return rows


def markdown_table(rows: list, k: int) -> list[str]:
    """The report's Markdown table, one line per (specimen, bound) cell."""

    header = ("| specimen | rho | bound | rays/reading (estimate) | rays spent | x Hoeffding | s per reading (ms) "
              "| mean abs error | max abs error | misses / K | miss rate 95 % CI | exact q | binomial p | ok |")
    lines = [header, "|" + "---|" * (header.count("|") - 1)]
    hoeffding = {s.name: r.rays_spent for s, r in rows if r.bound == "hoeffding"}
    for specimen, r in rows:
        ok = r.passed() and r.within_delta
        lines.append(
            f"| {specimen.name} | {specimen.reflectance:.4f} | {r.bound} | {r.rays:,.0f} | {r.rays_spent:,.0f} "
            f"| {r.rays_spent / hoeffding[specimen.name]:.3f} | {1e3 * r.seconds / k:.3f} | {r.mean_abs_error:.2e} "
            f"| {r.max_abs_error:.2e} | {r.misses}/{k} | [{r.miss_interval[0]:.4f}, {r.miss_interval[1]:.4f}] "
            f"| {r.miss_probability:.2e} | {r.pvalue:.3f} | {'yes' if ok else 'NO'} |"
        )
    return lines


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument("--quick", action="store_true", help="K = 100 readings per cell")
    parser.add_argument("--readings", type=int, help="K readings per (bound, specimen)")
    parser.add_argument("--mu", type=float, default=0.005)
    parser.add_argument("--delta", type=float, default=0.01)
    parser.add_argument("--seed", type=int, default=2026)
    parser.add_argument("--out", type=Path, default=HERE, help="folder for speed_vs_error.{md,png}")
    args = parser.parse_args(argv)
    k = args.readings or (100 if args.quick else 400)
    mu, delta = args.mu, args.delta
    virtspec_mi.mitsuba()
    load = os.getloadavg()[0]
    started = time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())
    rows = run_cells(specimens(), k, mu, delta, args.seed)
    lines = markdown_table(rows, k)
    exact_ratio = bounds.exact_rays(mu, delta) / bounds.hoeffding_rays(mu, delta)
    laws = {rho: two_stage_law(rho, mu, delta) for rho in (0.05, 0.5)}
    measured = {s.reflectance: r.rays_spent for s, r in rows if r.bound == "two-stage"}
    h = bounds.hoeffding_rays(mu, delta)
    targets = [
        f"- exact / Hoeffding rays: {exact_ratio:.4f} ({bounds.exact_rays(mu, delta):,} / {h:,}); target 0.63: "
        f"{'met' if round(exact_ratio, 2) <= 0.63 else 'NOT met'}",
        f"- Hoeffding / two-stage rays at rho = 0.05: {h / measured[0.05]:.2f} measured (mean of {k}), "
        f"{h / laws[0.05].expected_rays:.2f} exact expectation ({laws[0.05].expected_rays:,.0f} rays); target >= 4: "
        f"{'met' if h / measured[0.05] >= 4 else 'NOT met'}",
        f"- Hoeffding / two-stage rays at rho = 0.5: {h / measured[0.5]:.2f} measured, "
        f"{h / laws[0.5].expected_rays:.2f} exact expectation ({laws[0.5].expected_rays:,.0f} rays); target >= 1.4: "
        f"{'met' if h / measured[0.5] >= 1.4 else 'NOT met'}",
        f"- miss rates consistent with <= delta = {delta:g} (95 % CI reaches below delta) and with the exact "
        f"law (two-sided binomial p > 1e-4) in every cell: "
        f"{'yes' if all(r.passed() and r.within_delta for _, r in rows) else 'NO'}",
    ]
    footer = [
        f"- command: benchmarks/speed_vs_error.py {' '.join(argv if argv is not None else sys.argv[1:])}".rstrip(),
        f"- mu = {mu:g}, delta = {delta:g}, K = {k} readings per cell (one trace_readings call each), seed {args.seed}",
        f"- date: {started}; machine: {machine()}",
        f"- load average (1 min): {load:.2f} before the run, {os.getloadavg()[0]:.2f} after",
    ]
    text = "\n".join(lines + [""] + targets + [""] + footer)
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "speed_vs_error.md").write_text(text + "\n")
    plot(rows, k, delta, args.out / "speed_vs_error.png")
    print(text)
    return 0


def plot(rows: list, k: int, delta: float, path: Path | None = None, dpi: int = 110):
    """Rays per reading and observed miss rate of each cell; saved to ``path`` when given."""

    from matplotlib.figure import Figure

    fig = Figure(figsize=(12, 4.5))
    left, right = fig.subplots(1, 2)
    names = list(dict.fromkeys(s.name for s, _ in rows))
    x = np.arange(len(names))
    for i, bound in enumerate(BOUNDS):
        cells = [r for _, r in rows if r.bound == bound]
        offset = (i - 1.5) * 0.2
        left.bar(x + offset, [r.rays_spent for r in cells], 0.2, label=bound)
        rate = np.array([r.misses / k for r in cells])
        lo = rate - np.array([r.miss_interval[0] for r in cells])
        hi = np.array([r.miss_interval[1] for r in cells]) - rate
        right.errorbar(x + offset, rate, yerr=[lo, hi], fmt="o", capsize=3, label=f"{bound} observed")
        right.scatter(x + offset, [r.miss_probability for r in cells], marker="x", color="k", s=20,
                      label="exact q" if i == 0 else None, zorder=3)
    left.set_yscale("log")
    left.set_ylabel("rays per reading (spent)")
    right.axhline(delta, color="r", linestyle="--", label=f"delta = {delta:g}")
    right.set_ylabel(f"miss rate |m/N - rho| >= mu (K = {k}, 95 % CI)")
    for axis in (left, right):
        axis.set_xticks(x, [n.replace(" deg", "°") for n in names], rotation=20)
    left.legend(fontsize=8)
    right.legend(fontsize=7, ncol=2)
    fig.suptitle("Ray budgets: rays per reading and observed miss rate")
    fig.tight_layout()
    if path is not None:
        fig.savefig(path, dpi=dpi)
    return fig


if __name__ == "__main__":
    sys.exit(main())
