"""
Measures of cloud detail
========================

Defines the measures of cloud detail that the volume tests and previews compare with real clouds
(docs/stages/volume.md, "Previews and measured detail"):

-   :func:`box_counting_dimension`: the box-counting dimension of a silhouette's boundary (:func:`boundary`).
-   :func:`band_energy`: the energy of a 3-D field in octave bands.
-   :func:`thin_edge_fraction`, :func:`speck_fraction`: the shares of thin and of isolated cloud voxels.
-   :func:`islands`: the small isolated islands of a silhouette.

- Box-counting dimension of a silhouette's boundary (Mandelbrot; Lovejoy 1982 measured the perimeter-area
  dimension of real cloud outlines at about 1.35): the boundary pixels of a binary mask (inside pixels with a
  4-neighbour outside) are covered with boxes of side s = 2, 4, ..., 64 px; ``D = -slope`` of the least-squares
  line through (log s, log N(s)). A smooth curve gives 1, a plane-filling one 2.
- Speck fraction: the share of cloud voxels in tiny isolated components (salt-and-pepper speckle).
- Band energy: the radial power spectrum of a 3-D field (:func:`natscene.volume.noise.radial_energy_spectrum`)
  summed over the octave band [f / sqrt(2), f * sqrt(2)) around a frequency f (cycles per longest side).

References
----------
-   Lovejoy, S. (1982). Area-perimeter relation for rain and cloud areas. Science, 216(4542), 185–187.
-   Mandelbrot, B. B. (1982). The Fractal Geometry of Nature. W. H. Freeman.
"""
from __future__ import annotations

import numpy as np

from natscene.volume.noise import radial_energy_spectrum

__all__ = ["box_counting_dimension", "boundary", "band_energy", "thin_edge_fraction", "speck_fraction", "islands"]


def boundary(mask: np.ndarray) -> np.ndarray:
    """Boundary pixels of a binary image: inside pixels with at least one 4-neighbour outside (or on the edge)."""
    m = np.asarray(mask, bool)
    p = np.pad(m, 1, constant_values=False)
    interior = p[:-2, 1:-1] & p[2:, 1:-1] & p[1:-1, :-2] & p[1:-1, 2:]
    return m & ~interior


def box_counting_dimension(mask: np.ndarray, sizes=(2, 4, 8, 16, 32, 64)) -> float:
    """Box-counting dimension of the boundary of ``mask`` over box sides ``sizes`` (pixels)."""
    b = boundary(mask)
    if not b.any():
        raise ValueError("box_counting_dimension: the mask has no boundary (empty or full)")
    counts = []
    for s in sizes:
        h, w = -(-b.shape[0] // s) * s, -(-b.shape[1] // s) * s
        pad = np.zeros((h, w), bool)
        pad[: b.shape[0], : b.shape[1]] = b
        counts.append(int(pad.reshape(h // s, s, w // s, s).any(axis=(1, 3)).sum()))
    slope = np.polyfit(np.log(np.asarray(sizes, float)), np.log(np.asarray(counts, float)), 1)[0]
    return float(-slope)


def band_energy(field: np.ndarray, frequencies) -> np.ndarray:
    """Energy of ``field`` (a grid whose longest side is 1) in the octave band around each frequency."""
    ext = np.array(field.shape, float) / max(field.shape)
    k, e = radial_energy_spectrum(field.astype(np.float64), ext)
    out = []
    for f in frequencies:
        sel = (k >= f / np.sqrt(2)) & (k < f * np.sqrt(2))
        out.append(float(e[sel].sum()))
    return np.array(out)


def thin_edge_fraction(density: np.ndarray, below: float = 0.2) -> float:
    """Share of the cloud's voxels (rho > 0) that are thin: 0 < rho < ``below``."""
    cloud = density > 0
    return float(((density > 0) & (density < below)).sum() / max(int(cloud.sum()), 1))


def speck_fraction(density: np.ndarray, level: float = 0.05, min_voxels: int = 27) -> float:
    """Share of the cloud's voxels (rho > ``level``) that lie in isolated specks: 26-connected components of
    fewer than ``min_voxels`` voxels (a 3x3x3 block), the salt-and-pepper of noise sampled finer than the grid
    holds. Coherent wisps are connected to the cloud or are larger; a clean cloud gives 0."""
    from scipy import ndimage

    m = np.asarray(density) > level
    total = int(m.sum())
    if total == 0:
        return 0.0
    lab, n = ndimage.label(m, structure=np.ones((3, 3, 3), bool))
    sizes = np.bincount(lab.ravel())[1:]
    return float(sizes[sizes < min_voxels].sum() / total)


def islands(mask: np.ndarray, max_pixels: int = 4) -> int:
    """Number of isolated islands of a 2-D silhouette (8-connected components) of at most ``max_pixels``
    pixels: specks floating beside the cloud in a projection."""
    from scipy import ndimage

    lab, n = ndimage.label(np.asarray(mask, bool), structure=np.ones((3, 3), bool))
    if n == 0:
        return 0
    sizes = np.bincount(lab.ravel())[1:]
    return int((sizes <= max_pixels).sum())
