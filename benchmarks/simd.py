"""
The SIMD width of Dr.Jit's LLVM backend, read and narrowed for a benchmark
==========================================================================

Dr.Jit compiles its CPU kernels for the host's widest vectors (16 single-precision lanes
with AVX-512, 8 with AVX2). A figure stated for an AVX2 machine can be taken on an
AVX-512 one by compiling for AVX2 (Haswell's instruction set, 8 lanes) before the first
kernel is built: :func:`use_avx2`, through libdrjit-core's ``jit_llvm_set_target``
(exported by the library Dr.Jit ships, as C++). The same cores, caches and clock run the
narrower code, so this is AVX2 code on this machine, not an AVX2 machine: say so beside
the figure.

References
----------
Dr.Jit-Core, ``include/drjit-core/jit.h``: ``jit_llvm_set_target(target_cpu,
target_features, vector_width)`` and ``jit_llvm_vector_width()``.
"""

from __future__ import annotations

import ctypes
import os

__all__ = ["lanes", "use_avx2"]

AVX2_FEATURES = (b"+avx,+avx2,+fma,+f16c,+bmi,+bmi2,+lzcnt,+popcnt,+sse4.1,+sse4.2,"
                 b"-avx512f,-avx512vl,-avx512bw,-avx512dq,-avx512cd")
"""Haswell's vector features, AVX-512's switched off."""


def _core() -> ctypes.CDLL:
    import drjit

    return ctypes.CDLL(os.path.join(drjit.__path__[0], "libdrjit-core.so"))


def lanes() -> int:
    """The lanes of the LLVM backend's kernels (single precision) as compiled now."""

    width = _core()._Z21jit_llvm_vector_widthv
    width.restype = ctypes.c_uint32
    return int(width())


def use_avx2() -> None:
    """Compile every later kernel for AVX2 (Haswell, 8 lanes); call before the first kernel is built."""

    _core()._Z19jit_llvm_set_targetPKcS0_j(b"haswell", AVX2_FEATURES, ctypes.c_uint32(8))
    if lanes() != 8:
        raise RuntimeError(f"Dr.Jit kept {lanes()} lanes after the AVX2 target was set")
