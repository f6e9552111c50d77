"""
Dr.Jit vector helpers
=====================

Defines the Dr.Jit vector helpers of the set's geometry:

-   :func:`array3f64`: numpy arrays as Array3f64.
-   :func:`dot`: the dot product written out (x + y) + z without fused multiply-adds, the order numpy evaluates
    it in.
"""
from __future__ import annotations

import numpy as np

__all__ = ["array3f64", "dot"]


def array3f64(a):
    """A (3,) vector or an (M, 3) array as a Dr.Jit Array3f64 of the active Mitsuba variant."""
    import mitsuba as mi
    a = np.asarray(a, np.float64)
    if a.ndim == 1:
        return mi.Array3f64(*(float(x) for x in a))
    return mi.Array3f64(*(mi.Float64(np.ascontiguousarray(a[:, k])) for k in range(3)))


def dot(a, b):
    """a · b of Dr.Jit 3-vectors, summed (x + y) + z."""
    return a.x * b.x + a.y * b.y + a.z * b.z
