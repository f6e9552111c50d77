"""
Linear stability theory of the reaction-diffusion
=================================================

Defines the linear (Turing) stability theory of Eq. 3.5 (Dong 2007, §3.3.2; Murray 2003, Ch. 2):

-   :func:`growth_rate`: the growth rate of a perturbation of wavenumber q about the homogeneous steady state.
-   :func:`fastest_wavelength`: the wavelength of the fastest-growing mode.
-   :func:`dominant_wavelength`: the dominant wavelength of a simulated field (the tests compare the two).

References
----------
-   Dong, W. (2007). Rendering Algorithms for Natural Scenes. PhD thesis, Université Henri Poincaré - Nancy I.
-   Murray, J. D. (2003). Mathematical Biology, Volume II: Spatial Models and Biomedical Applications. Springer.
"""
from __future__ import annotations

import numpy as np

from natscene.patterns.reaction_diffusion.parameters import RDParams

__all__ = ["growth_rate", "fastest_wavelength", "dominant_wavelength"]


def growth_rate(p: RDParams, q: np.ndarray) -> np.ndarray:
    """Largest real part of the eigenvalues of J - (q^2 / 4) diag(D_A, D_B) (per step) for wavenumbers q
    (rad/pixel): the linear stability of Eq. 3.5 with the continuum limit of the 5-point l (= grad^2 / 4)."""
    J = p.jacobian()
    q = np.atleast_1d(np.asarray(q, float))
    mu = q * q / 4.0
    tr = J[0, 0] + J[1, 1] - mu * (p.D_A + p.D_B)
    det = (J[0, 0] - p.D_A * mu) * (J[1, 1] - p.D_B * mu) - J[0, 1] * J[1, 0]
    disc = tr * tr / 4 - det
    return np.where(disc >= 0, tr / 2 + np.sqrt(np.maximum(disc, 0)), tr / 2)


def fastest_wavelength(p: RDParams) -> float:
    """Wavelength (pixels) of the fastest-growing mode; inf when no mode grows (no Turing instability)."""
    q = np.linspace(1e-3, np.pi, 20000)
    g = growth_rate(p, q)
    i = int(np.argmax(g))
    return float(2 * np.pi / q[i]) if g[i] > 0 else float("inf")


def dominant_wavelength(field2d: np.ndarray) -> float:
    """Wavelength (pixels) of the radially averaged power-spectrum peak of a square field (mean removed)."""
    f = np.asarray(field2d, float)
    f = f - f.mean()
    n = min(f.shape)
    P = np.abs(np.fft.fft2(f[:n, :n])) ** 2
    k = np.fft.fftfreq(n) * n
    kr = np.hypot(*np.meshgrid(k, k, indexing="ij"))
    bins = np.rint(kr).astype(int)
    power = np.bincount(bins.ravel(), P.ravel()) / np.maximum(np.bincount(bins.ravel()), 1)
    power[0] = 0
    power = power[: n // 2]
    i = int(np.argmax(power))
    # sub-bin refinement: power-weighted mean over the peak's neighbours
    lo, hi = max(i - 1, 1), min(i + 2, power.size)
    kk = np.arange(lo, hi)
    kpk = float((power[lo:hi] * kk).sum() / power[lo:hi].sum())
    return n / kpk
