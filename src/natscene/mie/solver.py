"""
Point-to-point scattering passes
================================

Defines the light scattering passes with the Mie/isotropic ratio R_i of Reimschuessel (2011, Ch. 3
"Simulating light scattering", Eqs. 1–5, Figs. 6–8):

-   :func:`solve`: run the scattering passes on a point cloud; the result as a :class:`Solution`.
-   :func:`update_mie_isotropic_ratio`: Eq. 1, the thesis' main function, after a pass.
-   :func:`neighbour_pairs`: the pairs of points that exchange light.
-   :func:`cone_averaged_lut`: A_m averaged over a cone around each phase angle.
-   :func:`full_neighbourhood_fraction`: the fraction of isotropically scattered light a point would deposit
    in a full neighbourhood.
-   :func:`save_solution`, :func:`load_solution`: the solution on disk.

Every pass exchanges light between neighbouring points (within ``radius`` lattice spacings, found once
with a KD-tree, ``scipy.spatial.cKDTree.query_pairs``; never all pairs), in both directions of every pair,
vectorised over all pairs with numpy:

- Eq. 3, attenuation by distance: ``A_d = exp(-|P_src - P_dst| (D_src + D_dst)/2 σ_e)``; pairs with
  ``A_d`` below ``min_attenuation`` are dropped (the thesis' negligible events);
- ``A_m = Mie(θ)``, θ the phase angle between the source's prominent light direction ``L_src`` (the
  direction the light *travels*) and the direction from ``P_src`` to ``P_dst``; ``A_m`` is the table's
  ``4π p(θ)``, so that the isotropic phase is 1, the ``(1 - R_src)`` term of Eq. 4;
- Eq. 4: ``Co_dst += A_d (A_m R_src + (1 - R_src)) · k_src,dst · Ci_src`` and Eq. 5:
  ``Lsum_dst += A_d (A_m R_src + (1 - R_src)) · k_src,dst · Ci_src · (P_dst - P_src)/|…|``.
  The thesis' "percentage" ``A_m`` becomes physical through the transfer kernel
  ``k = n_src s_src h² / (4π d²)``: ``s_src`` the fraction of the light in the source cell that scatters
  there, ``h²/d²`` the solid angle of the receiving cell, ``n_src ≤ 1`` renormalises each source so that
  it never sends more than it scattered (albedo ``ω``, default 1: water droplets do not absorb visible
  light). No pass creates energy: ``Σ s_dst Co_dst ≤ ω Σ s_src Ci_src``;
- after each pass (main function, :func:`update_mie_isotropic_ratio`): Eq. 1, ``R_i ← R_i - R_i e^(-|L_sum|)``,
  ``L_i ← L_sum / |L_sum|``, ``Ci += Co``. ``|L_sum|`` is measured, as the thesis argues (vectors from all directions cancel, from one
  direction add up), by the coherence of the received light, the length of the light-weighted mean
  direction (1: all from one direction, 0: from all directions), times ``coherence_scale``: without a
  relative measure the absolute light level (an arbitrary unit) would decide R_i;
- each pass propagates the light scattered in the previous pass (one more scattering order), so that the
  total is the sum of orders (re-sending the accumulated Ci each pass would count light again and again);
- Eq. 2 maps the result to [0, 1]: ``Co = 1 - exp(-Ci_scattered)`` per channel (the scattered light;
  the direct sunlight ``Ci_0`` is kept separately for the final pass, as the thesis reads it from the
  input point cloud).

The solution depends on the sun direction only; it is reused for any view and light colour.

References
----------
-   Reimschuessel, C. A. (2011). Rendering Realistic Cloud Effects for Computer Generated Films. MSc thesis,
    Brigham Young University.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.spatial import cKDTree

from natscene.color import LUMA_709
from natscene.errors import InputError
from natscene.mie.phase import PhaseTable
from natscene.mie.points import PointCloud

__all__ = ["Solution", "neighbour_pairs", "cone_averaged_lut", "full_neighbourhood_fraction",
           "update_mie_isotropic_ratio", "solve", "save_solution", "load_solution"]


@dataclass
class Solution:
    """The solved point cloud (Table 1 after the passes)."""

    points: PointCloud
    ratio: np.ndarray          # (N,) R_i
    direction: np.ndarray      # (N, 3) L_i (unit; light propagation)
    scattered: np.ndarray      # (N, 3) Σ passes of Co (linear, fraction of the sun)
    co: np.ndarray             # (N, 3) Eq. 2 output: 1 - exp(-scattered)
    energy: np.ndarray         # (passes + 1, 3) Σ h² s_i Ci_i per pass (pass 0: direct sunlight)
    passes: int
    params: dict = field(default_factory=dict)
    # per-sun quantities derived by the final pass (brickmap fields, the sun's optical-depth lattice,
    # the cone-averaged LUT): computed on the first frame and reused by every later frame of this sun
    cache: dict = field(default_factory=dict, repr=False, compare=False)


def neighbour_pairs(points: PointCloud, radius: float, min_attenuation: float):
    """Unique pairs (i < j) within ``radius`` spacings with A_d >= min_attenuation: i, j, unit u (i→j),
    distance, A_d (Eq. 3)."""
    tree = cKDTree(points.index.astype(np.float32))  # lattice units: exact integer distances
    pairs = tree.query_pairs(radius * (1 + 1e-6), output_type="ndarray")
    i, j = pairs[:, 0].astype(np.int32), pairs[:, 1].astype(np.int32)
    delta = points.position[j] - points.position[i]
    dist = np.linalg.norm(delta, axis=1).astype(np.float32)
    a_d = np.exp(-dist * (points.density[i] + points.density[j]) * 0.5 * np.float32(points.sigma_e))
    keep = a_d >= min_attenuation
    i, j, delta, dist, a_d = i[keep], j[keep], delta[keep], dist[keep], a_d[keep]
    return i, j, (delta / dist[:, None]).astype(np.float32), dist, a_d.astype(np.float32)


def cone_averaged_lut(table: PhaseTable, half_angle: float, n_theta: int = 3601, n_dirs: int | None = None) -> np.ndarray:
    """``A_m`` averaged over a cone of ``half_angle`` (rad) around each phase angle: (n_theta, 3) on a
    uniform θ grid 0..π. A receiving cell of side h at distance d subtends about h²/d² sr; sampling the
    forward peak (≈ 1° wide, ≈ 600/sr) at the cell's centre alone would send almost all light straight
    along lattice axes, so the exchange uses the mean of the phase function over the cell's solid angle.

    The mean is integrated exactly on the table's own (fine) angular grid, not sampled: for a cone of
    half-angle α around an axis at angle θ from the light, the directions at angle θ' from the light
    that fall inside the cone are the azimuths with ``cos θ cos θ' + sin θ sin θ' cos φ >= cos α``, a
    fraction ``f = arccos((cos α - cos θ cos θ') / (sin θ sin θ')) / π`` of the circle, so
    ``<p> = ∫ p(θ') f(θ, θ') 2π sin θ' dθ' / (2π (1 - cos α))``. (Sampling the cone with a few hundred
    directions aliases the 1°-wide diffraction peak into ±50 % noise in θ, which the renderer shows as
    speckle wherever L_i varies.) ``n_dirs`` is accepted for compatibility and ignored."""
    th = np.linspace(0, np.pi, n_theta)
    tp = np.asarray(table.theta, np.float64)
    # trapezoid weights of ∫ · sin θ' dθ' on the table grid
    dt = np.diff(tp)
    wq = np.zeros_like(tp)
    wq[:-1] += 0.5 * dt
    wq[1:] += 0.5 * dt
    wq *= np.sin(tp)
    ca = np.cos(half_angle)
    out = np.empty((n_theta, 3), np.float64)
    for lo in range(0, n_theta, 256):  # blocks of θ: (256, n_table) at a time
        t = th[lo:lo + 256, None]
        num = ca - np.cos(t) * np.cos(tp)[None]
        den = np.sin(t) * np.sin(tp)[None]
        with np.errstate(divide="ignore", invalid="ignore"):
            x = np.where(den > 1e-12, num / np.where(den > 1e-12, den, 1.0), np.where(num <= 0, -1.0, 2.0))
        f = np.arccos(np.clip(x, -1.0, 1.0)) / np.pi  # x >= 1: outside the cone (0), x <= -1: whole circle (1)
        kw = f * wq[None]
        out[lo:lo + 256] = (kw @ table.rgb) * 2 * np.pi / (2 * np.pi * (1 - ca))
    return (out * 4 * np.pi).astype(np.float32)


def full_neighbourhood_fraction(density, s, sigma_e: float, h: float, radius: float,
                                min_attenuation: float) -> np.ndarray:
    """F_full(D_i): the fraction of isotropically scattered light a point of density D_i would deposit in
    a complete neighbourhood (all lattice offsets within ``radius``) of the same density."""
    r = int(np.floor(radius))
    o = np.mgrid[-r:r + 1, -r:r + 1, -r:r + 1].reshape(3, -1).T
    d2 = (o**2).sum(1)
    d2 = d2[(d2 > 0) & (d2 <= radius * radius * (1 + 1e-6))]
    c2, count = np.unique(d2, return_counts=True)
    d = np.sqrt(c2) * h
    dens = np.asarray(density, np.float64)[:, None]
    a_d = np.exp(-d[None] * dens * sigma_e)
    a_d = np.where(a_d >= min_attenuation, a_d, 0.0)
    f = (a_d * (count / (4 * np.pi * c2))[None]).sum(1) * np.asarray(s, np.float64)
    return np.maximum(f, 1e-30)


def _lookup(lut: np.ndarray, cos: np.ndarray) -> np.ndarray:
    n = lut.shape[0]
    x = np.arccos(np.clip(cos, -1.0, 1.0)) * np.float32((n - 1) / np.pi)
    i0 = np.minimum(x.astype(np.int32), n - 2)
    f = (x - i0)[:, None]
    return lut[i0] * (1 - f) + lut[i0 + 1] * f


def update_mie_isotropic_ratio(ratio: np.ndarray, direction: np.ndarray, lvec: np.ndarray, lmag: np.ndarray,
                               coherence_scale: float) -> tuple[np.ndarray, np.ndarray]:
    """Eq. 1, the thesis' main function, after a pass: the Mie/isotropic ratio ``R_i <- R_i - R_i e^(-|L_sum|)``
    and the prominent light direction ``L_i <- L_sum / |L_sum|`` of every point that received light.

    ``lvec`` (N, 3): the light-weighted sum of the received light's directions (Eq. 5's L_sum); ``lmag`` (N,): the
    received light (luminance); ``|L_sum|`` is their coherence ``|lvec| / lmag`` (1: all from one direction, 0: from
    all directions) times ``coherence_scale`` (see the module docstring). Returns (ratio float32 (N,), direction);
    ``direction`` (N, 3) is updated in place."""
    length = np.linalg.norm(lvec, axis=1)
    got = (lmag > 0) & (length > 0)
    coherence = np.where(got, length / np.where(got, lmag, 1), 0.0)
    ratio = np.where(got, ratio - ratio * np.exp(-coherence_scale * coherence), ratio).astype(np.float32)
    direction[got] = (lvec[got] / length[got, None]).astype(np.float32)
    return ratio, direction


def solve(points: PointCloud, table: PhaseTable, passes: int = 10, radius: float = 2.5,
          coherence_scale: float = 5.0, albedo: float = 1.0, min_attenuation: float = 1e-3,
          log=None, keep_history: bool = False):
    """Run ``passes`` scattering passes; returns a :class:`Solution` (and the R_i history if asked)."""
    if passes < 0 or radius < 1 or not (0 <= albedo <= 1):
        raise InputError(f"mie.solver: need passes >= 0, radius >= 1 spacing and 0 <= albedo <= 1 "
                         f"(got {passes}, {radius}, {albedo})")
    n = len(points.density)
    i, j, u, dist, a_d = neighbour_pairs(points, radius, min_attenuation)
    h = np.float32(points.spacing)
    # Distance classes (lattice distances are few) -> cone-averaged A_m tables (solid angle ~ h²/d²).
    d_lat = np.round((dist / h) ** 2).astype(np.int32)
    classes, cls = np.unique(d_lat, return_inverse=True)
    # cone of solid angle h²/d² = 1/c2: 2π (1 - cos α) = 1/c2
    luts = [cone_averaged_lut(table, float(np.arccos(max(-1.0, 1 - 1 / (2 * np.pi * c2))))) for c2 in classes]
    members = [np.flatnonzero(cls == q) for q in range(len(classes))]
    s = points.interact
    f_full = full_neighbourhood_fraction(points.density, s, points.sigma_e, float(h), radius, min_attenuation)
    geo = a_d * h * h / (np.float32(4 * np.pi) * dist * dist)  # A_d · h²/(4π d²)
    s = points.interact
    if log:
        log(f"{n} points, {len(i)} neighbour pairs (radius {radius} spacings), {passes} passes")
    ratio = np.ones(n, np.float32)
    direction = np.repeat(-points.sun_dir[None].astype(np.float32), n, axis=0)
    light = np.repeat(points.ci0[:, None], 3, axis=1).astype(np.float32)  # Ci of the current order
    scattered = np.zeros((n, 3), np.float64)
    energy = [np.sum(s[:, None] * light, axis=0, dtype=np.float64) * h * h]
    history = [ratio.copy()]
    luma = LUMA_709.astype(np.float32)
    # Both directions of every pair: (src, dst, u src->dst).
    dirs = ((i, j, u), (j, i, -u))
    for k in range(passes):
        # Phase weights per direction: A_m R_src + (1 - R_src)  (Eq. 4's bracket), float32 (E, 3).
        phase = []
        fsum = np.zeros((n, 3))
        for src, dst, ud in dirs:
            cos = np.einsum("ij,ij->i", direction[src], ud)
            r = ratio[src][:, None]
            ph = np.empty((len(src), 3), np.float32)
            for lut, sel in zip(luts, members):
                ph[sel] = _lookup(lut, cos[sel])
            ph = ph * r + (1 - r)
            ph *= geo[:, None]
            phase.append(ph)
            w = s[dst]
            for c in range(3):
                fsum[:, c] += np.bincount(src, ph[:, c] * w, minlength=n)
        # n_src: the neighbourhood stands for the whole medium (a source inside a homogeneous region
        # deposits all it scatters, ω/F_full), light escapes where neighbours are missing, and a source
        # never sends more than ω times what scattered in it (ω/F_actual).
        norm = np.minimum(albedo / f_full[:, None], albedo / np.maximum(fsum, 1e-30))
        emit = (norm * s[:, None] * light).astype(np.float32)
        co = np.zeros((n, 3))
        lvec = np.zeros((n, 3))
        lmag = np.zeros(n)
        for (src, dst, ud), ph in zip(dirs, phase):
            contrib = ph * emit[src]
            for c in range(3):
                co[:, c] += np.bincount(dst, contrib[:, c], minlength=n)
            lum = contrib @ luma
            lmag += np.bincount(dst, lum, minlength=n)
            for c in range(3):
                lvec[:, c] += np.bincount(dst, lum * ud[:, c], minlength=n)
        del phase
        # Main function (Eq. 1): R_i <- R_i - R_i exp(-|L_sum|), L_i <- L_sum/|L_sum|, Ci += Co.
        ratio, direction = update_mie_isotropic_ratio(ratio, direction, lvec, lmag, coherence_scale)
        scattered += co
        light = co.astype(np.float32)
        energy.append(np.sum(s[:, None] * co, axis=0) * h * h)
        if keep_history:
            history.append(ratio.copy())
        if log:
            log(f"pass {k + 1}/{passes}: scattered energy {energy[-1][1]:.4g} "
                f"(direct {energy[0][1]:.4g}), mean R {ratio.mean():.3f}")
    sol = Solution(points, ratio, direction, scattered.astype(np.float32),
                   (1.0 - np.exp(-scattered)).astype(np.float32), np.array(energy), passes,
                   {"radius": radius, "coherence_scale": coherence_scale, "albedo": albedo,
                    "min_attenuation": min_attenuation, "table": table.meta.get("kind", "?")})
    return (sol, history) if keep_history else sol


# ------------------------------------------------------------------------------------------- I/O
def save_solution(path, sol: Solution) -> None:
    """Write the solution as a compressed ``.npz`` (atomically)."""
    from natscene.io import atomic_path
    p = sol.points
    with atomic_path(path) as tmp:
        with open(tmp, "wb") as f:
            np.savez_compressed(
                f, position=p.position, density=p.density, ci0=p.ci0, index=p.index, origin=p.origin,
                basis=p.basis, shape=np.array(p.shape), spacing=p.spacing, sigma_e=p.sigma_e,
                sun_dir=p.sun_dir, sun_in=p.sun_in, ratio=sol.ratio, direction=sol.direction,
                scattered=sol.scattered, co=sol.co, energy=sol.energy, passes=sol.passes,
                params=np.array(repr(sol.params)))


def load_solution(path) -> Solution:
    """Read a solution written by :func:`save_solution`."""
    import ast
    from pathlib import Path
    path = Path(path)
    if not path.is_file():
        raise InputError(f"{path}: point-cloud solution not found; run rule point_scatter")
    z = np.load(path, allow_pickle=False)
    pts = PointCloud(z["position"], z["density"], z["ci0"], z["index"], z["origin"], z["basis"],
                     tuple(int(x) for x in z["shape"]), float(z["spacing"]), float(z["sigma_e"]),
                     z["sun_dir"], float(z["sun_in"]))
    return Solution(pts, z["ratio"], z["direction"], z["scattered"], z["co"], z["energy"], int(z["passes"]),
                    ast.literal_eval(str(z["params"])))
