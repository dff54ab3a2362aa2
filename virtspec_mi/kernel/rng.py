"""
Counter-based random numbers keyed on (seed, global ray index)
===============================================================

Every ray of a measurement has a global index g (readings occupy consecutive
ranges of g). Its d-th random number is a pure function of (seed, g, d):

    u_d(g) = hash32(g_lo XOR key_d) / 2³²,   key_d = hash32(root + d·φ),
    root = hash32(hash32(seed + c₁) XOR hash32(g_hi + c₂)),

with ``hash32`` the bijective "triple32" integer hash (three multiply–xorshift
rounds, one of the best-mixing 32-bit hashes known), g_lo / g_hi the low / high
32 bits of g and φ = 0x9E3779B9. Because nothing depends on how rays are grouped
into chunks or threads, a seed gives identical counts whatever the chunk size or
thread count; because ``hash32`` is a bijection, the rays of one chunk never share
a random number in the same dimension.

The keys are computed once per chunk on the host (NumPy); the kernel spends one
hash per random number. :func:`hash32` is written once for both NumPy ``uint32``
arrays and Dr.Jit ``UInt32`` arrays.

Uniforms have 24 random bits (u = k·2⁻²⁴, k ∈ [0, 2²⁴)): a comparison ``u < p``
happens with probability p to within 2⁻²⁴ ≈ 6·10⁻⁸, far below any certified μ.
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["GOLDEN", "FIXED_DIMENSIONS", "hash32", "chunk_root", "dimension_key", "dimension_keys", "to_unit"]

GOLDEN: int = 0x9E3779B9
"""φ·2³², the dimension stride of the keys."""

FIXED_DIMENSIONS: int = 8
"""Dimensions whose keys are precomputed per chunk (emitter 2, specimen 2, BSDF 3, survival 1)."""

_MASK = 0xFFFFFFFF


def hash32(x: Any) -> Any:
    """The "triple32" bijective hash of 32-bit unsigned integers (NumPy or Dr.Jit)."""

    x = x ^ (x >> 17)
    x = x * 0xED5AD4BB
    x = x ^ (x >> 11)
    x = x * 0xAC4C1B51
    x = x ^ (x >> 15)
    x = x * 0x31848BAB
    x = x ^ (x >> 14)
    return x


def _u32(value: int) -> np.ndarray:
    return np.array([value & _MASK], dtype=np.uint32)


def chunk_root(seed: int, block: int) -> int:
    """Root key of the rays whose global index has high word ``block`` (= g >> 32)."""

    with np.errstate(over="ignore"):
        mixed = hash32(_u32(seed + 0x6A09E667)) ^ hash32(_u32(block + 0xBB67AE85))
        return int(hash32(mixed)[0])


def dimension_key(root: Any, dimension: Any) -> Any:
    """Key of one dimension under ``root``: ``hash32(root + dimension·φ)`` (NumPy or Dr.Jit uint32)."""

    return hash32(root + dimension * GOLDEN)


def dimension_keys(root: int, count: int = FIXED_DIMENSIONS) -> list[int]:
    """Keys of dimensions 0 … count − 1 under ``root``, computed on the host."""

    with np.errstate(over="ignore"):
        keys = dimension_key(_u32(root), np.arange(count, dtype=np.uint32))
    return [int(k) for k in keys]


def to_unit(bits: Any, float_type: Any) -> Any:
    """Map 32 random bits to a uniform in [0, 1) with 24-bit resolution."""

    return float_type(bits >> 8) * (1.0 / 16777216.0)
