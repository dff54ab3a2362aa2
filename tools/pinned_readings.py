"""
Readings of every pinned case, this tree against a git revision, within their certificates
==========================================================================================

When a change alters the random stream of some rays (a new walk generator, issue 25), the
counts pinned by ``tests/test_pinned_counts.py`` and ``tests/test_pinned_instruments.py``
are written again; this shows that nothing but the random stream changed. Every case of
those tests' ``CASES`` is measured with the working tree and with a throwaway checkout of
``--against REV`` (default ``main``), each in a worker process running its own tree's code
(``benchmarks/revisions.py``: ``Worker``, ``serve``), and every certified quantity of a
reading is checked:

    |x_old − x_new| ≤ μ_old + μ_new,

with μ its certified tolerance in each tree (each holds with probability ≥ 1 − δ, so both
together with ≥ 1 − 2δ):

- spectrophotometer readings (``measure``, ``sweep``, ``mi.render``): R and T, μ =
  ``Result.certified_mu`` (the rule's tolerance of the reading's N at its δ);
- goniophotometer readings: R and T as above, and every bin fraction m_k/N with μ =
  ``GonioResult.bins_mu`` (simultaneous over the bins);
- integrating-sphere readings: the detector fraction and the hemispherical fraction of the
  specimen's rays, μ = ``SphereResult.fraction_mu`` (Hoeffding's μ of their N at δ/2).

A reading without a certificate (weight violations: μ is NaN) must be identical in both
trees. A case whose counts are unchanged is marked ``identical``. Exit status 1 when any
reading falls outside the sum of its certificates.

Usage::

    python tools/pinned_readings.py                  # against main
    python tools/pinned_readings.py --against HEAD~1
"""

from __future__ import annotations

import argparse
import importlib.util
import sys
import warnings
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))

from revisions import Worker, describe_worktree, serve, within_certificates, worktree  # noqa: E402

__all__ = ["PINNED_TESTS", "reading", "main"]


PINNED_TESTS = ("test_pinned_counts.py", "test_pinned_instruments.py")
"""The test files whose ``CASES`` are compared (both exist since issue 21)."""


def _pinned_cases(root: Path) -> dict[str, tuple[Any, str, dict]]:
    """Every pinned case of the tree at ``root``: name → (its test module, kind, settings)."""

    cases = {}
    for name in PINNED_TESTS:
        path = root / "tests" / name
        if not path.exists():
            continue
        spec = importlib.util.spec_from_file_location(path.stem, path)
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        cases.update({case: (module, *value) for case, value in module.CASES.items()})
    return cases


def _flat(values: Any) -> list[float]:
    return np.asarray(values, dtype=np.float64).reshape(-1).tolist()


def reading(pinned: Any, kind: str, spec: dict) -> dict[str, Any]:
    """
    The certified quantities of one pinned case, as its test runs it: ``{"values": {name:
    (x, μ) flattened over the readings}, "counts": …}``.
    """

    import virtspec_mi as vm

    spec = dict(spec)
    scene = str(pinned.SCENES / spec.pop("scene")) if "scene" in spec else vm.instrument_scene(spec.pop("bsdf"))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the built-ins with weights > 1 warn, as in the test
        if kind == "sphere":
            sphere = vm.sphere_measure(scene, **spec)
            mu = _flat(sphere.fraction_mu)
            return {"values": {"detector": (_flat(sphere.detector_fraction), mu),
                               "hemispherical": (_flat(sphere.hemispherical), mu)},
                    "counts": {f"{config}.{name}": _flat(values) for config, counts in sorted(sphere.counts.items())
                               for name, values in sorted(counts.items())}}
        if kind == "gonio":
            gonio = vm.gonio(scene, **spec)
            result = gonio.result
            fraction = np.asarray(gonio.fraction, dtype=np.float64)
            per_bin = np.broadcast_to(np.asarray(gonio.bins_mu, dtype=np.float64)[..., None, None], fraction.shape)
            extra = {"bins": (_flat(fraction), _flat(per_bin))}
            counts = {"bins": _flat(gonio.bin_counts)}
        elif kind == "render":
            mi = vm.mitsuba()
            loaded = mi.load_file(scene)
            mi.render(loaded, seed=spec["seed"], spp=spec["spp"])
            result, extra, counts = loaded.integrator().last_reading, {}, {}
        elif kind == "sweep":
            result, extra, counts = vm.sweep(scene, progress=False, **spec), {}, {}
        else:
            result, extra, counts = vm.measure(scene, **spec), {}, {}
    mu = _flat(result.certified_mu)
    counts.update({name: _flat(getattr(result, name)) for name in ("reflected", "transmitted", "capped")})
    return {"values": {"R": (_flat(result.reflectance), mu), "T": (_flat(result.transmittance), mu), **extra},
            "counts": counts}


def worker(root: str) -> None:
    """Answer ``{"case": name}`` requests with :func:`reading` of that pinned case, in ``root``'s tree."""

    cases = _pinned_cases(Path(root))
    serve(Path(root), lambda request: reading(*cases[request["case"]]))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[1])
    parser.add_argument("--against", default="main", metavar="REV", help="the revision to compare with")
    parser.add_argument("--worker", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.worker:
        worker(args.worker)
        return 0
    cases = _pinned_cases(ROOT)
    script, rows, failed = Path(__file__).resolve(), [], []
    with worktree(args.against) as old_root:
        trees = {"old": Worker(args.against, old_root, script), "new": Worker(describe_worktree(), ROOT, script)}
        try:
            for tree in trees.values():
                tree.start()
            for case in sorted(cases):
                old, new = (trees[label].ask(case=case) for label in ("old", "new"))
                inside, largest, allowance = within_certificates(old["values"], new["values"])
                same = old["counts"] == new["counts"]
                if not inside:
                    failed.append(case)
                readings = len(next(iter(old["values"].values()))[0])
                rows.append(f"| {case} | {readings} | {'identical' if same else 'changed'} | {largest:.5f} | "
                            f"{'none certified' if np.isnan(allowance) else f'{allowance:.5f}'} | "
                            f"{'yes' if inside else 'NO'} |")
        finally:
            for tree in trees.values():
                tree.close()
    print(f"Pinned cases: {args.against} (old) against {describe_worktree()} (new); per reading and certified "
          "quantity x (R, T; bin fractions; sphere detector and hemispherical fractions): "
          "|x_old - x_new| <= mu_old + mu_new")
    print()
    print("| case | readings | counts | largest abs(dx) | smallest mu_old + mu_new | within |")
    print("|---|---|---|---|---|---|")
    print("\n".join(rows))
    print()
    print(f"{len(rows) - len(failed)} of {len(rows)} cases within their certificates"
          + (f"; outside: {', '.join(failed)}" if failed else ""))
    return 1 if failed else 0


if __name__ == "__main__":
    raise SystemExit(main())
