"""
Kernel-side code: what runs inside the fused Dr.Jit ray kernel
==============================================================

Plain values in, exact tallies out: the kernel imports nothing from the package outside
``virtspec_mi.kernel`` (the engine validates at the boundary and hands it typed values),
and the package itself imports nothing, so a plugin that needs one helper loads only
that one.

- :mod:`~virtspec_mi.kernel.rng` — counter-based random numbers keyed on
  (seed, global ray index, dimension);
- :mod:`~virtspec_mi.kernel.disk` — disk sampling, eqs. (3) and (4);
  :mod:`~virtspec_mi.kernel.incidence` — the incidence rotation;
- :mod:`~virtspec_mi.kernel.walk` and :mod:`~virtspec_mi.kernel.walk_optics` — the
  conventions and optical pieces of random-walk specimens;
- :mod:`~virtspec_mi.kernel.counts` — fates and exact counts by name;
- :mod:`~virtspec_mi.kernel.tracer` — the ray kernel itself: rays → specimen BSDF →
  fate → exact integer counts, with an optional exit hook (driven by
  :mod:`virtspec_mi.engine.readings`);
- :mod:`~virtspec_mi.kernel.hooks` — the exit-hook protocol. An instrument's own hook
  lives in its folder and imports only this package
  (:mod:`virtspec_mi.instruments.goniophotometer.hook`, the goniophotometer's bins;
  :mod:`virtspec_mi.instruments.sphere.walk`, the integrating sphere's walk).
"""
