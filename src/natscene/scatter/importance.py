"""
Weight windows
==============

Defines the weight windows of the all-orders photon tracing, which send the photons where the camera looks
(after Cooper & Larsen 2001 and Wagner & Haghighat 1998):

-   :func:`window_targets`: the weight window's centre T per cell.

A photon's tallies count only where the camera sees the cloud (the camera transmittance w weights every tally,
:mod:`.photons`), but most of a thick cloud is hidden behind its first optical depths: few of the tally samples
of an unguided photon land where the camera sees the cloud (docs/stages/precompute.md), and the cloud's shadow side,
which the sun's photons reach only after diffusing through it, gets few of them. Splitting and Russian roulette
against a weight window (the variance reduction of neutron transport codes; the windows follow the forward
flux where the camera sees, after Cooper & Larsen 2001, and are raised behind the visible skin, the role of the
adjoint in Wagner & Haghighat's CADIS 1998) change where the photons go without changing any expected tally.

Per cell of ``factor`` voxels the window's centre is

    T(cell) = c φ(cell) min(1, τ(cell)) / V(cell),

- φ the forward scalar flux of this source (a short pilot run, phase-free tallies; smoothed in log space over
  a cell so that the window is not noisier than it must be),
- V the camera's view of the cell: the density-weighted mean of w over its voxels, blurred by a cell and
  clamped below at ``floor`` (relative to its maximum): V ≈ 1 on the skin the camera sees, ``floor`` deep
  inside,
- τ the cell's optical thickness (σ_t times its mean density times its width): a photon crossing an optically
  thin cell leaves tally samples weighted by a small μ_t / μ̄ (:func:`natscene.scatter.majorant.flight_event`),
  so a thin cell needs proportionally more crossings for the same relative error (the cloud's thin edges),
- c such that T = 1 on average where the photons collide first (so a new photon, of multiplier 1, starts
  inside its window).

Where the camera sees, the photons' weights follow φ, so their density there is uniform: the dim shadow side
gets as many tally samples as the lit side (the photons split as they reach it). Behind the skin the window is
1/floor times higher: photons are rouletted there, and the survivors carry the weight that the ones killed
would have carried. Splitting and roulette keep every expected tally, so the window only moves the noise.

References
----------
-   Cooper, M. A., & Larsen, E. W. (2001). Automated weight windows for global Monte Carlo particle transport
    calculations. Nuclear Science and Engineering, 137(1), 1–13.
-   Wagner, J. C., & Haghighat, A. (1998). Automated variance reduction of Monte Carlo shielding calculations
    using the discrete ordinates adjoint function. Nuclear Science and Engineering, 128(2), 186–208.
"""
from __future__ import annotations

import numpy as np

__all__ = ["window_targets"]


def window_targets(flux: np.ndarray, first: np.ndarray, visibility: np.ndarray, occupied: np.ndarray,
                   thickness: np.ndarray | None = None, floor: float = 0.05, smooth: float = 1.0) -> np.ndarray:
    """T (cz, cy, cx) float32: the weight window's centre per cell (see the module docstring).

    ``flux``: φ per cell (any units); ``first``: the pilot's first-flight tallies per cell (the normalisation's
    weights); ``visibility``: the cells' density-weighted mean camera transmittance; ``occupied``: cells with
    density; ``thickness``: the cells' optical thickness τ (None: thick everywhere). Cells without density get
    T = 1 (no photon collides there)."""
    from scipy.ndimage import gaussian_filter
    occ = np.asarray(occupied, bool)
    phi = np.asarray(flux, np.float64)
    if thickness is not None:
        phi = phi * np.clip(np.asarray(thickness, np.float64), 0.05, 1.0)
    out = np.ones(occ.shape, np.float32)
    pos = occ & (phi > 0)
    if not pos.any():
        return out
    lp = np.where(pos, np.log(np.where(pos, phi, 1.0)), np.log(phi[pos].min()))
    lp = np.where(occ, lp, 0.0)
    norm = gaussian_filter(occ.astype(np.float64), smooth, mode="constant")
    lp = gaussian_filter(lp, smooth, mode="constant") / np.maximum(norm, 1e-12)
    v = gaussian_filter(np.asarray(visibility, np.float64), smooth, mode="constant")
    v = np.maximum(v / max(float(v.max()), 1e-30), float(floor))
    t = np.exp(lp - lp[occ].max()) / v
    w1 = np.where(occ, np.maximum(np.asarray(first, np.float64), 0.0), 0.0)
    c = float((w1 * t).sum() / w1.sum()) if w1.sum() > 0 else float(np.median(t[occ]))
    t = np.clip(t / c, 1e-4, 1e4)
    out[occ] = t[occ]
    return out
