"""
In-scatter cache
================

Defines the in-scatter cache of the all-orders transport, from photon tallies to the light each pixel sees
(Dobashi et al. 2012, Eq. 5 with the cache's in-scattered radiance in place of the sun term):

-   :func:`voxel_camera_depth`, :class:`CameraDepth`: the optical depth D_cam from every voxel to the camera and
    its interpolation D̃ between the voxels.
-   :func:`visibility`: the camera transmittance w(x) at world points.
-   :func:`weighted_voxel_integrals`: the exact ∫ rho w dV per voxel (Gauss-Legendre).
-   :func:`block_sum`: sums over cells of voxels.
-   :func:`cache_fields`: the cache's numerators and denominators.
-   :func:`gather`: the view march of the cache fields, E_b(q).

A tally C_b(cell) of :mod:`.photons` estimates ∫_cell w(x) sigma_t(x) S_b(x) dV, S_b the in-scattered radiance
toward the camera of the orders of band b and w(x) = exp(-sigma_t k D̃(x)) the camera transmittance
(:func:`visibility`; D̃ the trilinear interpolation of the voxels' optical depth to the camera, :class:`CameraDepth`;
in a volume whose density reaches its box's faces, that of the mean density along the ray to the camera, times the
point's own distance to the box's face). The ratio
estimator

    S_b(cell) = C_b(cell) / Q(cell),    Q(cell) = ∫_cell w sigma_t dV,

gives the mean of S_b over the cell weighted by w sigma_t, the weighting of a view ray's integrand (Eq. 5:
T_cam sigma_t S). Unweighted, a cell several mean free paths deep would average S over its whole depth while
the camera sees only its first mean free path; near the lit surface S changes over that distance, and the thick
clouds' high orders would come out too bright against Mitsuba (docs/stages/precompute.md). Any positive
weight gives a consistent weighted mean as long as the tallies and Q use the same one, so Q must be exact:
:func:`weighted_voxel_integrals` integrates the trilinear density times w per voxel by Gauss-Legendre nodes
inside each trilinear patch (in smaller pieces where a box-filling volume's exact depth falls steeply).

The view march (Eq. 5's integral with the cache's S_b in place of the sun term) interpolates the cells' S_b
trilinearly, each cell weighted by its confidence m = Q / (Q + eps Q_max) (eps = :data:`CONFIDENT_Q`):

    S_b(x) = Σ_i a_i(x) m_i S_b,i / Σ_i a_i(x) m_i,        a_i the trilinear weights,

so a cell of ordinary Q weighs in by its position alone, a cell of little Q (density only from its neighbours'
trilinear support, or far behind the visible skin: few tallies, a noisy ratio) by its Q, and a cell the camera
cannot see not at all. Weighting every cell by its Q (C_b and Q interpolated, then divided) leaned each point
toward its neighbour of more visible density, the shallower or the denser: a cloud's thin edges took the brighter
light of its inside and a slab's transmitted light read low (docs/stages/precompute.md, "The cache's interpolation").
Each segment is integrated exactly for a density constant over it, as :mod:`.single`:

    E_b(q) = Σ_segments T_prev (1 - exp(-sigma_t k rho_i h)) S_b(x_i),

and stops where the view transmittance falls below 1e-4. It passes over the empty cells of the volume's
majorant grid (:class:`natscene.scatter.majorant.MajorantGrid`) in whole steps: the same sample points.

References
----------
-   Dobashi, Y., Iwasaki, W., Ono, A., Yamamoto, T., Yue, Y., & Nishita, T. (2012). An inverse problem approach
    for automatically adjusting the parameters for rendering clouds using photographs. ACM Transactions on
    Graphics, 31(6).
"""
from __future__ import annotations

import numpy as np

import natscene.variant  # noqa: F401
import drjit as dr
import mitsuba as mi

from natscene.scatter.medium import ray_box_dr
from natscene.scatter.rays import camera_rays, pixel_means
from natscene.scatter.single import one_minus_exp

__all__ = ["voxel_camera_depth", "CameraDepth", "MOST_PIECES", "visibility",
           "weighted_voxel_integrals", "block_sum", "cache_fields", "gather", "VISIBLE_DEPTH", "CONFIDENT_Q",
           "interpolation_fields"]

#: the cells' confidence scale: a cell whose Q is below this fraction of the largest weighs in by its Q in the view
#: march's interpolation (:func:`gather`), above it by its position
CONFIDENT_Q = 1e-3

#: the camera optical depth past which the visibility weight w = exp(-depth) is below 1e-8: what lies deeper adds
#: nothing the camera sees
VISIBLE_DEPTH = 18.5


def voxel_camera_depth(med, camera_position, step_voxels: float = 1.0) -> np.ndarray:
    """D_cam at every voxel centre, float32 [nz, ny, nx]: ∫ rho ds (world units) from the voxel centre to the
    camera (or to the box face on the way), marched only within two voxels of density (where a photon can
    collide, with the trilinear lookup's support); elsewhere 0."""
    from scipy.ndimage import binary_dilation
    from natscene.scatter.medium import _march_depth
    d = np.asarray(med.volume.density)
    nz, ny, nx = d.shape
    live = binary_dilation(d > 0, iterations=2)
    iz, iy, ix = np.nonzero(live)
    vox = (med.bbox_max - med.bbox_min) / np.array([nx, ny, nz])
    out = np.zeros(d.shape, np.float32)
    if iz.size == 0:
        return out
    pts = med.bbox_min + (np.stack([ix, iy, iz], -1) + 0.5) * vox
    o = mi.Point3f(*[pts[:, i].astype(np.float32) for i in range(3)])
    cam = mi.ScalarPoint3f(*[float(e) for e in camera_position])
    to_cam = cam - o
    dist = dr.norm(to_cam)
    dvec = to_cam / dr.maximum(dist, 1e-30)
    _, t1 = ray_box_dr(o, dvec, med.bbox_min, med.bbox_max)
    depth = _march_depth(med, o, dvec, dr.minimum(dr.maximum(t1, 0.0), dist), med.voxel * step_voxels)
    out[iz, iy, ix] = np.asarray(depth, np.float32)
    return out


def camera_reach(med, camera_position, p):
    """Distance from world points ``p`` toward the camera to the box's face or to the camera, the nearer."""
    to_cam = mi.ScalarPoint3f(*[float(e) for e in camera_position]) - p
    dist = dr.norm(to_cam)
    _, t1 = ray_box_dr(p, to_cam / dr.maximum(dist, 1e-30), med.bbox_min, med.bbox_max)
    return dr.minimum(dr.maximum(t1, 0.0), dist)


#: the most pieces per half voxel and axis of the denominator's quadrature (:func:`weighted_voxel_integrals`)
MOST_PIECES = 64


class CameraDepth:
    """D̃(x), the lookup of the visibility weight's camera depth at world points.

    The voxel-centred D_cam (:func:`voxel_camera_depth`) interpolated trilinearly, except in a volume whose density
    reaches its box's faces (``med.face_dense``): there the trilinear D_cam is held over the half voxel at a face,
    where it overestimates the depth, and the cells' weighted mean leaned to their deeper part (a slab filling its
    box read 3-4 % bright at 100 and 300 optical depths; seen from 85 degrees, its orders >= 2 14 % bright, from 89
    degrees the top voxels' weight e^-21 where the face's own is 1; docs/stages/precompute.md). Such a volume takes
    the exact depth: the mean density along each voxel's ray, D_cam / t (t: :func:`camera_reach`), interpolated,
    times x's own t (exact in a box of constant density), and holds its change across each voxel along each axis
    (:attr:`across`: the larger of the centres' central difference and the mean density times the change of t
    between the voxel's faces, which a face seen at a grazing angle makes 1 / cos(zenith) voxels), by which
    :func:`weighted_voxel_integrals` divides its quadrature.
    """

    def __init__(self, med, depth_vox: np.ndarray, camera_position):
        self.med = med
        self.camera_position = tuple(float(e) for e in camera_position)
        self.per_length = bool(getattr(med, "face_dense", False))
        depth = np.asarray(depth_vox, np.float32)
        self.values = depth
        self.tex = _texture(depth)
        self.mean_tex = self.across = None
        if self.per_length:
            nz, ny, nx = depth.shape
            vox = (med.bbox_max - med.bbox_min) / np.array([nx, ny, nz])
            zz, yy, xx = np.meshgrid(*[(np.arange(n) + 0.5) for n in (nz, ny, nx)], indexing="ij")
            pts = med.bbox_min + np.stack([xx.ravel(), yy.ravel(), zz.ravel()], -1) * vox

            def reach_at(q):
                return np.asarray(camera_reach(med, self.camera_position,
                                               mi.Point3f(*[q[:, i].astype(np.float32) for i in range(3)])),
                                  np.float64).reshape(depth.shape)

            mean = depth / np.maximum(reach_at(pts), 1e-6 * med.voxel)
            self.mean_tex = _texture(mean)
            half = np.diag(vox / 2)
            self.across = np.stack([np.maximum(
                np.abs(np.gradient(depth.astype(np.float64), axis=2 - a)) if depth.shape[2 - a] > 1 else 0.0,
                mean * np.abs(reach_at(pts + half[a]) - reach_at(pts - half[a]))) for a in range(3)])

    def __call__(self, p, uvw):
        """D̃ at world points ``p`` (their texture coordinates ``uvw``)."""
        if not self.per_length:
            return self.tex.eval(uvw)[0]
        return self.mean_tex.eval(uvw)[0] * camera_reach(self.med, self.camera_position, p)

    def trilinear(self, uvw):
        """The voxel-centred D_cam interpolated trilinearly at texture coordinates ``uvw``."""
        return self.tex.eval(uvw)[0]

    def lower(self) -> np.ndarray:
        """A lower bound of D̃ in each voxel (float64 [nz, ny, nx]): the voxel-centred depth less 2 voxels of the
        largest density next to the voxel and, in a volume that fills its box, less half its change across it."""
        from scipy.ndimage import maximum_filter
        d = np.asarray(self.med.volume.density, np.float32)
        out = np.asarray(self.values, np.float64) - maximum_filter(d, size=3) * 2.0 * self.med.voxel
        if self.per_length:
            out = np.minimum(out, np.asarray(self.values, np.float64) - self.across.sum(0) / 2)
        return out

    def pieces(self, sig_k: float) -> np.ndarray:
        """(3, nz, ny, nx) int: the quadrature's pieces per half voxel along x, y and z, so that the weight changes
        by at most e^-1 across a piece (1 outside a volume that fills its box; at most :data:`MOST_PIECES`)."""
        if not self.per_length:
            return np.ones((3,) + self.values.shape, np.int64)
        return np.clip(np.ceil(sig_k * self.across / 2.0), 1, MOST_PIECES).astype(np.int64)


def _texture(values: np.ndarray):
    """A trilinear ``mi.Texture3f`` of voxel-centred values [nz, ny, nx]."""
    return mi.Texture3f(mi.TensorXf(np.ascontiguousarray(np.asarray(values, np.float32)[..., None])))


def visibility(depth: CameraDepth, p, uvw, sig_k):
    """w(x) = exp(-sig_k D̃(x)): the camera transmittance at world points ``p`` (texture coordinates ``uvw``), D̃
    the interpolated D_cam (:class:`CameraDepth`). The weight of every tally (:mod:`.photons`) and of the
    cache's denominator (:func:`weighted_voxel_integrals`)."""
    return dr.exp(-sig_k * depth(p, uvw))


#: Gauss-Legendre nodes (2 per half voxel, in voxel units from the voxel's low corner): each half voxel lies
#: inside one patch of the cell-centred trilinear textures, where the integrand is smooth
_GL = np.array([0.25 - 0.25 / np.sqrt(3.0), 0.25 + 0.25 / np.sqrt(3.0), 0.75 - 0.25 / np.sqrt(3.0),
                0.75 + 0.25 / np.sqrt(3.0)])


def _axis_nodes(m: int) -> np.ndarray:
    """2 Gauss-Legendre nodes in each of m equal pieces of both half voxels, in voxel units (m = 1: :data:`_GL`)."""
    c = np.arange(2 * m) / (2 * m) + 1 / (4 * m)
    off = 1 / (4 * m) / np.sqrt(3.0)
    return np.sort(np.concatenate([c - off, c + off]))


def weighted_voxel_integrals(med, depth_vox: np.ndarray, camera_position, sig_k: float,
                             chunk: int = 1 << 23) -> np.ndarray:
    """∫_v rho(x) w(x) dV / voxel volume for every voxel v, float64 [nz, ny, nx], w the visibility
    (:func:`visibility`).

    4 x 4 x 4 Gauss-Legendre nodes per voxel (2 per half voxel and axis, :data:`_GL`): exact for the trilinear
    density alone, and within 0.2 % for a transmittance that falls by e^-3 across a voxel. In a volume that fills
    its box each half voxel is split along each axis into :meth:`CameraDepth.pieces` of 2 nodes, where the exact
    depth falls steeply (a face seen at a grazing angle: e^-45 across the top voxels of a slab of 10 optical depths
    in 16 layers, seen from 89 degrees). ``chunk``: quadrature nodes at a time. Voxels the camera cannot see
    (w < 1e-8 everywhere in them: :meth:`CameraDepth.lower`) and voxels without density near them are left 0
    (their tallies are weighted below 1e-8 too)."""
    from scipy.ndimage import binary_dilation
    d = np.asarray(med.volume.density, np.float32)
    nz, ny, nx = d.shape
    out = np.zeros(d.shape, np.float64)
    depth = CameraDepth(med, depth_vox, camera_position)
    live = binary_dilation(d > 0, iterations=1) & (sig_k * depth.lower() < VISIBLE_DEPTH)
    if not live.any():
        return out
    pieces = depth.pieces(sig_k)
    key = pieces[0] + (MOST_PIECES + 1) * (pieces[1] + (MOST_PIECES + 1) * pieces[2])
    lo, ext = mi.ScalarPoint3f(*med.bbox_min), mi.ScalarVector3f(*(med.bbox_max - med.bbox_min))
    for kval in np.unique(key[live]):
        iz, iy, ix = np.nonzero(live & (key == kval))
        nodes = [_axis_nodes(int(pieces[a][iz[0], iy[0], ix[0]])) for a in range(3)]
        mx, my, mz = (nd.size for nd in nodes)
        per = mx * my * mz
        gx, gy, gz = (mi.Float(nd.astype(np.float32)) for nd in nodes)
        step = max(1, chunk // per)
        for c0 in range(0, iz.size, step):
            sel = slice(c0, min(c0 + step, iz.size))
            k = dr.arange(mi.UInt32, iz[sel].size * per)
            v, o = k // per, k % per
            ox, oy = dr.gather(mi.Float, gx, o % mx), dr.gather(mi.Float, gy, (o // mx) % my)
            oz = dr.gather(mi.Float, gz, o // (mx * my))
            uvw = mi.Point3f((mi.Float(dr.gather(mi.UInt32, mi.UInt32(ix[sel].astype(np.uint32)), v)) + ox) / nx,
                             (mi.Float(dr.gather(mi.UInt32, mi.UInt32(iy[sel].astype(np.uint32)), v)) + oy) / ny,
                             (mi.Float(dr.gather(mi.UInt32, mi.UInt32(iz[sel].astype(np.uint32)), v)) + oz) / nz)
            f = dr.maximum(med.density_tex.eval(uvw)[0], 0.0) * visibility(depth, lo + uvw * ext, uvw, sig_k)
            out[iz[sel], iy[sel], ix[sel]] = np.asarray(dr.block_sum(f, per), np.float64) / per
    return out


def block_sum(values: np.ndarray, factor: int) -> np.ndarray:
    """Sums of ``values`` (..., nz, ny, nx) over cells of ``factor``^3 voxels (the last cells padded)."""
    v = np.asarray(values, np.float64)
    nz, ny, nx = v.shape[-3:]
    cz, cy, cx = -(-nz // factor), -(-ny // factor), -(-nx // factor)
    pad = [(0, 0)] * (v.ndim - 3) + [(0, cz * factor - nz), (0, cy * factor - ny), (0, cx * factor - nx)]
    v = np.pad(v, pad)
    v = v.reshape(v.shape[:-3] + (cz, factor, cy, factor, cx, factor))
    return v.sum(axis=(-5, -3, -1))


def cache_fields(numerators: np.ndarray, weighted_integrals: np.ndarray, guide: np.ndarray | None = None,
                 guide_width: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """(numerators, denominators) float32 of the cache, both divided by the largest denominator.

    ``numerators`` (..., cz, cy, cx): the tallies C_b (:mod:`.photons`), each weighted by the visibility w;
    ``weighted_integrals`` (cz, cy, cx): ∫_cell w sigma_t dV (:func:`weighted_voxel_integrals`).
    The in-scattered radiance is their ratio, S = C / Q, which :func:`gather` interpolates between the cells by
    their confidence (:func:`interpolation_fields`).

    With ``guide`` (cz, cy, cx; the cells' optical depth toward the camera) and ``guide_width`` > 0, S is
    smoothed by a 3x3x3 cross-bilateral local-linear fit (:func:`_local_linear`): a [1, 2, 1] tent in space
    times exp(-(Δguide)² / (2 guide_width²)), so that it averages cells at the same optical depth from the
    camera (along the visible surface) but not across depth. The fit is local-linear, not a weighted mean: a
    weighted mean of S pulls the cells at the cloud's edge toward the denser interior, which brightened thin
    clouds by 5-20 % against Mitsuba; a local plane has no such first-order bias.
    """
    den = np.asarray(weighted_integrals, np.float64)
    # a cell the camera cannot see (Q = 0: :func:`weighted_voxel_integrals`) holds nothing: tallies that reached it
    # anyway are not light the camera sees
    num = np.where(den > 0, np.asarray(numerators, np.float64), 0.0)
    if guide is not None and guide_width > 0:
        num, den = _local_linear(num, den, np.asarray(guide, np.float64), float(guide_width))
    top = float(den.max()) if den.size else 0.0
    if top <= 0:
        return np.zeros(num.shape, np.float32), np.zeros(den.shape, np.float32)
    return (num / top).astype(np.float32), (den / top).astype(np.float32)


def interpolation_fields(caches: np.ndarray, denominators: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(m S, m[None]) float32: the fields whose trilinear interpolations' ratio is the view march's S
    (:func:`gather`): S = ``caches`` / ``denominators`` (0 where Q = 0) and each cell's confidence
    m = Q / (Q + :data:`CONFIDENT_Q` Q_max)."""
    den = np.asarray(denominators, np.float64)
    top = float(den.max()) if den.size else 0.0
    if top <= 0:
        return np.zeros(np.shape(caches), np.float32), np.zeros((1,) + den.shape, np.float32)
    seen = den > 0
    m = den / (den + CONFIDENT_Q * top)
    S = np.where(seen, np.asarray(caches, np.float64) / np.where(seen, den, 1.0), 0.0)
    return (m * S).astype(np.float32), m[None].astype(np.float32)


@dr.syntax
def _march(med, tex, nch: int, o, d, sig_k: float, step: float, lo, cache_ext, box_lo, box_hi, grid=None):
    t0, t1 = ray_box_dr(o, d, box_lo, box_hi)
    length = dr.maximum(t1 - t0, 0.0)
    n = dr.select(length > 0, dr.maximum(dr.ceil(length / step), 1.0), 0.0)
    h = dr.select(n > 0, length / dr.maximum(n, 1.0), 0.0)
    trans = mi.Float(1.0)
    acc = [dr.zeros(mi.Float, dr.width(o)) for _ in range(nch)]
    i = mi.Float(0.0)
    while (i < n) & (trans > 1e-4):
        p = o + d * (t0 + (i + 0.5) * h)
        r = med.rho(p)
        a = one_minus_exp(sig_k * r * h)
        if r > 0:
            s = tex.eval((p - lo) / cache_ext)
            q = trans * a / dr.maximum(s[nch], 1e-30)
            for j in range(nch):
                acc[j] += q * s[j]
        trans *= 1.0 - a
        if grid is not None:  # in an empty cell every step within its safe jump adds nothing
            i += grid.empty_steps(p, h)
        else:
            i += 1.0
    return acc


def gather(med, camera, sigma: float, caches: np.ndarray, denominators: np.ndarray, factor: int,
           step_voxels: float = 0.5, supersample: int = 4, bounds=None, grid=None) -> np.ndarray:
    """E (C, H, W) float32: the view integral of the C cache fields S = ``caches`` / ``denominators``
    ((C, cz, cy, cx) and (cz, cy, cx), :func:`cache_fields`), interpolated between the cells by their confidence
    (:func:`interpolation_fields`).

    ``bounds``: (lo, hi) world box the march is limited to (where the density is non-zero; default the
    volume's box). ``grid``: the volume's :class:`natscene.scatter.majorant.MajorantGrid`, whose empty cells the
    march passes over in whole steps (the same sample points, the same result: a step in an empty cell adds
    nothing); a march evaluates every image at every step it takes, so on a cloud that fills a small part of its
    box most of the work is in empty space."""
    caches = np.asarray(caches, np.float32)
    C = caches.shape[0]
    W, H = camera.width, camera.height
    if C == 0 or sigma <= 0:
        return np.zeros((C, H, W), np.float32)
    nz, ny, nx = med.volume.density.shape
    cz, cy, cx = caches.shape[1:]
    vox = (med.bbox_max - med.bbox_min) / np.array([nx, ny, nz])
    cache_ext = mi.ScalarVector3f(*[float(e) for e in vox * factor * np.array([cx, cy, cz])])
    lo = mi.ScalarPoint3f(*[float(e) for e in med.bbox_min])
    fields = np.concatenate(interpolation_fields(caches, denominators))
    tex = mi.Texture3f(mi.TensorXf(np.ascontiguousarray(np.moveaxis(fields, 0, -1))))
    box_lo, box_hi = bounds if bounds is not None else (med.bbox_min, med.bbox_max)
    o, d, _ = camera_rays(camera, supersample, stratified=supersample > 1)
    acc = _march(med, tex, C, o, d, dr.opaque(mi.Float, float(sigma) * med.scale), med.voxel * step_voxels, lo, cache_ext,
                 np.asarray(box_lo, np.float64), np.asarray(box_hi, np.float64), grid)
    return pixel_means(acc, supersample, W, H)


def _local_linear(num: np.ndarray, den: np.ndarray, guide: np.ndarray, width: float):
    """Cross-bilateral local-linear smoothing of S = num / den over 3x3x3 cells.

    Per cell c, S_c = a is the intercept of the plane a + b·o (o the neighbour offset) fitted by weighted least
    squares to the neighbours' ratios S_o = num_o / den_o with weights k_o den_o (k_o the tent times the
    guide's Gaussian): normal equations M [a, b] = r with M = Σ k_o den_o [1, o][1, o]^T and
    r = Σ k_o num_o [1, o]. Where the plane is ill-determined (a cell with few dense neighbours) or its
    intercept is negative, the weighted mean Σ k num / Σ k den is used. Returns (a·den, den) so that the
    caller's ratio gives a."""
    cz, cy, cx = den.shape
    lead = num.shape[:-3]
    pn = np.pad(num, [(0, 0)] * len(lead) + [(1, 1)] * 3)
    pd = np.pad(den, 1)
    pg = np.pad(guide, 1, mode="edge")
    inv2w2 = 0.5 / width ** 2
    M = np.zeros((cz, cy, cx, 4, 4))
    r = np.zeros(lead + (cz, cy, cx, 4))
    for dz in (-1, 0, 1):
        for dy in (-1, 0, 1):
            for dx in (-1, 0, 1):
                sl = (slice(1 + dz, 1 + dz + cz), slice(1 + dy, 1 + dy + cy), slice(1 + dx, 1 + dx + cx))
                k = (0.5 ** (3 + abs(dz) + abs(dy) + abs(dx))) * np.exp(-inv2w2 * (pg[sl] - guide) ** 2)
                v = np.array([1.0, dx, dy, dz])
                kd = k * pd[sl]
                M += kd[..., None, None] * np.outer(v, v)
                r += (k * pn[(Ellipsis,) + sl])[..., None] * v
    mean_den = M[..., 0, 0]
    ok = mean_den > 0
    u = np.zeros((cz, cy, cx, 4))
    e0 = np.zeros(4)
    e0[0] = 1.0
    Mo = M[ok] + np.eye(4) * (1e-9 * mean_den[ok])[:, None, None]
    cond = np.linalg.cond(Mo)
    good = cond < 1e4
    sol = np.zeros((Mo.shape[0], 4))
    if good.any():
        sol[good] = np.linalg.solve(Mo[good], np.broadcast_to(e0, (int(good.sum()), 4))[..., None])[..., 0]
    u[ok] = sol
    a_lin = np.einsum("...zyxi,zyxi->...zyx", r, u)
    a_mean = np.divide(r[..., 0], mean_den, out=np.zeros(r.shape[:-1]), where=ok)
    use_lin = np.zeros((cz, cy, cx), bool)
    use_lin[ok] = good
    a = np.where(use_lin & (a_lin >= 0), a_lin, a_mean)
    return a * den, den
