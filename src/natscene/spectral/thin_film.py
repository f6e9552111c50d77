"""
Multilayer thin films
=====================

Defines the multilayer thin-film reflectance and transmittance (Dong 2007, §1.1.6, Eqs. 1.14-1.25, after
Hirayama et al. 1999 [HKY+99] and Born & Wolf [BW99]), tabulated per (incident angle, wavelength) as the
preprocessing step of Dong §2.2 (Eqs. 2.1-2.2):

-   :func:`multilayer`: the composite reflectance and transmittance of a stack.
-   :func:`film_table`: R and T of a stack tabulated per (incident angle, wavelength), a :class:`FilmTable`.

Layers are numbered as in Dong's Fig. 1.8: 0 is the incident medium (real index n_0), 1..N the films
(complex n̂_j, thickness d_j), N+1 the substrate. Boundary B_j separates layers j-1 and j.

- Snell (Eq. 1.19): s_x,j = n_0 sin θ_0 / n̂_j, s_z,j = sqrt(1 - s_x,j²); we evaluate n̂_j s_z,j =
  sqrt(n̂_j² - n_0² sin² θ_0) on the branch with Im ≥ 0 (a wave decaying into absorbing/evanescent layers).
- Fresnel amplitudes at B_j (Eqs. 1.20-1.23), parallel (p) and perpendicular (s) components.
- Phase across layer j (Eq. 1.18): φ_j = 2π/λ n̂_j d_j s_z,j.
- Seed (Eqs. 1.14-1.15) γ_0 = r_{N+1}, τ_0 = t_{N+1}; recurrence from B_{N+1} to B_1 (Eqs. 1.16-1.17):
  γ ← (r_j + γ e^{2iφ_j}) / (1 + r_j γ e^{2iφ_j}),  τ ← t_j τ e^{iφ_j} / (1 + r_j γ e^{2iφ_j}).
- R = (|γ_∥|² + |γ_⊥|²)/2 (Eq. 1.24); T = Re(n̂_{N+1} s_z,N+1)/(n_0 s_z,0) (|τ_∥|² + |τ_⊥|²)/2 for a
  non-absorbing substrate, 0 for an absorbing one (Eq. 1.25).

Two misprints of the thesis text are corrected (both are Born & Wolf's formulas, and the tests check the
result against an independent transfer-matrix computation): in Eq. 1.17 the denominator is
``1 + r_j γ e^{2iφ_j}`` (the text prints ``1 + r_j τ e^{iφ_j}``), and the numerator of Eq. 1.21 is
``n̂_{j-1} s_z,j-1 - n̂_j s_z,j`` (the text prints ``n̂_j s_z,j-1`` for its second term).

References
----------
-   Born, M., & Wolf, E. (1999). Principles of Optics: Electromagnetic Theory of Propagation, Interference and
    Diffraction of Light (7th ed.). Cambridge University Press.
-   Dong, W. (2007). Rendering algorithms for natural scenes. PhD thesis, Université Henri Poincaré – Nancy 1.
-   Hirayama, H., Kaneda, K., Yamashita, H., Yamaji, Y., & Monden, Y. (1999). Visualization of optical phenomena
    caused by multilayer films with complex refractive indices. Proceedings of the 7th Pacific Conference on
    Computer Graphics and Applications (PG '99), 128–137.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from natscene.spectral.grid import DEFAULT_GRID, WavelengthGrid

__all__ = ["multilayer", "FilmTable", "film_table"]


def _kz(n: np.ndarray, n0_sin: np.ndarray) -> np.ndarray:
    """n̂ s_z = sqrt(n̂² - (n_0 sin θ_0)²), branch with Im ≥ 0 (and Re ≥ 0 when Im = 0)."""
    q = np.sqrt(n.astype(np.complex128) ** 2 - n0_sin.astype(np.complex128) ** 2)
    return np.where(q.imag < 0, -q, q)


def multilayer(indices, thicknesses_nm, wavelengths_nm, theta0_rad) -> dict:
    """Composite reflectance and transmittance of a multilayer stack.

    ``indices``: sequence of N+2 complex indices (scalars or arrays over wavelength, shape (W,)): incident
    medium (real), N films, substrate. ``thicknesses_nm``: N film thicknesses. ``wavelengths_nm``: (W,).
    ``theta0_rad``: incident angles (A,) in the incident medium. Returns a dict of (A, W) arrays:
    ``R``, ``T``, and per polarisation ``R_p``, ``R_s``, ``T_p``, ``T_s`` and amplitudes ``r_p``, ``r_s``.
    """
    wl = np.atleast_1d(np.asarray(wavelengths_nm, np.float64))
    th = np.atleast_1d(np.asarray(theta0_rad, np.float64))
    d = np.atleast_1d(np.asarray(thicknesses_nm, np.float64))
    n = [np.broadcast_to(np.asarray(x, np.complex128), wl.shape) for x in indices]
    if len(n) != len(d) + 2:
        raise ValueError(f"{len(n)} indices for {len(d)} films: need films + 2 (incident medium, substrate)")
    if np.any(d < 0):
        raise ValueError("film thicknesses must be >= 0")
    if np.any(np.abs(n[0].imag) > 0):
        raise ValueError("the incident medium must be non-absorbing (real index)")
    n = [x[None, :] for x in n]  # (1, W)
    n0_sin = n[0].real * np.sin(th)[:, None]  # (A, 1) x (1, W) -> (A, W)
    n0_sin = np.broadcast_to(n0_sin, (th.size, wl.size))
    q = [_kz(x, n0_sin) for x in n]  # n̂_j s_z,j, (A, W)
    # s_z,j = q_j / n̂_j, so n̂_j s_z,j-1 = n̂_j q_{j-1} / n̂_{j-1}; write the Fresnel terms with q.
    out = {}
    for pol in ("p", "s"):
        def fresnel(j):
            a, b = n[j - 1], n[j]
            sa, sb = q[j - 1] / a, q[j] / b
            if pol == "p":  # Eqs. 1.20, 1.22
                den = b * sa + a * sb
                return (b * sa - a * sb) / den, 2 * a * sa / den
            den = a * sa + b * sb  # Eqs. 1.21, 1.23
            return (a * sa - b * sb) / den, 2 * a * sa / den

        last = len(n) - 1
        gamma, tau = fresnel(last)  # Eqs. 1.14, 1.15 at B_{N+1}
        for j in range(last - 1, 0, -1):  # films N..1
            r, t = fresnel(j)
            e1 = np.exp(1j * 2 * np.pi / wl[None, :] * q[j] * d[j - 1])  # e^{iφ_j}, Eq. 1.18
            e2 = e1 * e1
            den = 1 + r * gamma * e2
            gamma, tau = (r + gamma * e2) / den, t * tau * e1 / den  # Eqs. 1.16, 1.17
        out[f"r_{pol}"] = gamma
        out[f"R_{pol}"] = np.abs(gamma) ** 2
        sub = n[last]
        if np.all(sub.imag == 0):
            with np.errstate(divide="ignore", invalid="ignore"):  # grazing incidence: q_0 = 0, T = 0
                ratio = (q[last].real) / (q[0].real)
            with np.errstate(invalid="ignore"):
                out[f"T_{pol}"] = np.where(q[0].real > 0, ratio * np.abs(tau) ** 2, 0.0)
        else:
            out[f"T_{pol}"] = np.zeros_like(out[f"R_{pol}"])
    out["R"] = 0.5 * (out["R_p"] + out["R_s"])  # Eq. 1.24
    out["T"] = 0.5 * (out["T_p"] + out["T_s"])  # Eq. 1.25
    return out


@dataclass
class FilmTable:
    """R and T of a stack tabulated per (incident angle, wavelength) (Dong §2.2 preprocessing)."""

    angles_deg: np.ndarray  # (A,) 0..90
    grid: WavelengthGrid
    R: np.ndarray  # (A, N)
    T: np.ndarray  # (A, N)

    def reflectance(self, cos_theta: np.ndarray) -> np.ndarray:
        """R(θ, λ) for incidence cosines (...,) -> (..., N), linear interpolation in angle."""
        c = np.clip(np.asarray(cos_theta, np.float64), 0.0, 1.0)
        ang = np.degrees(np.arccos(c))
        x = np.interp(ang, self.angles_deg, np.arange(self.angles_deg.size, dtype=np.float64))
        i0 = np.clip(np.floor(x).astype(np.int64), 0, self.angles_deg.size - 2)
        f = (x - i0)[..., None].astype(self.R.dtype)
        return (self.R[i0] * (1 - f) + self.R[i0 + 1] * f)


def film_table(layers, substrate, ambient="air", grid: WavelengthGrid = DEFAULT_GRID,
               angle_step_deg: float = 1.0) -> FilmTable:
    """Tabulate R, T of ``ambient | layers | substrate`` for θ in [0, 90°] (step ``angle_step_deg``).

    ``layers``: list of (material, thickness_nm); materials as in :func:`natscene.spectral.indices.complex_index`.
    """
    from natscene.spectral.indices import complex_index

    wl = grid.wavelengths
    idx = [complex_index(ambient, wl)] + [complex_index(m, wl) for m, _ in layers] + [complex_index(substrate, wl)]
    d = [float(t) for _, t in layers]
    n_ang = int(round(90.0 / angle_step_deg)) + 1
    ang = np.linspace(0.0, 90.0, n_ang)
    res = multilayer(idx, d, wl, np.radians(ang))
    return FilmTable(ang, grid, res["R"], res["T"])
