"""
Diffusion jumps
===============

Defines the jumps of a photon across a homogeneous ball deep inside a thick cloud (shell tracing):

-   :data:`BALL_RADII`: the radii of the precomputed balls, in mean free paths.
-   :func:`ball_exits`: the exits of isotropic random walks from the centre of a homogeneous ball of each radius.
-   :func:`homogeneous_radii`: per majorant cell, the largest ball about it whose density is nearly constant.
-   :func:`jump_radii`: per majorant cell, the radius a photon may jump there for one camera and extinction.

A photon that collides at x inside a ball of radius R (mean free paths) of homogeneous medium, albedo 1 and
isotropic scattering, leaves the ball at a point uniformly distributed on its sphere (the walk from the centre is
symmetric under every rotation), with a direction whose cosine mu to the outward normal, and a number of
collisions N inside the ball, jointly distributed as in every other such ball of the same R. A random walk of
isotropic scattering samples that joint distribution once per radius (:func:`ball_exits`); a photon deep inside
the cloud then crosses the ball in one step: it moves to a uniform point of the sphere, flies on from there in a
direction at mu to the normal (mid-flight: the exponential free path is memoryless), and its order grows by N
(Moon, Walter & Marschner 2007: the exits of a precomputed ball, "shell tracing"; Müller et al. 2016). A walk
across a slab of optical depth tau then costs O(log tau) jumps for each of its excursions into the deep
zone instead of O(tau^2) collisions.

The balls are walked in the similar medium of first-order similarity (sigma_t (1 - g), isotropic: Wyman et al.
1989; Zhao, Ramamoorthi & Bala 2014): each similar collision stands for a geometric number of real ones, so the
order grows by K = N + NegBin(N, 1 - g), drawn from its normal approximation (mean N / (1 - g), variance
N g / (1 - g)^2): the closed-form albedo of the bands, beta^K, holds in the mean and in the spread.

A ball is taken only where nothing in it is seen: where the camera's optical depth exceeds
:data:`natscene.scatter.inscatter.VISIBLE_DEPTH` everywhere in it (the visibility weight below 1e-8), so the
tallies its collisions would have made are nil; and only where the density inside it stays within
:data:`TOLERANCE` of its centre's (:func:`homogeneous_radii`), the ball inside the volume's box. The rest of the
walk, the visible skin and whatever is not homogeneous at the scale of :data:`BALL_RADII`'s smallest ball, is
traced collision by collision.

References
----------
-   Moon, J. T., Walter, B., & Marschner, S. R. (2007). Rendering discrete random media using precomputed
    scattering solutions. Eurographics Symposium on Rendering.
-   Müller, T., Papas, M., Gross, M., Jarosz, W., & Novák, J. (2016). Efficient rendering of heterogeneous
    polydisperse granular media. ACM Transactions on Graphics, 35(6).
-   Wyman, D. R., Patterson, M. S., & Wilson, B. C. (1989). Similarity relations for the interaction parameters in
    radiation transport. Applied Optics, 28(24).
-   Zhao, S., Ramamoorthi, R., & Bala, K. (2014). High-order similarity relations in radiative transfer. ACM
    Transactions on Graphics, 33(4).
"""
from __future__ import annotations

from functools import lru_cache

import numba
import numpy as np

__all__ = ["BALL_RADII", "BALL_SAMPLES", "TOLERANCE", "ball_exits", "cell_reduce", "homogeneous_radii", "jump_radii"]

#: the balls' radii in (similar) mean free paths: a ladder from 4 (a jump saves about R^2 / 2 = 8 collisions; a
#: smaller one costs about what it saves) to 64 (2000 collisions), ratio 2^(1/3)
BALL_RADII = 4.0 * 2.0 ** (np.arange(13) / 3.0)
#: the walks sampled per radius (a photon's jump takes one of them at random)
BALL_SAMPLES = 2048
#: the most the density may differ from the ball's largest inside a ball: max / min <= 1 + TOLERANCE
TOLERANCE = 0.1


@numba.njit(cache=True)
def _walks(radius: float, samples: int, seed: int):
    """``samples`` isotropic random walks from the centre of a ball of ``radius`` (mean free paths): the
    collisions inside the ball and the cosine of the exit direction to the outward normal."""
    np.random.seed(seed)
    n_out = np.zeros(samples, np.uint32)
    mu_out = np.zeros(samples, np.float32)
    r2 = radius * radius
    for i in range(samples):
        x = 0.0
        y = 0.0
        z = 0.0
        n = 0
        while True:
            cz = 1.0 - 2.0 * np.random.random()
            phi = 2.0 * np.pi * np.random.random()
            sz = np.sqrt(max(0.0, 1.0 - cz * cz))
            dx, dy, dz = sz * np.cos(phi), sz * np.sin(phi), cz
            s = -np.log(1.0 - np.random.random())
            b = x * dx + y * dy + z * dz            # the flight meets the sphere at |p + t d| = R, t > 0
            t_out = -b + np.sqrt(max(0.0, b * b - (x * x + y * y + z * z - r2)))
            if s >= t_out:
                mu_out[i] = ((x + t_out * dx) * dx + (y + t_out * dy) * dy + (z + t_out * dz) * dz) / radius
                n_out[i] = n
                break
            x += s * dx
            y += s * dy
            z += s * dz
            n += 1
    return n_out, mu_out


@lru_cache(maxsize=None)
def ball_exits(samples: int = BALL_SAMPLES, seed: int = 12345) -> tuple[np.ndarray, np.ndarray]:
    """The exits of ``samples`` isotropic random walks (albedo 1, unit mean free path) from the centre of a ball of
    each radius of :data:`BALL_RADII`, the walk's first direction isotropic: the collisions inside the ball
    (uint32 [radii, samples]) and the cosine of the exit direction to the sphere's outward normal (float32
    [radii, samples])."""
    n = np.empty((len(BALL_RADII), samples), np.uint32)
    mu = np.empty((len(BALL_RADII), samples), np.float32)
    for i, r in enumerate(BALL_RADII):
        n[i], mu[i] = _walks(float(r), samples, seed + i)
    return n, mu


def cell_reduce(values: np.ndarray, block: int, reduce=np.min, fill: float = 0.0) -> np.ndarray:
    """``reduce`` (np.min or np.max) of voxel ``values`` [nz, ny, nx] over cells of ``block`` voxels (the majorant
    grid's), the partial cells at the far faces padded with ``fill``."""
    nz, ny, nx = values.shape
    b = max(1, int(block))
    cz, cy, cx = -(-nz // b), -(-ny // b), -(-nx // b)
    pad = np.full((cz * b, cy * b, cx * b), fill, np.asarray(values).dtype)
    pad[:nz, :ny, :nx] = values
    return reduce(pad.reshape(cz, b, cy, b, cx, b), axis=(1, 3, 5))


def homogeneous_radii(density: np.ndarray, voxel_size, block: int = 4,
                      tolerance: float = TOLERANCE) -> tuple[np.ndarray, np.ndarray]:
    """Per cell of ``block`` voxels [cz, cy, cx] (the majorant grid's, :mod:`.majorant`): the radius (world units)
    of the largest ball centred anywhere in the cell within which the trilinear density stays within
    ``tolerance`` (max / min <= 1 + tolerance, min > 0) and which lies inside the volume's box, and the largest
    density in it (0 where no ball fits). The balls are tested as boxes of whole cells, each cell's range the
    density's over its voxels and their neighbours (the trilinear lookup's support; outside the box: 0), for
    radii of half a cell's smallest side times 2^(j/2)."""
    from scipy.ndimage import maximum_filter, minimum_filter
    d = np.asarray(density, np.float32)
    b = max(1, int(block))
    mn = cell_reduce(minimum_filter(d, size=3, mode="constant", cval=0.0), b, np.min)
    mx = cell_reduce(maximum_filter(d, size=3, mode="constant", cval=0.0), b, np.max)
    cell = np.asarray(voxel_size, np.float64)[::-1] * b          # (z, y, x) sides
    radius = np.zeros(mn.shape, np.float64)
    top = np.zeros(mn.shape, np.float64)
    r = 0.5 * float(cell.min())
    while True:
        half = np.ceil(r / cell - 1e-9).astype(int)
        if np.any(2 * half + 1 > np.array(mn.shape)):
            break
        size = tuple(int(2 * h + 1) for h in half)
        big = maximum_filter(mx, size=size, mode="constant", cval=0.0)
        small = minimum_filter(mn, size=size, mode="constant", cval=0.0)
        ok = (small > 0) & (big <= (1.0 + tolerance) * small)
        if not ok.any():
            break
        radius[ok] = r
        top[ok] = big[ok]
        r *= np.sqrt(2.0)
    return radius, top


def jump_radii(radius: np.ndarray, top: np.ndarray, depth_lower: np.ndarray, sig_k: float,
               visible_depth: float) -> np.ndarray:
    """Per cell: the radius (world units) of a jump there for a camera whose optical depth (at extinction ``sig_k``
    per unit density) is at least ``sig_k * depth_lower`` in the cell: the homogeneous ball's
    (:func:`homogeneous_radii`), shrunk so that the camera's optical depth stays above ``visible_depth``
    everywhere in the ball (it falls by at most sig_k * top per unit length); 0 where none fits."""
    room = np.where(top > 0, (np.asarray(depth_lower, np.float64) - visible_depth / sig_k) / np.maximum(top, 1e-30),
                    0.0)
    return np.clip(np.minimum(radius, room), 0.0, None).astype(np.float32)
