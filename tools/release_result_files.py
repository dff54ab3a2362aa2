"""Write one result of every instrument in every format with the package on PYTHONPATH (a release's files for tests)."""
import json, subprocess, sys
from pathlib import Path
import numpy as np
import virtspec_mi as vm

out = Path(sys.argv[1]); out.mkdir(parents=True, exist_ok=True)
rough = vm.instrument_scene({"type": "roughdielectric", "alpha": 0.3, "int_ior": 1.5})
results = {
    "reading": vm.measure("soybean_abmb", wavelengths=[450, 650], rays=500, seed=1),
    "sweep": vm.sweep(rough, wavelengths=[500, 600], theta_i=[0, 40], rays=400, seed=2,
                      parameters={"specimen.alpha": [0.2, 0.4]}),
    "gonio": vm.gonio(rough, wavelengths=[550], theta_i=[30], rays=400, theta_o_bins=3, phi_o_bins=4, seed=3),
    "sphere": vm.sphere_measure("sphere_150mm_8d", wavelengths=[450, 650], rays=400, seed=4),
    "gloss": vm.take("gloss", vm.instrument_scene({"type": "simple_dielectric", "eta": 1.5}), theta_i=60,
                     beam="collimated", wavelengths=[550], rays=400, cone=1, seed=5),
}
manifest = {"commit": subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True,
                                     cwd=Path(vm.__file__).parents[1]).stdout.strip(), "files": {}}
for name, result in results.items():
    for suffix in (".nc", ".csv", ".json") + ((".zarr",) if name == "sweep" else ()):
        path = result.write(out / f"{name}{suffix}")
        manifest["files"][path.name] = {"format": type(result).FORMAT, "class": type(result).__name__}
    manifest[name] = json.dumps(result.as_dict(), sort_keys=True, default=lambda v: np.asarray(v).tolist())
(out / "manifest.json").write_text(json.dumps(manifest, indent=1, default=lambda v: np.asarray(v).tolist()))
print("written", sorted(p.name for p in out.iterdir()))
