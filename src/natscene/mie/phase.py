"""
Mie phase function of cloud droplets
====================================

Defines the Mie phase tables of Reimschuessel (2011, Ch. 3 "Scattering Function", Fig. 3):

-   :func:`compute_mie_table`: the phase table of a gamma droplet population at the RGB primaries
    (:data:`RGB_WAVELENGTHS_NM`) and a spectral grid, as a :class:`PhaseTable`.
-   :func:`hg_table`: a Henyey–Greenstein table in the same format.
-   :func:`mie_phase_polydisperse`, :func:`gamma_size_distribution`, :func:`water_index`: the population's
    phase function, size distribution and the refractive index of water.
-   :func:`radius_grid`, :func:`angle_grid_deg`, :func:`sphere_integral`, :func:`asymmetry`: the grids and
    integrals over the sphere.
-   :func:`fogbow_peak_deg`, :func:`glory_ring_deg`: where the fogbow and the first glory ring are.
-   :func:`write_table`, :func:`read_table`, :func:`table_channels`, :func:`plot_table`: the table on disk and
    its Fig. 3 plot.

The thesis shades clouds with the wavelength-dependent Mie phase function of water droplets (taken from
Bouthors 2008), looked up by the phase angle. Here it is computed with ``miepython`` for a polydisperse
droplet population:

- droplet radii follow the gamma distribution of Hansen (1971), the standard model of cumulus droplet
  spectra: ``n(r) ∝ r^((1-3b)/b) · exp(-r / (a b))`` with effective radius ``a = r_eff`` (default 10 µm)
  and effective variance ``b = v_eff`` (default 0.1);
- the phase function of the population is the scattering-cross-section-weighted mean of the
  single-sphere phase functions ``(|S1|² + |S2|²)/2`` (unpolarised light):
  ``p(θ) = ∫ n(r) C_sca(r) p_r(θ) dr / ∫ n(r) C_sca(r) dr``;
- the refractive index of water follows a Cauchy fit of Hale & Querry (1973) (absorption neglected in
  the visible): ``n(λ) = 1.3236 + 0.00330 / λ²`` (λ in µm);
- one phase function per wavelength: the dominant wavelengths of the Rec. 709 / sRGB primaries
  (611, 549, 464 nm) for the RGB renderer, and a spectral grid (default 400–700 nm every 20 nm);
- the angular grid is fine (0.01°) near 0° (diffraction peak, silver lining) and near 180° (glory), 0.05°
  around the fogbow and 0.1° elsewhere; every phase function is normalised over the sphere:
  ``2π ∫_{-1}^{1} p(μ) dμ = 1``.

The table is the ``A_m = Mie(θ)`` of Eqs. 4–6 (as ``4π p``: 1 for isotropic scattering, see
:mod:`natscene.mie.solver`). A Henyey–Greenstein table in the same format (:func:`hg_table`, the HG function of
:mod:`natscene.phase`) gives like-for-like comparisons.

References
----------
-   Bouthors, A., Neyret, F., Max, N., Bruneton, E., & Crassin, C. (2008). Interactive multiple anisotropic
    scattering in clouds. Proceedings of the 2008 Symposium on Interactive 3D Graphics and Games, 173–182.
-   Hale, G. M., & Querry, M. R. (1973). Optical constants of water in the 200-nm to 200-µm wavelength region.
    Applied Optics, 12(3), 555–563.
-   Hansen, J. E. (1971). Multiple scattering of polarized light in planetary atmospheres. Part II. Sunlight
    reflected by terrestrial water clouds. Journal of the Atmospheric Sciences, 28(8), 1400–1426.
-   Reimschuessel, C. A. (2011). Rendering Realistic Cloud Effects for Computer Generated Films. MSc thesis,
    Brigham Young University.
"""
from __future__ import annotations

import os
from dataclasses import dataclass, field

import numpy as np

from natscene.phase import hg

__all__ = ["RGB_WAVELENGTHS_NM", "water_index", "gamma_size_distribution", "radius_grid", "angle_grid_deg",
           "sphere_integral", "asymmetry", "mie_phase_polydisperse", "PhaseTable", "compute_mie_table", "hg_table",
           "fogbow_peak_deg", "glory_ring_deg", "table_channels", "write_table", "read_table", "plot_table"]

os.environ.setdefault("MIEPYTHON_USE_JIT", "1")  # 60x faster; must be set before miepython is imported

#: Dominant wavelengths (nm) of the Rec. 709 / sRGB R, G, B primaries.
RGB_WAVELENGTHS_NM = (611.3, 549.1, 464.3)


def water_index(wavelength_nm) -> np.ndarray:
    """Real refractive index of liquid water (Cauchy fit of Hale & Querry 1973, 400–700 nm)."""
    lam = np.asarray(wavelength_nm, np.float64) / 1000.0
    return 1.3236 + 0.00330 / lam**2


def gamma_size_distribution(r_um, r_eff_um: float = 10.0, v_eff: float = 0.1) -> np.ndarray:
    """Hansen's gamma droplet size distribution n(r) (scaled to max 1), r in µm."""
    r = np.asarray(r_um, np.float64)
    alpha = (1.0 - 3.0 * v_eff) / v_eff
    with np.errstate(divide="ignore"):
        logn = alpha * np.log(np.where(r > 0, r, 1.0)) - r / (r_eff_um * v_eff)
    logn = np.where(r > 0, logn, -np.inf)
    return np.exp(logn - np.max(logn))  # in log space: r^alpha overflows for narrow distributions


def radius_grid(r_eff_um: float, v_eff: float, n: int) -> np.ndarray:
    """Radii covering the gamma distribution (its 0.01 % .. 99.99 % quantiles), equally spaced."""
    from scipy.stats import gamma
    shape = (1.0 - 2.0 * v_eff) / v_eff  # r^alpha e^{-r/s}: gamma with shape alpha + 1
    scale = r_eff_um * v_eff
    lo, hi = gamma.ppf([1e-4, 1 - 1e-4], shape, scale=scale)
    return np.linspace(max(lo, 0.05), hi, n)


def angle_grid_deg() -> np.ndarray:
    """Scattering angles (degrees, ascending 0..180): 0.01° near 0 and 180, 0.05° around the fogbow."""
    parts = [np.arange(0.0, 5.0, 0.01), np.arange(5.0, 20.0, 0.05), np.arange(20.0, 120.0, 0.1),
             np.arange(120.0, 160.0, 0.05), np.arange(160.0, 175.0, 0.05), np.arange(175.0, 180.0, 0.01),
             [180.0]]
    return np.unique(np.round(np.concatenate(parts), 6))


def sphere_integral(theta_rad: np.ndarray, p: np.ndarray) -> np.ndarray:
    """``2π ∫ p dμ`` over the sphere (trapezoid in μ = cos θ), for p of shape (n,) or (n, k)."""
    mu = np.cos(theta_rad)
    p = np.asarray(p, np.float64)
    if p.ndim == 1:
        p = p[:, None]
    dmu = -(mu[1:] - mu[:-1])  # theta ascending: mu descending
    return 2 * np.pi * np.sum(0.5 * (p[1:] + p[:-1]) * dmu[:, None], axis=0)


def asymmetry(theta_rad: np.ndarray, p: np.ndarray) -> np.ndarray:
    """Mean cosine g = ``2π ∫ p μ dμ`` (p normalised over the sphere)."""
    mu = np.cos(theta_rad)
    p = np.asarray(p, np.float64)
    if p.ndim == 1:
        p = p[:, None]
    return sphere_integral(theta_rad, p * mu[:, None])


def mie_phase_polydisperse(wavelength_nm: float, theta_rad: np.ndarray, r_eff_um: float = 10.0,
                           v_eff: float = 0.1, n_radii: int = 120) -> np.ndarray:
    """Phase function (1/sr, normalised over the sphere) of the gamma droplet population at one wavelength."""
    import miepython

    m = complex(water_index(wavelength_nm), 0.0)
    lam_um = wavelength_nm / 1000.0
    r = radius_grid(r_eff_um, v_eff, n_radii)
    mu = np.cos(theta_rad)
    nr = gamma_size_distribution(r, r_eff_um, v_eff)
    acc = np.zeros_like(mu)
    wsum = 0.0
    dr = r[1] - r[0]
    for k, rk in enumerate(r):
        x = 2 * np.pi * rk / lam_um
        s1, s2 = miepython.S1_S2(m, x, mu, norm="one")  # (|S1|²+|S2|²)/2 integrates to 1 over 4π
        p_r = 0.5 * (np.abs(s1) ** 2 + np.abs(s2) ** 2)
        qsca = miepython.efficiencies_mx(m, x)[1]
        w = nr[k] * np.pi * rk**2 * qsca * dr * (0.5 if k in (0, len(r) - 1) else 1.0)
        acc += w * p_r
        wsum += w
    p = acc / wsum
    return p / sphere_integral(theta_rad, p)[0]


@dataclass
class PhaseTable:
    """A tabulated phase function per channel: ``theta`` (rad, ascending 0..π), ``rgb`` (n, 3) and
    optionally ``spectral`` (n, L) at ``wavelengths_nm`` (all in 1/sr, normalised over the sphere)."""

    theta: np.ndarray
    rgb: np.ndarray
    spectral: np.ndarray | None = None
    wavelengths_nm: np.ndarray | None = None
    meta: dict = field(default_factory=dict)
    _lut: np.ndarray | None = field(default=None, repr=False)

    @property
    def theta_deg(self) -> np.ndarray:
        return np.degrees(self.theta)

    @property
    def g(self) -> np.ndarray:
        """Asymmetry parameter of each RGB channel."""
        return asymmetry(self.theta, self.rgb)

    def evaluate(self, cos_theta) -> np.ndarray:
        """p(θ) per RGB channel at ``cos_theta`` (any shape) -> shape + (3,), exact table interpolation."""
        th = np.arccos(np.clip(np.asarray(cos_theta, np.float64), -1, 1))
        return np.stack([np.interp(th, self.theta, self.rgb[:, c]) for c in range(3)], axis=-1)

    # A uniform-in-θ lookup table (0.01°) for the hot loops of the solver and the ray marcher.
    LUT_N = 18001

    def lut(self) -> np.ndarray:
        """(LUT_N, 3) float32: ``4π p`` (=: A_m; 1 for isotropic scattering) on θ = 0..180° uniformly."""
        if self._lut is None:
            th = np.linspace(0, np.pi, self.LUT_N)
            self._lut = np.stack([np.interp(th, self.theta, self.rgb[:, c]) for c in range(3)],
                                 axis=-1).astype(np.float32) * np.float32(4 * np.pi)
        return self._lut

    def a_m(self, cos_theta: np.ndarray) -> np.ndarray:
        """``A_m = 4π p(θ)`` per RGB channel from the uniform LUT (linear interpolation), float32."""
        lut = self.lut()
        c = np.clip(np.asarray(cos_theta, np.float32), -1.0, 1.0)
        x = np.arccos(c) * np.float32((self.LUT_N - 1) / np.pi)
        i0 = np.minimum(x.astype(np.int32), self.LUT_N - 2)
        f = (x - i0)[..., None]
        return lut[i0] * (1 - f) + lut[i0 + 1] * f


def compute_mie_table(r_eff_um: float = 10.0, v_eff: float = 0.1, n_radii: int = 120,
                      rgb_nm=RGB_WAVELENGTHS_NM, spectral_nm=tuple(range(400, 701, 20)),
                      theta_deg: np.ndarray | None = None, log=None) -> PhaseTable:
    """The Mie phase table of the droplet population at the RGB primaries and a spectral grid."""
    if r_eff_um <= 0 or not (0 < v_eff < 1 / 3):
        raise ValueError(f"need r_eff > 0 and 0 < v_eff < 1/3, got r_eff={r_eff_um}, v_eff={v_eff}")
    th = np.radians(angle_grid_deg() if theta_deg is None else np.asarray(theta_deg, np.float64))
    rgb = np.stack([mie_phase_polydisperse(w, th, r_eff_um, v_eff, n_radii) for w in rgb_nm], axis=-1)
    spec = []
    for k, w in enumerate(spectral_nm or ()):
        spec.append(mie_phase_polydisperse(w, th, r_eff_um, v_eff, n_radii))
        if log:
            log(f"spectral {k + 1}/{len(spectral_nm)}: {w} nm")
    spectral = np.stack(spec, axis=-1) if spec else None
    meta = {"kind": "mie", "r_eff_um": r_eff_um, "v_eff": v_eff, "n_radii": n_radii,
            "rgb_wavelengths_nm": list(rgb_nm), "size_distribution": "gamma (Hansen 1971)",
            "refractive_index": "1.3236 + 0.00330/lambda_um^2 (Hale & Querry 1973 fit)"}
    return PhaseTable(th, rgb, spectral, np.asarray(spectral_nm, np.float64) if spec else None, meta)


def hg_table(g: float, theta_deg: np.ndarray | None = None) -> PhaseTable:
    """A Henyey–Greenstein phase table (same g in R, G, B) in the format of the Mie table."""
    th = np.radians(angle_grid_deg() if theta_deg is None else np.asarray(theta_deg, np.float64))
    p = hg(np.cos(th), g)
    p = p / sphere_integral(th, p)[0]
    return PhaseTable(th, np.repeat(p[:, None], 3, axis=1), None, None, {"kind": "hg", "g": g})


def fogbow_peak_deg(table: PhaseTable, lo: float = 125.0, hi: float = 165.0) -> np.ndarray:
    """Scattering angle (deg) of the fogbow maximum of each RGB channel between ``lo`` and ``hi``: the
    centroid of the part of the bow above 90 % of its maximum (robust to the residual Mie ripple)."""
    d = table.theta_deg
    sel = (d >= lo) & (d <= hi)
    out = []
    for c in range(3):
        p = table.rgb[sel, c]
        top = p >= 0.9 * p.max()
        out.append(float(np.sum(d[sel][top] * p[top]) / np.sum(p[top])))
    return np.array(out)


def glory_ring_deg(table: PhaseTable, lo: float = 170.0) -> np.ndarray:
    """Scattering angle (deg) of the first glory ring (the outermost local maximum nearest 180° beyond
    the central peak), per RGB channel: the largest-θ local maximum with θ < 180° - 0.3°."""
    d = table.theta_deg
    out = []
    for c in range(3):
        p = table.rgb[:, c]
        idx = np.where((d[1:-1] >= lo) & (d[1:-1] < 179.7) & (p[1:-1] > p[:-2]) & (p[1:-1] >= p[2:]))[0] + 1
        out.append(d[idx[-1]] if len(idx) else np.nan)
    return np.array(out)


# ------------------------------------------------------------------------------------------- I/O
def table_channels(table: PhaseTable) -> tuple[np.ndarray, list[str]]:
    """(1, n, C) image + channel names: theta (deg), R, G, B, then nm<λ> per spectral wavelength."""
    cols = [table.theta_deg, table.rgb[:, 0], table.rgb[:, 1], table.rgb[:, 2]]
    names = ["theta", "R", "G", "B"]
    if table.spectral is not None:
        for k, w in enumerate(table.wavelengths_nm):
            cols.append(table.spectral[:, k])
            names.append(f"nm{int(round(w))}")
    return np.stack(cols, axis=-1)[None].astype(np.float32), names


def write_table(path, table: PhaseTable, stage: str = "mie_table") -> None:
    from natscene.io import write_exr
    img, names = table_channels(table)
    write_exr(path, img, channels=names, attrs={**table.meta, "g_rgb": table.g.tolist()}, stage=stage)


def read_table(path) -> PhaseTable:
    """Read a table written by :func:`write_table` (renormalised over the sphere in float64)."""
    from natscene.errors import InputError
    from natscene.io import read_exr
    img = read_exr(path)
    for c in ("theta", "R", "G", "B"):
        if c not in img.channels:
            raise InputError(f"{path}: not a phase table (missing channel '{c}'); rerun rule mie_table")
    th = np.radians(img.channel("theta")[0].astype(np.float64))
    rgb = img.channel("R", "G", "B")[0].astype(np.float64)
    rgb = rgb / sphere_integral(th, rgb)
    spec_names = [c for c in img.channels if c.startswith("nm")]
    spectral = wl = None
    if spec_names:
        spectral = img.channel(*spec_names)[0].astype(np.float64)
        spectral = spectral.reshape(len(th), -1)
        spectral = spectral / sphere_integral(th, spectral)
        wl = np.array([float(c[2:]) for c in spec_names])
    meta = {k: v for k, v in img.attrs.items() if k in ("kind", "r_eff_um", "v_eff", "g", "n_radii")}
    return PhaseTable(th, rgb, spectral, wl, meta)


def plot_table(table: PhaseTable, cartesian_png, polar_png, hg: PhaseTable | None = None) -> None:
    """Fig. 3 of the thesis: Cartesian (log intensity vs phase angle) and polar plots of R, G, B."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from natscene.io import atomic_path

    d = table.theta_deg
    cols = ["#d62728", "#2ca02c", "#1f77b4"]
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.2))
    for ax, (lo, hi) in zip(axes, [(0, 180), (125, 160), (165, 180)]):
        sel = (d >= lo) & (d <= hi)
        for c in range(3):
            ax.plot(d[sel], table.rgb[sel, c], color=cols[c], lw=1)
        if hg is not None:
            ax.plot(hg.theta_deg[(hg.theta_deg >= lo) & (hg.theta_deg <= hi)],
                    hg.rgb[(hg.theta_deg >= lo) & (hg.theta_deg <= hi), 1], "k--", lw=1,
                    label=f"HG g={hg.meta.get('g', 0):.2f}")
            ax.legend()
        ax.set_yscale("log")
        ax.set_xlim(lo, hi)
        ax.set_xlabel("phase angle θ (deg)")
        ax.set_ylabel("p(θ) (1/sr)")
    axes[0].set_title(f"Mie, r_eff={table.meta.get('r_eff_um')} µm, v_eff={table.meta.get('v_eff')}")
    axes[1].set_title("fogbow")
    axes[2].set_title("glory")
    fig.tight_layout()
    with atomic_path(cartesian_png) as tmp:
        fig.savefig(tmp, dpi=80, format="png")
    plt.close(fig)

    fig = plt.figure(figsize=(5.5, 5.5))
    ax = fig.add_subplot(projection="polar")
    ax.set_theta_zero_location("N")  # incoming light up, as in the thesis
    for c in range(3):
        r = np.log10(table.rgb[:, c]) - np.log10(table.rgb.min()) + 0.1
        ax.plot(table.theta, r, color=cols[c], lw=0.8)
        ax.plot(-table.theta, r, color=cols[c], lw=0.8)
    ax.set_title("Mie phase (log10 radius), light from the top")
    ax.set_yticklabels([])
    with atomic_path(polar_png) as tmp:
        fig.savefig(tmp, dpi=80, format="png")
    plt.close(fig)
