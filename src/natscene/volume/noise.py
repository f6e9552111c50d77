"""Procedural noise for cloud volumes in the style of Ebert et al. (Texturing & Modeling, 2003/2009):
fractional Brownian motion (fBm) of value noise, and Worley (cellular) noise for billowy detail.

fBm: ``fbm(p) = sum_o gain^o * n(lacunarity^o * f0 * p) / sum_o gain^o`` with ``n`` value noise on an
integer lattice (uniform values in [-1, 1], quintic fade ``6t^5 - 15t^4 + 10t^3`` between lattice points,
a random lattice offset per octave). Each octave is evaluated on the whole grid at once as three
separable 1-D interpolation matrices applied to the lattice (tensor products), so the cost is a few
matrix products, not per-voxel work.

Worley F1: distance from each voxel to the nearest of a set of jittered feature points (one per cell of
a ``cells``-per-unit grid), computed with an exact Euclidean distance transform.
"""
from __future__ import annotations

import numpy as np
from scipy import ndimage


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
