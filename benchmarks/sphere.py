"""
Integrating-sphere speed (issue 16): the sphere walk against the hemispherical reading of
the same specimen, in one run.

- rays/s and wall reflections/s of one sphere configuration (8°/d SCI, 150 mm sphere of
  ``scenes/sphere_150mm_8d.xml`` with its baffle, grey Lambertian sample ρ = 0.5, ρw = 0.98)
  beside the rays/s of ``vm.measure`` of the same specimen and beam;
- the warm time of a certified 8°/d SCI reading of that sample at ρw = 0.98 with 105,967 rays
  per configuration: one configuration (the sample's detector fraction) and the whole
  readout (sample and standard);
- the cost of correcting that reading by the sphere theory (``SphereResult.corrected`` and
  ``corrected_interval``: closed-form NumPy, no rays);
- ``--spectrum``: the certified SCI spectrum 400–2500 nm / 5 nm (421 wavelengths) of that
  grey sample, both configurations, under each ray budget (``hoeffding`` at δ/2 per
  configuration, ``two-stage`` on each configuration's detector fraction): wall time,
  rays traced, rays/s (issue 21's target: ≤ 3 s on 2 cores).

Run: python benchmarks/sphere.py [--repeat K] [--spectrum]
"""

from __future__ import annotations

import argparse
import time

import virtspec_mi as vm

SCENE = "scenes/sphere_150mm_8d.xml"


def best(function, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        function()
        times.append(time.perf_counter() - start)
    return min(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--rays", type=int, default=105_967)
    parser.add_argument("--spectrum", action="store_true", help="the certified SCI spectrum 400-2500/5 nm only")
    args = parser.parse_args()
    if args.spectrum:
        spectrum(args.repeat)
        return
    from virtspec_mi.engine.plan import kernel_options
    from virtspec_mi.instruments.sphere import configurations
    from virtspec_mi.kernel.tracer import ReadingPlan, tally_readings
    from virtspec_mi.runtime.scene import find_bench

    mi = vm.mitsuba()
    scene = mi.load_file(SCENE)
    integrator = scene.integrator()
    instrument = find_bench(scene)
    settings = integrator.settings.updated(rays=args.rays)
    options = integrator.sphere_options
    sphere = options.sphere
    holders, actions = configurations(sphere, options, instrument.geometry.specimen_radius)["sample"]
    layout = sphere.layout(holders, actions, options.max_bounces, settings.wavelengths)
    plans = [ReadingPlan(w, settings.theta_i, settings.phi_i, args.rays) for w in settings.wavelengths]

    def one_configuration():
        tally = tally_readings(instrument, plans, hook=layout, **kernel_options(settings))
        return [{"cross": tally.bins[k].reshape(4, layout.codes), **{name: value[k] for name, value in tally.sums.items()}}
                for k in range(len(plans))]

    def hemispherical():
        return vm.measure(scene, rays=args.rays)

    def readout():
        return vm.sphere_measure(scene, rays=args.rays)

    counts = one_configuration()[0]
    hemispherical()
    result = readout()  # warm-up: compile every kernel

    def correction():
        return result.corrected(), result.corrected_interval()

    t_walk, t_hemi, t_readout, t_correct = (best(f, args.repeat) for f in (one_configuration, hemispherical, readout,
                                                                            correction))
    reflections = counts["wall_reflections"]
    print(f"sphere walk vs hemispherical reading, {args.rays:,} rays, best of {args.repeat} (warm)")
    print(f"  sphere walk (one configuration): {t_walk * 1e3:8.1f} ms  {args.rays / t_walk / 1e6:6.2f} Mray/s  "
          f"{reflections / t_walk / 1e6:6.1f} M wall reflections/s  ({reflections / args.rays:.1f} per ray)")
    print(f"  hemispherical reading (measure):  {t_hemi * 1e3:8.1f} ms  {args.rays / t_hemi / 1e6:6.2f} Mray/s")
    print(f"  ratio sphere/hemispherical time:  {t_walk / t_hemi:8.1f}")
    print(f"  certified 8/d SCI readout (sample + standard, {args.rays:,} rays each): {t_readout * 1e3:.1f} ms")
    print(f"  its correction by the sphere theory (corrected + corrected_interval): {t_correct * 1e3:.2f} ms "
          f"(reading {result.reading[0]:.4f} -> {result.corrected()[0]:.4f}; "
          f"hemispherical {result.hemispherical[0]:.4f})")
    print(f"  detector fraction {counts['cross'][:, 0].sum() / args.rays:.5f}; "
          f"hemispherical {(counts['cross'][1].sum() + counts['cross'][3].sum()) / args.rays:.5f}")


def spectrum(repeat: int) -> None:
    """The certified SCI spectrum 400–2500 nm / 5 nm of the grey sample under each ray budget (warm, best of ``repeat``)."""

    from revisions import load_average, machine, machine_lines

    print("\n".join(machine_lines({**machine(), "load": load_average()})))
    scene = vm.mitsuba().load_file(SCENE)
    print("certified 8/d SCI spectrum of the grey sample (rho = 0.5, rho_w = 0.98), 400-2500 nm / 5 nm, "
          f"mu = 0.005, delta = 0.01, both configurations; best of {repeat} (warm)")
    for bound in ("hoeffding", "two-stage"):
        def run():
            return vm.sphere_measure(scene, wavelengths="400:2500:5", bound=bound, progress=False)

        result = run()  # warm-up: compile the kernels
        seconds = best(run, repeat)
        rays = sum(int(counts["rays"].sum()) for counts in result.counts.values())
        rays += sum(int(counts["rays"].sum()) for counts in (result.pilot or {}).values())  # two-stage pilots
        print(f"  {bound:9s}: {seconds:7.2f} s  {rays / 1e6:7.2f} M rays  {rays / seconds / 1e6:6.2f} Mray/s  "
              f"certified {bool(result.certified.all())}, reading at 550 nm {result.reading[30]:.4f}")


if __name__ == "__main__":
    main()
