"""
Procedural noise
================

Defines the procedural noise of the cloud volumes in the style of Ebert et al. (Texturing & Modeling,
2003/2009): fractional Brownian motion (fBm) of value noise, and Worley (cellular) noise for billowy detail:

-   :func:`value_noise`, :func:`fbm`: one octave of value noise, and its normalised fBm.
-   :func:`worley_f1`: Worley F1 noise.
-   :func:`perlin_tile`, :func:`worley_tile`, :func:`worley_fbm_tile`, :func:`perlin_worley_tile`: the periodic
    noise tiles of the production modeller (Perlin's improved noise, Worley F1, Schneider's Perlin-Worley).
-   :func:`radial_energy_spectrum`: the energy of a 3-D field per spherical frequency shell.

fBm: ``fbm(p) = sum_o gain^o * n(lacunarity^o * f0 * p) / sum_o gain^o`` with ``n`` value noise on an
integer lattice (uniform values in [-1, 1], quintic fade ``6t^5 - 15t^4 + 10t^3`` between lattice points,
a random lattice offset per octave). Each octave is evaluated on the whole grid at once as three
separable 1-D interpolation matrices applied to the lattice (tensor products), so the cost is a few
matrix products, not per-voxel work.

Worley F1: distance from each voxel to the nearest of a set of jittered feature points (one per cell of
a ``cells``-per-unit grid), computed with an exact Euclidean distance transform.

References
----------
-   Ebert, D. S., Musgrave, F. K., Peachey, D., & Perlin, K. (2009). Texturing and Modeling: A Procedural
    Approach (3rd ed.). Morgan Kaufmann.
-   Perlin, K. (2002). Improving noise. ACM Transactions on Graphics, 21(3), 681–682.
-   Schneider, A., & Vos, N. (2015). The real-time volumetric cloudscapes of Horizon: Zero Dawn. SIGGRAPH 2015
    course Advances in Real-Time Rendering in Games.
-   Worley, S. (1996). A cellular texture basis function. Proceedings of ACM SIGGRAPH 1996, 291–294.
"""
from __future__ import annotations

import numpy as np
from scipy import ndimage

__all__ = ["value_noise", "fbm", "worley_f1", "perlin_tile", "worley_tile", "worley_fbm_tile",
           "perlin_worley_tile", "radial_energy_spectrum"]


def _fade(t: np.ndarray) -> np.ndarray:
    return t * t * t * (t * (t * 6 - 15) + 10)


def _interp_matrix(n_out: int, extent: float, frequency: float, offset: float) -> np.ndarray:
    """(n_out, n_lattice) weights mapping lattice values to voxel centres along one axis."""
    u = (np.arange(n_out) + 0.5) / n_out * extent * frequency + offset
    i = np.floor(u).astype(np.int64)
    t = _fade(u - i)
    n_lat = int(i.max()) + 2
    m = np.zeros((n_out, n_lat), np.float32)
    rows = np.arange(n_out)
    m[rows, i] = 1 - t
    m[rows, i + 1] = t
    return m


def value_noise(shape, extent, frequency: float, rng: np.random.Generator) -> np.ndarray:
    """One octave of value noise in [-1, 1] on a grid ``shape`` = (nz, ny, nx) spanning ``extent`` = (ez, ey, ex)."""
    mz, my, mx = (_interp_matrix(n, e, frequency, rng.uniform(0, 16)) for n, e in zip(shape, extent))
    lattice = rng.uniform(-1, 1, (mz.shape[1], my.shape[1], mx.shape[1])).astype(np.float32)
    a = lattice @ mx.T                               # (lz, ly, nx)
    a = np.einsum("yl,zlx->zyx", my, a)              # (lz, ny, nx)
    return np.tensordot(mz, a, axes=(1, 0))          # (nz, ny, nx)


def fbm(shape, extent, base_frequency: float, octaves: int, lacunarity: float = 2.0, gain: float = 0.5,
        rng: np.random.Generator | None = None) -> np.ndarray:
    """Normalised fBm (roughly in [-1, 1]) of ``octaves`` value-noise octaves, float32 (nz, ny, nx)."""
    rng = rng or np.random.default_rng()
    out = np.zeros(shape, np.float32)
    amp, total, f = 1.0, 0.0, float(base_frequency)
    for _ in range(octaves):
        out += np.float32(amp) * value_noise(shape, extent, f, rng)
        total += amp
        amp *= gain
        f *= lacunarity
    out /= np.float32(total)
    return out


def worley_f1(shape, extent, cells: float, rng: np.random.Generator, downsample: int = 2) -> np.ndarray:
    """Worley F1 noise: distance (in units of the cell size) to the nearest jittered feature point.

    Evaluated on a grid ``downsample`` times coarser and upsampled linearly (the cells are many voxels wide).
    """
    shape = np.asarray(shape)
    coarse = np.maximum(1, np.ceil(shape / downsample).astype(int))
    extent = np.asarray(extent, np.float64)
    ncell = np.maximum(1, np.round(extent * cells).astype(int))          # cells per axis
    # one jittered point per cell, in continuous coarse-voxel coordinates
    grid = np.stack(np.meshgrid(*[np.arange(n) for n in ncell], indexing="ij"), -1).reshape(-1, 3)
    pts = (grid + rng.uniform(0, 1, grid.shape)) / ncell * coarse
    idx = np.clip(np.floor(pts).astype(int), 0, coarse - 1)
    seeds = np.ones(tuple(coarse), bool)
    seeds[idx[:, 0], idx[:, 1], idx[:, 2]] = False
    voxel = extent / coarse                                               # world size of a coarse voxel
    dist = ndimage.distance_transform_edt(seeds, sampling=voxel).astype(np.float32)
    dist *= np.float32(cells)                                             # in cell units
    zoom = shape / coarse
    return ndimage.zoom(dist, zoom, order=1, grid_mode=True, mode="nearest")[: shape[0], : shape[1], : shape[2]]


def radial_energy_spectrum(field: np.ndarray, extent) -> tuple[np.ndarray, np.ndarray]:
    """Energy of a 3-D field per spherical frequency shell of width 1 cycle/unit: (shell centre, sum |F|^2)."""
    f = np.fft.fftn(field - field.mean())
    p = (np.abs(f) ** 2).ravel()
    freqs = [np.fft.fftfreq(n, d=e / n) for n, e in zip(field.shape, extent)]
    kz, ky, kx = np.meshgrid(*freqs, indexing="ij")
    k = np.sqrt(kx ** 2 + ky ** 2 + kz ** 2).ravel()
    shell = np.round(k).astype(np.int64)
    return np.arange(shell.max() + 1, dtype=np.float64), np.bincount(shell, p)


# ------------------------------------------------------------------ periodic noise tiles (Schneider's Nubis)
# The production modeller samples small periodic 3-D noise textures at several frequencies, as Schneider's
# Nubis cloud system does on the GPU (a 128^3 "Perlin-Worley" shape texture and a 32^3 Worley detail texture,
# "The real-time volumetric cloudscapes of Horizon: Zero Dawn", SIGGRAPH 2015; "Nubis", 2017). A tile of ``n``
# texels holds ``cells`` noise cells per axis and wraps, so the noise of any frequency is a trilinear lookup.

def perlin_tile(n: int, cells: int, rng: np.random.Generator) -> np.ndarray:
    """Periodic 3-D gradient (Perlin) noise, float32 (n, n, n), ``cells`` lattice cells per axis, scaled to
    unit maximum magnitude (values in [-1, 1]).

    Perlin's improved noise: random unit gradients at the lattice points, the dot product of each corner's
    gradient with the offset to the sample, blended with the quintic fade ``6t^5 - 15t^4 + 10t^3``."""
    g = rng.normal(size=(cells, cells, cells, 3))
    g /= np.linalg.norm(g, axis=-1, keepdims=True)
    u = (np.arange(n) + 0.5) / n * cells
    i0 = np.floor(u).astype(np.int64)
    f = u - i0
    w = _fade(f)
    out = np.zeros((n, n, n), np.float64)
    for dz in (0, 1):
        for dy in (0, 1):
            for dx in (0, 1):
                cz, cy, cx = (i0 + dz) % cells, (i0 + dy) % cells, (i0 + dx) % cells
                grad = g[cz[:, None, None], cy[None, :, None], cx[None, None, :]]          # (n, n, n, 3)
                dot = (grad[..., 0] * (f - dx)[None, None, :] + grad[..., 1] * (f - dy)[None, :, None]
                       + grad[..., 2] * (f - dz)[:, None, None])
                wz = w if dz else 1 - w
                wy = w if dy else 1 - w
                wx = w if dx else 1 - w
                out += dot * wz[:, None, None] * wy[None, :, None] * wx[None, None, :]
    return (out / max(float(np.abs(out).max()), 1e-12)).astype(np.float32)


def worley_tile(n: int, cells: int, rng: np.random.Generator) -> np.ndarray:
    """Periodic Worley F1 noise, float32 (n, n, n): distance (in cell units) from each texel to the nearest of
    one jittered feature point per cell (``cells`` per axis, wrapping), over the 27 neighbouring cells."""
    pts = rng.uniform(0, 1, (cells, cells, cells, 3))
    out = np.empty((n, n, n), np.float32)
    _worley_kernel()(pts, out)
    return out


_WORLEY = None


def _worley_kernel():
    """Compiled F1 search (numba, cached on disk): 27 neighbour cells per texel."""
    global _WORLEY
    if _WORLEY is None:
        import numba as nb

        @nb.njit(parallel=True, cache=True)
        def kern(pts, out):
            n = out.shape[0]
            c = pts.shape[0]
            for z in nb.prange(n):
                uz = (z + 0.5) / n * c
                cz = int(np.floor(uz))
                fz = uz - cz
                for y in range(n):
                    uy = (y + 0.5) / n * c
                    cy = int(np.floor(uy))
                    fy = uy - cy
                    for x in range(n):
                        ux = (x + 0.5) / n * c
                        cx = int(np.floor(ux))
                        fx = ux - cx
                        best = 1e30
                        for dz in range(-1, 2):
                            kz = (cz + dz) % c
                            for dy in range(-1, 2):
                                ky = (cy + dy) % c
                                for dx in range(-1, 2):
                                    kx = (cx + dx) % c
                                    ax = dx + pts[kz, ky, kx, 0] - fx
                                    ay = dy + pts[kz, ky, kx, 1] - fy
                                    az = dz + pts[kz, ky, kx, 2] - fz
                                    d2 = ax * ax + ay * ay + az * az
                                    if d2 < best:
                                        best = d2
                        out[z, y, x] = np.sqrt(best)
        _WORLEY = kern
    return _WORLEY


def worley_fbm_tile(n: int, cells: int, rng: np.random.Generator, octaves: int = 3) -> np.ndarray:
    """Inverted Worley fBm in [0, 1] (1 at feature points): ``sum_o 0.5^o (1 - F1_o)`` over octaves of
    ``cells * 2^o`` cells, normalised; the billowy "cauliflower" basis of Nubis' shape and detail textures."""
    out = np.zeros((n, n, n), np.float32)
    amp, total = 1.0, 0.0
    for o in range(octaves):
        out += np.float32(amp) * (1 - np.clip(worley_tile(n, cells * 2 ** o, rng), 0, 1))
        total += amp
        amp *= 0.5
    out /= np.float32(total)
    lo, hi = float(out.min()), float(out.max())
    return ((out - lo) / max(hi - lo, 1e-12)).astype(np.float32)


def perlin_worley_tile(n: int, cells: int, rng: np.random.Generator) -> np.ndarray:
    """Schneider's Perlin-Worley noise in [0, 1]: Perlin fBm (3 octaves, in [0, 1]) dilated by inverted Worley
    fBm, ``remap(perlin, worley - 1, 1, 0, 1)`` (Nubis 2015): connected, billowy blobs instead of Perlin's
    wispy ridges or Worley's isolated cells."""
    per = np.zeros((n, n, n), np.float32)
    amp, total = 1.0, 0.0
    for o in range(3):
        per += np.float32(amp) * perlin_tile(n, cells * 2 ** o, rng)
        total += amp
        amp *= 0.5
    per = per / np.float32(total) * np.float32(0.5) + np.float32(0.5)
    wor = worley_fbm_tile(n, cells, rng)
    pw = (per - (wor - 1)) / (2 - wor)                   # remap(per, wor - 1, 1, 0, 1)
    lo, hi = float(pw.min()), float(pw.max())
    return ((pw - lo) / max(hi - lo, 1e-12)).astype(np.float32)
