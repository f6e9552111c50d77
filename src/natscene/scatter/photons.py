"""
Photon tracing
==============

Defines the photon tracing of the all-orders transport, every scattering order of the sun's and the sky's light
(tallied toward the camera for Dobashi et al. 2012, Eq. 5's view integral):

-   :class:`SunBeam`: parallel sunlight of unit irradiance.
-   :class:`SkySource`: the light of a sky dome in four channels (R, G, B and the ground).
-   :func:`trace`: trace photons through the medium and tally the in-scatter caches (:class:`InscatterTally`).

Photons enter the cloud as a parallel beam from the sun (:class:`SunBeam`) or from a direction of the sky
dome (:class:`SkySource`), travel by delta tracking through mu_t = sigma_t k rho (:mod:`.majorant`) and
scatter by Henyey–Greenstein(g) with albedo 1 (the albedo enters the composition as beta^k, :mod:`.bands`).
Along the flight toward the k-th collision (the photon has scattered k - 1 times) the photon's contribution to
the light that scatters toward the camera is tallied in a voxel cache at every tentative collision x of delta
tracking:

    C_b(cell) += Φ (mu_t(x) / mu_bar(x)) p(ω · ω_cam(x), g) w(x)        for k in band b,

Φ the photon's power, ω its direction, ω_cam(x) the unit vector from x toward the camera, w(x) the camera
transmittance (:func:`natscene.scatter.inscatter.visibility`). The tentative collisions are a Poisson process of
rate mu_bar along the flight, each reached with the transmittance, so C_b(cell) estimates
∫_cell w(x) sigma_t(x) S_b(x) dV, S_b the in-scattered radiance toward the camera of the orders of band b
(:mod:`.inscatter` divides by ∫ w sigma_t). It is the expected-value (track-length-like) estimator of delta
tracking (Spanier & Gelbard 1969; the volume photon map of Jensen & Christensen 1998 without its density kernel),
shared by every pixel that looks at the cell; ``tally_rate`` keeps a floor of tentative collisions per voxel
length in thin cloud, where real collisions are rare.

From order ``similarity_order`` on (32 by default) a photon flies in the similar medium of high-order similarity,
sigma_t (1 - g) and isotropic, each collision standing for a geometric number of real ones (:func:`_walk`): the
long walks of a thick cloud cost (1 - g) of their collisions.

The sun's first flight (order 1) is not tallied: single scattering is ray-marched exactly (Eq. 5). The sky's
photons are tallied from their first flight. A histogram of the light per exact order (whole cloud, weighted by
w, collision estimator at the real collisions) gives each band's order distribution (:func:`natscene.scatter.bands.order_distribution`).

With a weight window (:mod:`.importance`) a photon that enters what the camera sees splits and one deep inside
the cloud is rouletted, at every collision; each photon carries a weight multiplier. With ``camera_lobe`` > 0 the
scatterings the camera sees are biased toward it (angle biasing, :func:`_new_direction`: a share of the new
directions drawn around the direction to the camera, each photon weighted by HG / the mixture's pdf), so that
the flights that carry the tally's forward peak are sampled often and lightly.

The walks run in one symbolic loop of events (:func:`_walk`): each iteration moves every lane's photon by one
event of delta tracking (a tentative collision or a majorant cell crossed), and a lane whose photon dies takes
the next one. Split copies are written out and walked in a second pass, and so on. A loop over whole flights
(or whole walks) keeps a SIMD packet busy until its longest flight ends, with most of its lanes idle; the loop
of events keeps most of them busy (docs/stages/precompute.md).

The tallies are sums of many small terms added by parallel threads in no fixed order; floating-point
atomics would make every run's last bits differ. They are therefore accumulated in 64-bit fixed point
(``FIXED`` units per unit of photon power: integer addition is associative), so the same seed and settings
give the same bytes on any thread count.

References
----------
-   Dobashi, Y., Iwasaki, W., Ono, A., Yamamoto, T., Yue, Y., & Nishita, T. (2012). An inverse problem approach
    for automatically adjusting the parameters for rendering clouds using photographs. ACM Transactions on
    Graphics, 31(6).
-   Jensen, H. W., & Christensen, P. H. (1998). Efficient simulation of light transport in scenes with
    participating media using photon maps. Proceedings of ACM SIGGRAPH 1998, 311–320.
-   Spanier, J., & Gelbard, E. M. (1969). Monte Carlo Principles and Neutron Transport Problems. Addison-Wesley.
-   Wyman, D. R., Patterson, M. S., & Wilson, B. C. (1989). Similarity relations for anisotropic scattering in
    Monte Carlo simulations of deeply penetrating neutral particles. Journal of Computational Physics, 81(1).
-   Zhao, S., Ramamoorthi, R., & Bala, K. (2014). High-order similarity relations in radiative transfer. ACM
    Transactions on Graphics, 33(4), 104.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

import natscene.variant  # noqa: F401
import drjit as dr
import mitsuba as mi

from natscene.scatter.bands import SKY_GROUPS, band_table
from natscene.scatter.majorant import MajorantGrid, flight_event
from natscene.scatter.medium import ray_box_dr
from natscene.scatter.phase import hg_dr, hg_p1_dr, hg_sample_cos_dr

__all__ = ["SunBeam", "SkySource", "InscatterTally", "trace"]


FIXED = float(2 ** 32)      # fixed-point units per unit of (tally value / photon power)


def _fixed(x):
    """Fixed-point UInt64 of a non-negative Float (rounded to nearest)."""
    return mi.UInt64(dr.round(x * FIXED))


def _vec(x) -> "mi.ScalarVector3f":
    return mi.ScalarVector3f(*[float(e) for e in x])


def _frame(s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    a = np.cross(s, [0.0, 1.0, 0.0] if abs(s[1]) < 0.9 else [1.0, 0.0, 0.0])
    a /= np.linalg.norm(a)
    return a, np.cross(s, a)


class SunBeam:
    """Parallel sunlight of unit irradiance: photons start on a plane perpendicular to the sun, uniformly
    over the texels whose rays can meet density (majorant > 0, dilated), so almost every photon enters the
    cloud; each carries the same power (lit area / n)."""

    channels = 1
    groups = (0,)         # the order histogram of each channel

    def __init__(self, grid: MajorantGrid, bbox_min, bbox_max, sun_dir, texels: int = 128, dilate: int = 2):
        from scipy.ndimage import binary_dilation
        s = np.asarray(sun_dir, np.float64)
        s = s / np.linalg.norm(s)
        a, b = _frame(s)
        lo, hi = np.asarray(bbox_min, np.float64), np.asarray(bbox_max, np.float64)
        c = (lo + hi) / 2
        corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])]) - c
        ua, ub = corners @ a, corners @ b
        R = float(np.linalg.norm(hi - lo))
        ta, tb = (ua.max() - ua.min()) / texels, (ub.max() - ub.min()) / texels
        ia, ib = np.meshgrid(np.arange(texels) + 0.5, np.arange(texels) + 0.5, indexing="ij")
        pa, pb = ua.min() + ia * ta, ub.min() + ib * tb
        cx, cy, cz = grid.shape
        ts = np.arange(0.0, 2 * R, 0.5 * float(np.min(grid.cell)))
        lit = np.zeros((texels, texels), bool)
        for t in np.array_split(ts, max(1, len(ts) // 16)):
            pts = c + a * pa[..., None, None] + b * pb[..., None, None] + s * (R - t[None, None, :, None])
            q = np.floor((pts - grid.origin) / grid.cell).astype(np.int64)
            ok = ((q >= 0) & (q < np.array([cx, cy, cz]))).all(-1)
            q = np.where(ok[..., None], q, 0)
            lit |= (ok & (grid.values[q[..., 2], q[..., 1], q[..., 0]] > 0)).any(-1)
        lit = binary_dilation(lit, iterations=dilate)
        self.idx = np.flatnonzero(lit.ravel()).astype(np.uint32)
        self.texels = texels
        self.area = float(self.idx.size * ta * tb)
        self._frame = (a, b, s, c, R, float(ua.min()), float(ub.min()), float(ta), float(tb))
        self._idx_dr = mi.UInt32(self.idx) if self.idx.size else None

    def sample(self, n: int, rng):
        """(origins, directions, [power]) of ``n`` photons."""
        a, b, s, c, R, ua0, ub0, ta, tb = self._frame
        j = mi.UInt32(dr.minimum(rng.next_float32() * self.idx.size, self.idx.size - 1))
        tex = dr.gather(mi.UInt32, self._idx_dr, j)
        ia = tex // self.texels
        ib = tex - ia * self.texels
        pa = ua0 + (mi.Float(ia) + rng.next_float32()) * ta
        pb = ub0 + (mi.Float(ib) + rng.next_float32()) * tb
        o = mi.Point3f(_vec(c) + _vec(a) * pa + _vec(b) * pb + _vec(s) * R)
        d = mi.Vector3f(dr.zeros(mi.Vector3f, n) + _vec(-s))
        return o, d, [dr.full(mi.Float, self.area / n, n)]


class SkySource:
    """Light from a :class:`natscene.scatter.skylight.Dome` in four channels: the dome's R, G, B and a
    unit-radiance lower hemisphere (the ground). A direction ω (toward the source) is drawn from the dome's
    luminance table (probability 1 - ``p_ground``) or uniformly below the horizon; the photon starts on a
    face of ``box`` that faces ω, with probability ∝ the face's projected area, and carries
    L_c(ω) A_proj(ω) / (pdf(ω) n) in channel c. With ``ground`` (a :class:`natscene.scatter.skylight.GroundLight`
    and the :class:`natscene.scatter.medium.Medium` of its shadow) a photon from the ground carries the ground's
    skylit radiance in R, G, B and, in the ground channel, the sun's transmittance through the cloud to the ground
    point it leaves."""

    channels = 4
    groups = SKY_GROUPS   # the order histogram of each channel: the dome's R, G, B one, the ground its own

    def __init__(self, dome, box_min, box_max, p_ground: float = 0.25, ground=None):
        from natscene.scatter.skylight import cell_directions
        self.dome = dome
        rgb = np.asarray(dome.rgb, np.float64)
        self.n_theta, self.n_phi = rgb.shape[:2]
        lum = rgb @ np.array([0.2126, 0.7152, 0.0722])
        lum = np.maximum(lum, 0.0).ravel()
        has_sky = lum.sum() > 0
        self.p_ground = float(p_ground) if has_sky else 1.0
        p_cell = lum / lum.sum() if has_sky else np.full(lum.size, 1.0 / lum.size)
        self.cdf = np.cumsum(p_cell)
        self.cdf[-1] = 1.0
        self.p_cell = p_cell
        self.lo = np.asarray(box_min, np.float64)
        self.hi = np.asarray(box_max, np.float64)
        self._dirs = cell_directions(self.n_theta, self.n_phi)
        self._rgb_dr = [mi.Float(rgb[..., c].ravel()) for c in range(3)]
        self._pcell_dr = mi.Float(p_cell)
        self._cdf_dr = mi.Float(self.cdf)
        self.lobe = None          # (direction toward the camera, g, share): see toward()
        self.ground = ground      # (GroundLight, Medium) or None: the open, unit-radiance ground

    def toward(self, camera_position, g: float = 0.7, share: float = 0.2) -> "SkySource":
        """This source with a share of its directions drawn from an HG(``g``) lobe of photon directions around
        the direction from the box's centre to ``camera_position``: the skylight that reaches the camera after
        one forward scattering comes from the dome behind the cloud, a small cone that the dome's luminance
        rarely samples (at g 0.85 the phase function's forward peak is 80× its mean). A mixture of the two
        densities (each direction weighted by 1 / the mixture's pdf) stays unbiased."""
        import copy
        c = np.asarray(camera_position, np.float64) - (self.lo + self.hi) / 2
        out = copy.copy(self)
        out.lobe = (c / np.linalg.norm(c), float(g), float(share))
        return out

    def _pdf_radiance(self, om):
        """(pdf of the dome's own sampling at om, radiance per channel at om)."""
        omega_cell = 2.0 * math.pi / (self.n_theta * self.n_phi)
        up = om.y > 0
        it = mi.UInt32(dr.clip(dr.floor((1.0 - om.y) * self.n_theta), 0, self.n_theta - 1))
        phi = dr.atan2(om.x, om.z)
        phi = dr.select(phi < 0, phi + 2.0 * math.pi, phi)
        ip = mi.UInt32(dr.clip(dr.floor(phi / (2.0 * math.pi) * self.n_phi), 0, self.n_phi - 1))
        cell = it * self.n_phi + ip
        pdf = dr.select(up, (1.0 - self.p_ground) * dr.gather(mi.Float, self._pcell_dr, cell) / omega_cell,
                        mi.Float(self.p_ground / (2.0 * math.pi)))
        rad = [dr.select(up, dr.gather(mi.Float, self._rgb_dr[c], cell), 0.0) for c in range(3)]
        rad.append(dr.select(up, 0.0, 1.0))
        return pdf, rad

    def sample(self, n: int, rng):
        u_sel = rng.next_float32()
        ground = u_sel < self.p_ground
        # upper hemisphere: a cell from the luminance CDF, uniform inside it
        u_cell = rng.next_float32()
        cell = mi.UInt32(dr.binary_search(0, self.cdf.size - 1,
                                          lambda i: dr.gather(mi.Float, self._cdf_dr, i) < u_cell))
        it = cell // self.n_phi
        ip = cell - it * self.n_phi
        mu_up = 1.0 - (mi.Float(it) + rng.next_float32()) / self.n_theta
        phi_up = 2.0 * math.pi * (mi.Float(ip) + rng.next_float32()) / self.n_phi
        # lower hemisphere: uniform
        mu_dn = -rng.next_float32()
        phi_dn = 2.0 * math.pi * rng.next_float32()
        mu = dr.select(ground, mu_dn, mu_up)
        phi = dr.select(ground, phi_dn, phi_up)
        sn = dr.safe_sqrt(1.0 - mu * mu)
        om = mi.Vector3f(sn * dr.sin(phi), mu, sn * dr.cos(phi))     # toward the source
        lobe = self.lobe
        if lobe is not None:
            c, g_l, share = lobe
            use = rng.next_float32() < share
            d_l = _scatter_dir(mi.Vector3f(dr.zeros(mi.Vector3f, n) + _vec(c)), g_l, rng)
            om = dr.select(use, -d_l, om)
        pdf, rad = self._pdf_radiance(om)
        if self.ground is not None:
            light, med = self.ground
            below = om.y <= 0
            rad = [r + dr.select(below, float(v), 0.0) for r, v in zip(rad[:3], light.sky)] + [rad[3]]
        if lobe is not None:
            pdf = (1.0 - share) * pdf + share * hg_dr(dr.dot(-om, _vec(c)), g_l)
        # a face of the box facing om, chosen by projected area, and a uniform point on it
        ext = [float(e) for e in self.hi - self.lo]
        areas = (ext[1] * ext[2], ext[0] * ext[2], ext[0] * ext[1])
        ax = [dr.abs(om.x) * areas[0], dr.abs(om.y) * areas[1], dr.abs(om.z) * areas[2]]
        a_proj = ax[0] + ax[1] + ax[2]
        u = rng.next_float32() * a_proj
        pick_x = u < ax[0]
        pick_y = ~pick_x & (u < ax[0] + ax[1])
        pick_z = ~pick_x & ~pick_y
        u1, u2 = rng.next_float32(), rng.next_float32()
        lo = _vec(self.lo)
        x = dr.select(pick_x, dr.select(om.x > 0, float(self.hi[0]), float(self.lo[0])), lo.x + u1 * ext[0])
        y = dr.select(pick_x, lo.y + u1 * ext[1], dr.select(pick_y, dr.select(om.y > 0, float(self.hi[1]), float(self.lo[1])),
                                                             lo.y + u2 * ext[1]))
        z = dr.select(pick_z, dr.select(om.z > 0, float(self.hi[2]), float(self.lo[2])), lo.z + u2 * ext[2])
        eps = 1e-4 * float(np.linalg.norm(ext))
        o = mi.Point3f(x, y, z) + om * eps
        d = -om
        if self.ground is not None:
            rad[3] = rad[3] * dr.exp(-float(light.extinction) * med.ground_sun_depth(o, om))
        base = a_proj / (pdf * n)
        return mi.Point3f(o), mi.Vector3f(d), [r * base for r in rad]


@dataclass
class InscatterTally:
    """Cache numerators per cache: ``numerators[i]`` (channels, len(band_sets[i]), cz, cy, cx) in cells of
    ``factors[i]`` voxels for the bands ``band_sets[i]``; the tallied light per exact order (index = order) of the
    cells in the camera's frame, per group of the source's channels."""

    numerators: list
    factors: tuple
    band_sets: tuple
    histogram: np.ndarray     # (groups, max_order + 1): per channel group of the source (its ``groups``)
    photons: int
    collisions: int
    truncated: float          # power of the photons still alive at max_order, relative to all tallied light


def _cache_index(p, lo, ext, res, factor: int, dims):
    nx, ny, nz = res
    cx, cy, cz = dims
    q = (p - lo) / ext
    ix = mi.UInt32(dr.clip(q.x * (nx / factor), 0, cx - 1))
    iy = mi.UInt32(dr.clip(q.y * (ny / factor), 0, cy - 1))
    iz = mi.UInt32(dr.clip(q.z * (nz / factor), 0, cz - 1))
    return (iz * cy + iy) * cx + ix


def _scatter_dir(w, g: float, rng):
    cos_t = hg_sample_cos_dr(rng.next_float32(), g)
    phi = 2.0 * math.pi * rng.next_float32()
    sin_t = dr.safe_sqrt(1.0 - cos_t * cos_t)
    return dr.normalize(mi.Frame3f(w).to_world(mi.Vector3f(sin_t * dr.cos(phi), sin_t * dr.sin(phi), cos_t)))


def _new_direction(lobe_on: bool, w, p, g, rng, share, cam, vis_p):
    """A new direction at a collision at p. With ``lobe_on``, from the mixture q = (1 - a) HG(w_in, g) +
    a HG(ω_cam(p), g), a = ``share`` · w_vis(p) (``vis_p`` the camera transmittance at p), with the weight factor
    HG(w_in · w_new, g) / q that keeps every expected tally (angle biasing toward the camera: the light the
    camera sees leaves the collision in the phase function's forward peak around ω_cam; any a in [0, 1) is
    unbiased). Without, plain HG(g) sampling and the factor 1."""
    if not lobe_on:
        return _scatter_dir(w, g, rng), mi.Float(1.0)
    a = share * vis_p
    to_cam = dr.normalize(cam - p)
    axis = dr.select(rng.next_float32() < a, to_cam, w)
    w_new = _scatter_dir(axis, g, rng)
    p_hg = hg_dr(dr.dot(w, w_new), g)
    q = (1.0 - a) * p_hg + a * hg_dr(dr.dot(to_cam, w_new), g)
    return w_new, p_hg / dr.maximum(q, 1e-30)


def _visibility(vis, p, lo, ext):
    """The visibility weight w(p) (:func:`natscene.scatter.inscatter.visibility`); 1 without a camera depth.
    ``vis``: (:class:`natscene.scatter.inscatter.CameraDepth`, sig_k) or None."""
    if vis is None:
        return mi.Float(1.0)
    from natscene.scatter.inscatter import visibility
    return visibility(vis[0], p, (p - lo) / ext, vis[1])


#: the fields of a photon record (a photon about to fly: from the source, or a split copy at a collision)
_RECORD = ("p", "w", "mult", "k", "vis", "state", "inc")


@dataclass
class _Walk:
    """What every walk of a trace shares: the medium, the caches and the tally targets."""

    med: object
    grid: MajorantGrid
    sig_k: object
    g: object
    lobe_share: object
    lobe_on: bool
    floor: object
    vis: object
    cam: object
    lo: object
    ext: object
    res: tuple
    caches: list          # (factor, dims, cells, offset) per cache: its numerators begin at offset in accs
    slot_tabs: list       # per cache: the band slot of each order (-1: not tallied)
    accs: list            # per channel: UInt64 fixed-point numerators of every cache, one after the other
    hist: object          # UInt64 [groups x (max_order + 1)]: the order histogram of each channel group
    groups: tuple         # the histogram group of each channel
    trunc: object         # UInt64 [1]
    max_order: int
    k_min: int
    phase: bool
    window: object
    split_max: int
    similarity: object    # None, or (first order, 1 - g, log g): high-order similarity (:func:`_walk`)
    p1: object = None     # None, or (first order, the numerators' size): P1 tallies (:func:`_walk`)
    jumps: object = None  # None, or (radius per majorant cell, collisions, exit cosines, 1 - g, g, any order):
                          # diffusion jumps (:func:`_jump`)
    seen: object = None   # None, or Float per voxel: 1 where the camera's frame sees it (the order histogram's)


@dr.syntax
def _jump(s: _Walk, p, w, k, vis_p, live, rng):
    """Diffusion jumps (:mod:`.jumps`) of the ``live`` photons at p whose majorant cell allows a ball of at least the
    smallest radius of :data:`natscene.scatter.jumps.BALL_RADII` (similar mean free paths, sigma_t (1 - g)): the
    largest ball of the ladder that fits; the photon moves to a uniform point of its sphere, flies on in a
    direction at one precomputed walk's exit cosine to the outward normal, and its order grows by that walk's
    collisions N, each a geometric number of real ones (K = N + NegBin(N, 1 - g), its normal approximation).
    The ``live`` lanes are those whose photon scatters isotropically at its next collision: where g is not
    (:data:`ISOTROPIC_G`), only photons in the similar medium (``similarity_order``). A photon of the exact walk at
    g 0.85 would lose the drift along its direction that its next forward scatterings carry (g / (1 - g) mean free
    paths): the transmittance of a slab of optical depth 100 read 0.88 of adding-doubling with jumps from any
    collision, 0.98 without.
    Returns p, w, k, vis_p, the jumped lanes and those whose order passed ``max_order`` (dropped). Only the jumping
    lanes draw random numbers: a walk that never jumps is the walk without jumps, number for number."""
    from natscene.scatter.jumps import BALL_RADII, BALL_SAMPLES
    radius, n_tab, mu_tab, one_minus_g, g, _ = s.jumps
    cx, cy, cz = s.grid.shape
    c = (p - s.lo) / mi.ScalarVector3f(*[float(v) for v in s.grid.cell])
    cell = (mi.UInt32(dr.clip(dr.floor(c.z), 0, cz - 1)) * cy + mi.UInt32(dr.clip(dr.floor(c.y), 0, cy - 1))) * cx \
        + mi.UInt32(dr.clip(dr.floor(c.x), 0, cx - 1))
    r_world = dr.gather(mi.Float, radius, cell, live)
    r0 = float(BALL_RADII[0])
    step = math.log(float(BALL_RADII[1] / BALL_RADII[0]))
    sig_k, rho, most = s.sig_k, s.med.rho, float(s.max_order)   # (the branch reads no member of s)
    ok = mi.Bool(False)
    if dr.hint(live & (r_world > 0), mode="symbolic"):     # a branch: a packet without a ball skips it
        sig = sig_k * rho(p) * one_minus_g
        avail = sig * r_world
        ok = avail >= r0
        i = mi.UInt32(dr.clip(dr.floor(dr.log(dr.maximum(avail, r0) / r0) / step), 0, len(BALL_RADII) - 1))
        r_ball = r0 * dr.exp(mi.Float(i) * step) / dr.maximum(sig, 1e-30)
        j = i * BALL_SAMPLES + mi.UInt32(dr.minimum(rng.next_float32(ok) * BALL_SAMPLES, BALL_SAMPLES - 1))
        n = mi.Float(dr.gather(mi.UInt32, n_tab, j, ok))
        mu = dr.gather(mi.Float, mu_tab, j, ok)
        nz_ = 1.0 - 2.0 * rng.next_float32(ok)
        phi = 2.0 * math.pi * rng.next_float32(ok)
        sz = dr.safe_sqrt(1.0 - nz_ * nz_)
        normal = mi.Vector3f(sz * dr.cos(phi), sz * dr.sin(phi), nz_)
        phi_w = 2.0 * math.pi * rng.next_float32(ok)
        s_mu = dr.safe_sqrt(1.0 - mu * mu)
        w_out = dr.normalize(mi.Frame3f(normal).to_world(mi.Vector3f(s_mu * dr.cos(phi_w), s_mu * dr.sin(phi_w), mu)))
        u1, u2 = rng.next_float32(ok), rng.next_float32(ok)
        z = dr.safe_sqrt(-2.0 * dr.log(1.0 - u1)) * dr.cos(2.0 * math.pi * u2)
        real = dr.maximum(dr.round((n + z * dr.safe_sqrt(n * g)) / one_minus_g), n)
        k = dr.select(ok, k + mi.UInt32(dr.minimum(real, most)), k)
        p = dr.select(ok, p + normal * r_ball, p)
        w = dr.select(ok, w_out, w)
        vis_p = dr.select(ok, 0.0, vis_p)
    return p, w, k, vis_p, ok, ok & (k >= s.max_order)


@dr.syntax
def _walk(s: _Walk, rec_p, rec_w, rec_wts, rec_mult, rec_k, rec_vis, rec_state, rec_inc, n_rec, lanes: int,
          cap: int, spawn: dict):
    """Walk the photons of a record list to the end, ``lanes`` at a time, in one symbolic loop of events.

    Every iteration each lane does one event of delta tracking (:func:`natscene.scatter.majorant.flight_event`)
    and tallies it; a lane whose photon collides scatters it (and may split it) and flies on in the next
    iteration, and a lane whose photon dies takes the next record (lane i walks records i, i + lanes, ...).
    A loop over whole flights or whole walks idles most of a SIMD packet's lanes while the longest of them
    finishes; this one keeps them busy.

    At a tentative collision x of the flight toward the photon's k-th collision the tally adds
    Φ (mu_t(x) / mu_bar(x)) p(ω · ω_cam(x), g) w_vis(x) to the cache cell of x, band of order k. At a real
    collision of order k >= k_min the order histogram adds Φ p(ω · ω_cam, g) w_vis (collision estimator). With a
    weight window a photon of multiplier m in a cell of target T survives with probability m / T at weight T
    when m < T / 2, and splits into n = min(floor(m / T), ``split_max``) copies of weight m / n when m > 2T; the
    lane walks the first copy on and writes one record for the other n - 1 into its ``cap`` slots of ``spawn``
    (a lane whose slots are full does not split: splitting is optional, every choice keeps the expected tallies).
    Returns the lanes' spawn counts and real collisions.

    High orders by similarity (``s.similarity``, Zhao, Ramamoorthi & Bala 2014, first order; Wyman et al. 1989):
    a flight that starts at order k >= ``similarity_order`` runs in the similar medium sigma_t* = sigma_t (1 - g),
    g* = 0, which has the same transport mean free path (the same diffusion); each of its collisions stands for
    K ~ Geometric(1 - g) real ones (k += K: E[beta^K] = beta (1 - g) / (1 - beta g) is the similar albedo, so the
    closed-form albedo of the bands holds), and its tallies count the real mu_t = mu_t* / (1 - g) with the real
    phase function toward the camera along the flight's direction (the similar field keeps the fluence and the
    flux). A walk of n real collisions then costs about n (1 - g) events.

    P1 tallies (``s.p1``, from order ``p1_order`` on): the tallied phase function toward the camera is HG's
    first two Legendre terms, (1 + 3 g ω · ω_cam) / 4π, instead of HG itself. Where the light has diffused (high
    orders) its radiance is nearly linear in direction, the terms of HG past the first do not see it, and the
    tally's range shrinks from HG's forward peak (98 / 4π at g 0.9) to 1 + 3g; a negative tally (ω away from the
    camera, g > 1/3) goes to a second half of the numerators, subtracted at the end."""
    nch = len(rec_wts)
    lane = dr.arange(mi.UInt32, lanes)
    rec = mi.UInt32(lane)
    # the lane count and the slots enter the kernel as opaque values: every pass reuses one compiled kernel
    lanes, cap = dr.opaque(mi.UInt32, lanes), dr.opaque(mi.UInt32, cap)
    p = dr.gather(mi.Point3f, rec_p, rec)
    w = dr.gather(mi.Vector3f, rec_w, rec)
    wts = [dr.gather(mi.Float, x, rec) for x in rec_wts]
    mult = dr.gather(mi.Float, rec_mult, rec)
    k = dr.gather(mi.UInt32, rec_k, rec)
    vis_p = dr.gather(mi.Float, rec_vis, rec)
    rng = mi.PCG32()
    rng.state = dr.gather(mi.UInt64, rec_state, rec)
    rng.inc = dr.gather(mi.UInt64, rec_inc, rec)
    active = rec < n_rec
    start = mi.Bool(active)                 # the lane's photon begins a flight in this iteration
    flying = mi.Bool(False)
    t = mi.Float(0.0)
    t1 = mi.Float(0.0)
    tau = mi.Float(0.0)
    ix = mi.Int32(0)
    iy = mi.Int32(0)
    iz = mi.Int32(0)
    tmx = mi.Float(0.0)
    tmy = mi.Float(0.0)
    tmz = mi.Float(0.0)
    spawned = mi.UInt32(0)
    collided = mi.UInt32(0)
    red = mi.Bool(False)                    # the flight is in the similar medium (sigma_t (1 - g), g = 0)
    jumped = mi.Bool(False)                 # the photon has just jumped across a ball (:mod:`.jumps`)
    while dr.hint(active, include=[rng]):
        # a new flight: after a collision (k > 0) the photon scatters first
        turn = start & (k > 0) & ~jumped        # a jump's photon leaves its ball mid-flight
        g_l, sig_l, boost = s.g, s.sig_k, mi.Float(1.0)
        if s.similarity is not None:
            first, one_minus_g, _ = s.similarity
            red = dr.select(start, k >= first, red)
            g_l = dr.select(red, 0.0, s.g)
            sig_l = dr.select(red, s.sig_k * one_minus_g, s.sig_k)
            boost = dr.select(red, 1.0 / one_minus_g, 1.0)
        w_new, f = _new_direction(s.lobe_on, w, p, g_l, rng, s.lobe_share, s.cam, vis_p)
        w = dr.select(turn, w_new, w)
        f = dr.select(turn, f, 1.0)
        wts = [x * f for x in wts]
        mult = mult * f
        t_in, t_out = ray_box_dr(p, w, s.med.bbox_min, s.med.bbox_max)
        t = dr.select(start, t_in, t)
        t1 = dr.select(start, t_out, t1)
        tau = dr.select(start, -dr.log(1.0 - rng.next_float32()), tau)
        missed = start & (t_out <= t_in)
        flying = dr.select(start, t_out > t_in, flying)
        # one event of delta tracking, tallied at a tentative collision (order k + 1)
        kk = dr.minimum(k + 1, s.max_order)
        rate = dr.select(k + 1 >= s.k_min, s.floor, 0.0)
        t, tau, cells, x, ratio, inside, accept, escaped = flight_event(
            s.med, s.grid, p, w, sig_l, rng, flying, start & flying, t, t1, tau, (ix, iy, iz, tmx, tmy, tmz), rate)
        ix, iy, iz, tmx, tmy, tmz = cells
        vis_x = _visibility(s.vis, x, s.lo, s.ext)
        cos_cam = dr.dot(w, dr.normalize(s.cam - x))
        light = vis_x * hg_dr(cos_cam, s.g)
        if s.similarity is not None:  # a similar flight: the real mu_t is boost x the similar one
            light = light * boost
        val = ratio * (light if s.phase else vis_x * boost)
        if s.p1 is not None:      # the diffuse orders: the phase function's P1 part, (1 + 3 g cos) / 4 pi
            p1 = vis_x * hg_p1_dr(cos_cam, s.g)
            if s.similarity is not None:
                p1 = p1 * boost
            val = dr.select(kk >= s.p1[0], ratio * p1, val)
        # the order's band lives in one cache: one scatter per channel (an atomic add per lane) at that cache's cell
        idx = mi.UInt32(0)
        tallied = mi.Bool(False)
        for ci, (factor, dims, ncell, offset) in enumerate(s.caches):
            slot = dr.gather(mi.Int32, s.slot_tabs[ci], kk)
            idx = dr.select(slot >= 0, offset + mi.UInt32(dr.maximum(slot, 0)) * ncell
                            + _cache_index(x, s.lo, s.ext, s.res, factor, dims), idx)
            tallied = tallied | (slot >= 0)
        if s.p1 is not None:  # a negative tally goes to the second half of the (doubled) numerators
            idx = dr.select(val < 0, idx + s.p1[1], idx)
        for c in range(nch):
            dr.scatter_reduce(dr.ReduceOp.Add, s.accs[c], _fixed(dr.abs(val * wts[c])), idx, inside & tallied)
        flying = flying & ~accept & ~escaped
        # a real collision: order k, the histogram, the end of the walk at max_order, the weight window
        p = dr.select(accept, x, p)
        vis_p = dr.select(accept, vis_x, vis_p)
        step = mi.UInt32(1)
        if s.similarity is not None:  # a similar collision stands for K real ones, P(K = n) = (1 - g) g^(n - 1)
            log_g = s.similarity[2]
            extra = dr.floor(dr.log(1.0 - rng.next_float32(accept & red)) / log_g)
            step = dr.select(red, mi.UInt32(dr.minimum(extra, float(s.max_order))) + 1, 1)
        k = dr.select(accept, k + step, k)
        collided += dr.select(accept, 1, 0)
        power = mi.Float(0.0)
        for c in range(nch):
            power += wts[c]
        seen = light
        if s.seen is not None:      # the histogram counts the light of the voxels in the camera's frame only
            seen = light * dr.gather(mi.Float, s.seen, _cache_index(p, s.lo, s.ext, s.res, 1, s.res), accept)
        for gi in range(max(s.groups) + 1):
            part = mi.Float(0.0)
            for c in range(nch):
                if s.groups[c] == gi:
                    part += wts[c]
            dr.scatter_reduce(dr.ReduceOp.Add, s.hist, _fixed(seen * part),
                              gi * (s.max_order + 1) + dr.minimum(k, s.max_order), accept & (k >= s.k_min))
        ends = accept & (k >= s.max_order)
        dr.scatter_reduce(dr.ReduceOp.Add, s.trunc, _fixed(power), 0, ends)
        goes_on = accept & ~ends
        if s.window is not None:
            factor, dims, targets = s.window
            target = dr.gather(mi.Float, targets, _cache_index(p, s.lo, s.ext, s.res, factor, dims), goes_on)
            r = mult / dr.maximum(target, 1e-30)
            low = goes_on & (r < 0.5)
            keep = goes_on & (~low | (rng.next_float32() < r))
            n = dr.select(keep & (r > 2.0) & (spawned < cap), dr.minimum(dr.floor(r), float(s.split_max)), 1.0)
            f = dr.select(low, target / dr.maximum(mult, 1e-30), 1.0) / n
            mult = dr.select(keep, mult * f, mult)
            wts = [dr.select(keep, x * f, x) for x in wts]
            split = keep & (n > 1.0)
            at = lane * cap + spawned
            for name, value in (("p", p), ("w", w), ("mult", mult), ("k", k), ("vis", vis_p),
                                ("state", rng.state), ("copies", mi.UInt32(n) - 1)):
                dr.scatter(spawn[name], value, at, split)
            for c in range(nch):
                dr.scatter(spawn["wts"][c], wts[c], at, split)
            spawned += dr.select(split, 1, 0)
            goes_on = keep
        jumped = mi.Bool(False)
        if s.jumps is not None:
            p, w, k, vis_p, jumped, over = _jump(s, p, w, k, vis_p, goes_on & (red | s.jumps[5]), rng)
            left = mi.Float(0.0)
            for c in range(nch):
                left += wts[c]
            dr.scatter_reduce(dr.ReduceOp.Add, s.trunc, _fixed(left), 0, over)
            goes_on = goes_on & ~over
        dead = missed | escaped | (accept & ~goes_on)
        # a lane whose photon died takes its next record
        rec = dr.select(dead, rec + lanes, rec)
        load = dead & (rec < n_rec)
        p = dr.select(load, dr.gather(mi.Point3f, rec_p, rec, load), p)
        w = dr.select(load, dr.gather(mi.Vector3f, rec_w, rec, load), w)
        wts = [dr.select(load, dr.gather(mi.Float, rec_wts[c], rec, load), wts[c]) for c in range(nch)]
        mult = dr.select(load, dr.gather(mi.Float, rec_mult, rec, load), mult)
        k = dr.select(load, dr.gather(mi.UInt32, rec_k, rec, load), k)
        vis_p = dr.select(load, dr.gather(mi.Float, rec_vis, rec, load), vis_p)
        rng.state = dr.select(load, dr.gather(mi.UInt64, rec_state, rec, load), rng.state)
        rng.inc = dr.select(load, dr.gather(mi.UInt64, rec_inc, rec, load), rng.inc)
        start = goes_on | load
        active = flying | start
    return spawned, collided


#: lanes of one walk on the CPU (fewer lanes walk more photons each, so the SIMD packets stay full until late in
#: the pass: on the main job's cumulus 2^12 lanes walked a node's photons 1.3-1.5 times faster than 2^14 or 2^15);
#: a GPU needs many more threads in flight
WALK_LANES_CPU = 1 << 12
WALK_LANES_GPU = 1 << 20
#: split records per lane: a few per photon the lane walks (the main job's nodes write about 0.3), and a lane whose
#: slots are full stops splitting
SPAWN_PER_PHOTON = 2
SPAWN_MIN = 16


def _walk_lanes() -> int:
    return WALK_LANES_GPU if mi.variant().startswith("cuda") else WALK_LANES_CPU


def _copies(spawn: dict, spawned, lanes: int, cap: int, seed: int, stream: int):
    """The records of the split copies of one walk (each spawn record stands for its ``copies`` copies, in the
    order of the lanes and their slots), each copy with a PCG32 stream of its own (``stream`` numbers them
    across the trace). Returns (records, count, next stream)."""
    counts = np.asarray(spawned).astype(np.int64)
    sel = np.flatnonzero((np.arange(cap)[None, :] < counts[:, None]).ravel()).astype(np.uint32)
    if sel.size == 0:
        return None, 0, stream
    reps = np.asarray(spawn["copies"])[sel].astype(np.int64)
    total = int(reps.sum())
    idx = mi.UInt32(np.repeat(sel, reps))
    recs = {name: dr.gather(type(spawn[name]), spawn[name], idx) for name in ("p", "w", "mult", "k", "vis")}
    recs["wts"] = [dr.gather(mi.Float, x, idx) for x in spawn["wts"]]
    fresh = mi.PCG32(size=total, initstate=dr.gather(mi.UInt64, spawn["state"], idx),
                     initseq=mi.UInt64(np.arange(stream, stream + total, dtype=np.uint64))
                     + mi.UInt64(int(seed) * 104729 + 2 ** 40))
    recs["state"], recs["inc"] = fresh.state, fresh.inc
    return recs, total, stream + total


#: below this asymmetry a collision scatters nearly isotropically: every photon may jump, and there is no similar
#: medium (``similarity_order`` needs g above it)
ISOTROPIC_G = 0.05


def _jump_tables(med, grid: MajorantGrid, depth, sig_k: float, g: float):
    """The diffusion jumps' arrays (:attr:`_Walk.jumps`) for the camera depth ``depth``
    (:class:`natscene.scatter.inscatter.CameraDepth`) at extinction ``sig_k`` per unit density: the jump radius per
    cell of ``grid`` (the homogeneous balls are found once per medium:
    :meth:`natscene.scatter.medium.Medium.homogeneous`), the precomputed walks' collisions and exit cosines; None
    where no cell allows a jump (the walk then carries no jump code)."""
    from natscene.scatter.inscatter import VISIBLE_DEPTH
    from natscene.scatter.jumps import ball_exits, cell_reduce, jump_radii
    low = cell_reduce(depth.lower(), grid.block, np.min, -np.inf)
    radius = jump_radii(*med.homogeneous(grid.block), low, sig_k, VISIBLE_DEPTH)
    if not np.any(radius > 0):
        return None
    n, mu = ball_exits()
    g = max(float(g), 0.0)
    return (mi.Float(radius.ravel()), mi.UInt32(n.ravel()), mi.Float(mu.ravel()), dr.opaque(mi.Float, 1.0 - g),
            dr.opaque(mi.Float, g), g <= ISOTROPIC_G)


def trace(med, grid: MajorantGrid, source, sigma: float, g: float, camera_position, n_photons: int, bands,
          caches=((2, None),), seed: int = 0, max_order: int = 4096, k_min: int = 2, batch: int = 2 ** 18,
          progress=None, camera_depth=None, tally_rate: float = 0.0, phase: bool = True,
          window=None, split_max: int = 8, camera_lobe: float = 0.0, similarity_order: int = 0,
          p1_order: int = 0, jumps: bool = False, seen=None) -> InscatterTally:
    """Trace ``n_photons`` from ``source`` through the medium at (sigma, g) and tally the in-scatter caches.

    ``caches``: (factor, band indices or None = all bands) per cache; every band goes to exactly one cache.
    ``camera_depth``: the voxel-centred optical depth to the camera [nz, ny, nx]
    (:func:`natscene.scatter.inscatter.voxel_camera_depth`): each tally is weighted by the camera transmittance
    w(x) = exp(-sigma_t k D̃(x)) (:func:`natscene.scatter.inscatter.visibility`); None: 1 everywhere.
    ``tally_rate``: tentative collisions (tally samples) per voxel length at least, in every non-empty majorant
    cell (:func:`natscene.scatter.majorant.flight_event`'s ``rate_floor``).
    ``phase``: False tallies μ_t/μ̄ · w · Φ without the phase function (the scalar flux, for the weight window's
    pilot run, :func:`natscene.scatter.allorders.weight_window`).
    ``window``: (factor, (cx, cy, cz), targets Float) or None: splitting and Russian roulette at every collision
    against this weight window (:func:`_walk`, :mod:`natscene.scatter.importance`).
    ``similarity_order`` > 0 (and g > 0.05): from that order on the photon flies in the similar medium of
    high-order similarity (:func:`_walk`).
    ``p1_order`` > 0: from that order on the tallies take the phase function's P1 part (:func:`_walk`).
    ``jumps``: a photon deep inside the cloud, where the camera sees nothing (needs ``camera_depth``) and the
    density is nearly constant, crosses a ball of it in one step (:mod:`.jumps`, :func:`_jump`).
    ``seen``: bool [nz, ny, nx], the voxels in the camera's frame (:func:`natscene.geometry.frame_voxels`): the
    order histogram takes the collisions there only (None: everywhere).

    The source's photons are walked by :func:`_walk` in one pass per ``batch`` photons; the copies that pass
    splits off are walked in the next, and so on until no copy is left (2^18 photons a batch keep a main-job node
    at 0.8 GB; 2^20 took 1.07 GB and no less time).
    """
    density = med.volume.density
    nz, ny, nx = density.shape
    res = (nx, ny, nz)
    nb = len(bands)
    vis = None
    if camera_depth is not None:
        from natscene.scatter.inscatter import CameraDepth
        vis = (CameraDepth(med, camera_depth, camera_position), dr.opaque(mi.Float, float(sigma) * med.scale))
    band_sets, geo, slot_np = [], [], []
    owner = -np.ones(nb, np.int64)
    for ci, (factor, sel) in enumerate(caches):
        sel = list(range(nb)) if sel is None else [int(i) for i in sel]
        if np.any(owner[sel] >= 0):
            raise ValueError(f"a band is assigned to two caches: {caches}")
        owner[sel] = ci
        dims = (-(-nx // factor), -(-ny // factor), -(-nz // factor))
        geo.append((int(factor), dims, dims[0] * dims[1] * dims[2]))
        band_sets.append(tuple(sel))
    if np.any(owner < 0):
        raise ValueError(f"bands {np.flatnonzero(owner < 0).tolist()} belong to no cache")
    tab = band_table(bands, max_order)
    for ci, sel in enumerate(band_sets):
        local = -np.ones(nb, np.int64)
        local[list(sel)] = np.arange(len(sel))
        slot = local[tab].astype(np.int32)
        slot[:k_min] = -1
        slot_np.append(slot)
    nch = source.channels
    n_hist = max(source.groups) + 1        # order histograms: one per group of the source's channels
    sizes = [max(1, geo[ci][2] * len(band_sets[ci])) for ci in range(len(caches))]
    offsets = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
    total = int(offsets[-1])
    if (2 if p1_order > 0 and phase else 1) * total >= 2 ** 32:     # P1 doubles the numerators
        raise ValueError(f"the caches' {total} numerators do not fit 32-bit indices: use larger cache cells "
                         "(precompute.all_orders.fine_voxels / coarse_voxels, shots.<name>.render.fine_voxels / "
                         "coarse_voxels)")
    # sigma_t, g, the tally rate and the lobe's share enter the kernel as opaque values (not literals), so that
    # every (sigma_t, g) node of a precompute reuses the same compiled kernel instead of compiling its own
    s = _Walk(med, grid, dr.opaque(mi.Float, float(sigma) * med.scale), dr.opaque(mi.Float, float(g)),
              dr.opaque(mi.Float, float(camera_lobe)), camera_lobe > 0 and vis is not None,
              dr.opaque(mi.Float, float(tally_rate) / float(med.voxel)), vis,
              mi.ScalarPoint3f(*[float(e) for e in camera_position]), _vec(med.bbox_min),
              _vec(med.bbox_max - med.bbox_min), res,
              [(f, dims, ncell, int(offsets[ci])) for ci, (f, dims, ncell) in enumerate(geo)],
              [mi.Int32(x) for x in slot_np], [dr.zeros(mi.UInt64, total) for _ in range(nch)],
              dr.zeros(mi.UInt64, n_hist * (max_order + 1)), tuple(source.groups),
              dr.zeros(mi.UInt64, 1), int(max_order), int(k_min), bool(phase), window, int(split_max), None)
    if p1_order > 0 and phase:
        s.p1 = (dr.opaque(mi.UInt32, int(p1_order)), total)
        s.accs = [dr.zeros(mi.UInt64, 2 * total) for _ in range(nch)]
    if similarity_order > 0 and g > ISOTROPIC_G:
        s.similarity = (dr.opaque(mi.UInt32, int(similarity_order)), dr.opaque(mi.Float, 1.0 - float(g)),
                        dr.opaque(mi.Float, math.log(float(g))))
    if jumps and vis is not None and (g <= ISOTROPIC_G or s.similarity is not None):
        s.jumps = _jump_tables(med, grid, vis[0], float(sigma) * med.scale, g)
    if seen is not None:
        s.seen = mi.Float(np.ascontiguousarray(seen, np.float32).ravel())
    unit = None     # photon power that one fixed-point unit of FIXED stands for (the first batch's mean)
    collisions = 0
    done = 0
    stream = 0          # PCG32 streams handed to split copies so far
    while done < n_photons:
        n = min(batch, n_photons - done)
        rng = mi.PCG32(size=n, initstate=dr.arange(mi.UInt64, n) + mi.UInt64(done),
                       initseq=mi.UInt64(int(seed) * 7919 + 1))
        p, w, wts = source.sample(n, rng)
        wts = [x * (n / n_photons) for x in wts]     # powers of this batch as a share of the whole run
        if unit is None:
            unit = max(float(dr.max(sum(wts))[0]), 1e-300)
        recs = dict(p=mi.Point3f(p), w=mi.Vector3f(w), wts=[x / unit for x in wts], mult=dr.full(mi.Float, 1.0, n),
                    k=dr.zeros(mi.UInt32, n), vis=dr.zeros(mi.Float, n), state=mi.UInt64(rng.state),
                    inc=mi.UInt64(rng.inc))
        count = n
        while count > 0:
            dr.eval(*[recs[x] for x in _RECORD], *recs["wts"])
            lanes = min(_walk_lanes(), count)
            cap = SPAWN_MIN + SPAWN_PER_PHOTON * -(-count // lanes) if window is not None else 1
            size = lanes * cap if window is not None else 1
            spawn = dict(p=dr.zeros(mi.Point3f, size), w=dr.zeros(mi.Vector3f, size), mult=dr.zeros(mi.Float, size),
                         k=dr.zeros(mi.UInt32, size), vis=dr.zeros(mi.Float, size),
                         state=dr.zeros(mi.UInt64, size), copies=dr.zeros(mi.UInt32, size),
                         wts=[dr.zeros(mi.Float, size) for _ in range(nch)])
            spawned, coll = _walk(s, recs["p"], recs["w"], recs["wts"], recs["mult"], recs["k"], recs["vis"],
                                  recs["state"], recs["inc"], dr.opaque(mi.UInt32, count), lanes, cap, spawn)
            dr.eval(spawned, coll, *s.accs, s.hist, s.trunc,
                    *[v for key, v in spawn.items() if key != "wts"], *spawn["wts"])
            collisions += int(np.asarray(coll).astype(np.int64).sum())
            if window is None:
                break
            recs, count, stream = _copies(spawn, spawned, lanes, cap, seed, stream)
        done += n
        if progress:
            progress(done, n_photons)
    scale = (unit or 0.0) / FIXED
    accs = [np.asarray(a, np.float64) for a in s.accs]
    if s.p1 is not None:          # the positive tallies less the negative ones
        accs = [a[:total] - a[total:] for a in accs]
    nums = [np.stack([(a[offsets[ci]:offsets[ci] + geo[ci][2] * len(band_sets[ci])] * scale)
                      .reshape(len(band_sets[ci]), geo[ci][1][2], geo[ci][1][1], geo[ci][1][0]) for a in accs])
            for ci in range(len(caches))]
    h = np.asarray(s.hist, np.float64).reshape(n_hist, max_order + 1) * scale
    tot_light = h.sum()
    trunc = float(np.asarray(s.trunc, np.float64)[0]) * scale
    return InscatterTally(nums, tuple(x[0] for x in geo), tuple(band_sets), h, int(done), int(collisions),
                          trunc / tot_light if tot_light > 0 else 0.0)
