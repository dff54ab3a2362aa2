"""
Kernel-side code: what runs inside the fused Dr.Jit ray kernel
==============================================================

One place for the device code that the engine and the specimen plugins share; the
package itself imports nothing, so a plugin that needs one helper loads only that one.

- :mod:`~virtspec_mi.kernel.rng` — counter-based random numbers keyed on
  (seed, global ray index, dimension);
- :mod:`~virtspec_mi.kernel.disk` — disk sampling, eqs. (3) and (4);
- :mod:`~virtspec_mi.kernel.walk` and :mod:`~virtspec_mi.kernel.walk_optics` — the
  conventions and optical pieces of random-walk specimens;
- :mod:`~virtspec_mi.kernel.tracer` — the ray kernel itself: rays → specimen BSDF →
  fate → exact integer counts (driven by :mod:`virtspec_mi.engine.readings`).
"""
