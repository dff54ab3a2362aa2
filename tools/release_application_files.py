"""
Write one result of every application kind in every format it writes, with the package on PYTHONPATH (a release's
files for tests): ``python tools/release_application_files.py OUT``.

The sibling of tools/release_result_files.py (the instruments' kinds). Each file is what the release's own writer
writes, byte for byte: ``DerivedResult`` and ``DerivedSweep`` as ``virtspec measure|sweep --target --json`` prints
them (``json.dumps(as_dict())``), ``FitResult.write`` (``.json``, ``.nc``), ``AlbedoTable.write`` (``.nc``;
``.npy`` with ``NAME_avg.npy`` and its ``NAME.json`` sidecar; ``.h``), ``KlemsMeasurement.write`` (``.xml`` and its
``.nc`` sidecar), ``Comparison`` as ``virtspec compare --json`` prints it; a ``TableComparison`` was printed only
(its summary: in the manifest). ``manifest.json`` names the commit that wrote them, each file's writer, and what
each result held (its ``as_dict()`` or, for the kinds without one, its counts and settings), canonical JSON.
A few hundred rays each: the files are small.
"""
import json
import subprocess
import sys
from pathlib import Path

import numpy as np

import virtspec_mi as vm


def canonical(data):
    return json.dumps(data, sort_keys=True, default=lambda v: np.asarray(v).tolist())


out = Path(sys.argv[1])
out.mkdir(parents=True, exist_ok=True)
commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True,
                        cwd=Path(vm.__file__).parents[1]).stdout.strip()
manifest = {"commit": commit, "files": {}, "held": {}}


def written(name, kind, writer, held):
    manifest["files"][name] = {"class": kind, "writer": writer}
    manifest["held"].setdefault(kind, held)


# certified targets: `virtspec measure --target --json` and `virtspec sweep --target --json` print json.dumps(as_dict())
derived = vm.measure("soybean_abmb", target=vm.band("B04", tolerance=0.05, step=10), seed=1)
(out / "derived.json").write_text(json.dumps(derived.as_dict()) + "\n")
written("derived.json", "DerivedResult", "virtspec measure --target --json (json.dumps(as_dict()))",
        canonical(derived.as_dict()))
sweep = vm.sweep("soybean_abmb", theta_i=[0, 40], target=vm.index("NDVI", tolerance=0.1, step=15), seed=2)
(out / "derived_sweep.json").write_text(json.dumps(sweep.as_dict()) + "\n")
written("derived_sweep.json", "DerivedSweep", "virtspec sweep --target --json (json.dumps(as_dict()))",
        canonical(sweep.as_dict()))

# a fit: FitResult.write (.json, .nc)
rough = vm.instrument_scene({"type": "roughdielectric", "alpha": 0.3, "int_ior": 1.5})
reading = vm.measure(rough, wavelengths=[450, 550, 650], rays=2000, seed=3)
measured = {"reflectance": (np.array([450.0, 550.0, 650.0]), reading.reflectance, np.full(3, 0.05))}
fit = vm.fit(measured, rough, {"specimen.alpha": (0.1, 0.6)}, evaluations=(4, 2, 1), profile_points=2,
             table_points=3, seed=4, delta=0.1, beam="collimated")
for suffix in (".json", ".nc"):
    fit.write(out / f"fit{suffix}")
    written(f"fit{suffix}", "FitResult", "FitResult.write", canonical(fit.as_dict()))

# an albedo table: AlbedoTable.write (.nc, .npy + NAME_avg.npy + NAME.json, .h)
from virtspec_mi.applications.tables.albedo import albedo_table  # noqa: E402

table = albedo_table("conductor", engine=None, mu=[1.0, 0.4], alpha=[0.3, 0.8], epsilon=0.1, seed=5, progress=False)
table_held = canonical({"description": table.description(), "counts": table.counts,
                        "average_counts": table.average_counts, "E": table.E, "E_avg": table.E_avg})
for suffix in (".nc", ".npy", ".h"):
    table.write(out / f"albedo{suffix}")
    written(f"albedo{suffix}", "AlbedoTable", "AlbedoTable.write", table_held)
for companion in ("albedo_avg.npy", "albedo.json"):
    written(companion, "AlbedoTable", "AlbedoTable.write (a .npy's companion)", table_held)
published = table.layout() + np.array([[0.0, 0.5], [0.0, 0.0]])  # one planted cell outside
comparison = table.compare(published)
manifest["table_comparison"] = {"class": "TableComparison", "writer": "printed only (virtspec albedo-table "
                                "--compare): no file", "summary": comparison.summary(), "outside": comparison.outside}

# Klems matrices: KlemsMeasurement.write (.xml and its .nc sidecar)
from virtspec_mi.applications.klems.measure import klems_measure  # noqa: E402

klems = klems_measure(rough, basis="quarter", epsilon=0.15, back=False, seed=6)
klems.write(out / "klems.xml")
klems_held = canonical({"counts": klems.counts, "rays": klems.rays, "reflected": klems.reflected,
                        "transmitted": klems.transmitted, "epsilon": klems.epsilon, "delta": klems.delta,
                        "sides": klems.sides, "wavelengths": klems.wavelengths, "basis": klems.basis.key})
for name in ("klems.xml", "klems.nc"):
    written(name, "KlemsMeasurement", "KlemsMeasurement.write", klems_held)

# a comparison: `virtspec compare --json` prints json.dumps(as_dict())
compared = vm.compare(reading, (np.array([400.0, 500.0, 700.0]), np.array([0.05, 0.06, 0.07]), 0.02))
(out / "comparison.json").write_text(json.dumps(compared.as_dict()) + "\n")
written("comparison.json", "Comparison", "virtspec compare --json (json.dumps(as_dict()))",
        canonical(compared.as_dict()))

(out / "manifest.json").write_text(json.dumps(manifest, indent=1, default=lambda v: np.asarray(v).tolist()) + "\n")
print("written", sorted(p.name for p in out.iterdir()))
