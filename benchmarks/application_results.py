"""
The cost of the applications' result kinds: built, shown, as plain data
=======================================================================

Issue 38 item 3 made the applications' results (a certified target, a fit, an albedo
table and its comparison, Klems matrices, a comparison) kinds of the one result family.
This times, in one process, what such a result costs beside the work that fills it:

1. **build**: the result from its fields (``dataclasses.replace(result)``: what a fit, a
   target or a table does once per call; a fit's forward readings are instrument results,
   timed by ``benchmarks/result_type.py``);
2. **summary**: ``result.summary()`` (``statement()`` for a table);
3. **as_dict**: its plain data (the JSON a file holds), where it has one.

Each figure is the best of ``--repeat`` runs of ``--number`` calls, in µs per call. Run
it once with each tree first on ``PYTHONPATH`` to compare two trees::

    PYTHONPATH=. .venv/bin/python benchmarks/application_results.py
"""

from __future__ import annotations

import argparse
import dataclasses
import timeit

import numpy as np


def results() -> dict:
    import virtspec_mi as vm
    from virtspec_mi.applications.tables.albedo import albedo_table

    rough = vm.instrument_scene({"type": "roughdielectric", "alpha": 0.3, "int_ior": 1.5})
    reading = vm.measure(rough, wavelengths=[450, 550, 650], rays=2000, seed=3)
    measured = {"reflectance": (np.array([450.0, 550.0, 650.0]), reading.reflectance, np.full(3, 0.05))}
    table = albedo_table("conductor", engine=None, mu=[1.0, 0.4], alpha=[0.3, 0.8], epsilon=0.1, seed=5,
                         progress=False)
    from virtspec_mi.applications.klems.measure import klems_measure

    return {
        "DerivedResult": vm.measure("soybean_abmb", target=vm.band("B04", tolerance=0.05, step=10), seed=1),
        "FitResult": vm.fit(measured, rough, {"specimen.alpha": (0.1, 0.6)}, evaluations=(4, 2, 1), profile_points=2,
                            table_points=3, seed=4, delta=0.1, beam="collimated"),
        "AlbedoTable": table,
        "TableComparison": table.compare(table.layout()),
        "KlemsMeasurement": klems_measure(rough, basis="quarter", epsilon=0.15, back=False, seed=6),
        "Comparison": vm.compare(reading, (np.array([400.0, 500.0, 700.0]), np.array([0.05, 0.06, 0.07]), 0.02)),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--number", type=int, default=200)
    parser.add_argument("--repeat", type=int, default=5)
    args = parser.parse_args()
    print(f"{'kind':<18}{'build us':>12}{'summary us':>12}{'as_dict us':>12}")
    for name, result in results().items():
        def best(call) -> float:
            return min(timeit.repeat(call, number=args.number, repeat=args.repeat)) / args.number * 1e6

        build = best(lambda: dataclasses.replace(result)) if dataclasses.is_dataclass(result) else float("nan")
        summary = best(result.statement if name in ("AlbedoTable", "KlemsMeasurement") else result.summary)
        plain = best(result.as_dict) if hasattr(result, "as_dict") else float("nan")
        print(f"{name:<18}{build:12.1f}{summary:12.1f}{plain:12.1f}")


if __name__ == "__main__":
    main()
