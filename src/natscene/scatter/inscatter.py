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
inside each trilinear patch.

The view march (Eq. 5's integral with the cache's S_b in place of the sun term) interpolates C_b and Q
trilinearly and divides after the interpolation (normalised interpolation: a cell with little visible
density weighs in by the little it holds, a cell without density not at all), and integrates each segment
exactly for a density constant over it, as :mod:`.single`:

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

__all__ = ["voxel_camera_depth", "CameraDepth", "blended_depth", "EXACT_STEEPNESS", "visibility",
           "weighted_voxel_integrals", "block_sum", "cache_fields", "gather", "VISIBLE_DEPTH"]

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


#: the camera depth's change across a voxel (sig_k x depth, summed over the axes) up to which a box-filling volume's
#: visibility weight takes the exact depth, and from which the voxel-centred one (between: a linear blend): the
#: denominator's 4 Gauss-Legendre nodes a voxel integrate e^-2.5 across it within 0.1 % and e^-4 within 1 %, and
#: fail where a grazing view crosses a face voxel (e^-200 across it)
EXACT_STEEPNESS = (2.5, 4.0)


class CameraDepth:
    """D̃(x), the voxel-centred D_cam (:func:`voxel_camera_depth`) between the voxels: the lookup of the visibility
    weight.

    Trilinear in D_cam, except in a volume whose density reaches its box's faces (``med.face_dense``). There the
    trilinear D_cam is held over the half voxel at a face, where it overestimates the depth, and the cells'
    weighted mean leaned to their deeper part: a slab filling its box read 3-4 % bright at 100 and 300 optical
    depths (docs/stages/precompute.md). Such a volume also holds the mean density along each voxel's ray, D_cam / t
    (t: :func:`camera_reach`), whose interpolation times x's own t is the exact depth in a box of constant density,
    and the depth's change across each voxel (the sum over the axes of its central differences): the weight takes
    the exact depth where sig_k times that change is at most :data:`EXACT_STEEPNESS` [0] and the trilinear one
    from [1] on (:func:`blended_depth`), so that the denominator's quadrature stays exact.
    """

    def __init__(self, med, depth_vox: np.ndarray, camera_position):
        self.med = med
        self.camera_position = tuple(float(e) for e in camera_position)
        self.per_length = bool(getattr(med, "face_dense", False))
        depth = np.asarray(depth_vox, np.float32)
        self.tex = _texture(depth)
        self.mean_tex = self.steep_tex = None
        if self.per_length:
            nz, ny, nx = depth.shape
            vox = (med.bbox_max - med.bbox_min) / np.array([nx, ny, nz])
            zz, yy, xx = np.meshgrid(*[(np.arange(n) + 0.5) for n in (nz, ny, nx)], indexing="ij")
            pts = med.bbox_min + np.stack([xx.ravel(), yy.ravel(), zz.ravel()], -1) * vox
            def reach_at(q):
                return np.asarray(camera_reach(med, self.camera_position,
                                               mi.Point3f(*[q[:, i].astype(np.float32) for i in range(3)])))
            reach = reach_at(pts).reshape(depth.shape)
            mean = depth / np.maximum(reach, 1e-6 * med.voxel)
            self.mean_tex = _texture(mean)
            steep = sum(np.abs(np.gradient(depth.astype(np.float64), axis=a)) if depth.shape[a] > 1 else 0.0
                        for a in range(3))
            # the exact depth's own change across the voxel: where the voxel's ray leaves the box through a face
            # the camera sees at a grazing angle, its reach falls to 0 within the voxel (1 / cos per unit across
            # the face) while the centres' differences, whose rays leave through the same face, need not show it
            half = np.diag(vox / 2)
            across = sum(np.abs(reach_at(pts + half[a]) - reach_at(pts - half[a])) for a in range(3))
            steep = np.maximum(steep, mean * across.reshape(depth.shape))
            self.steep_tex = _texture(steep)

    def parts(self, p, uvw):
        """(trilinear D_cam, exact depth, change across a voxel) at world points ``p`` (texture coordinates
        ``uvw``); the last two None unless the volume fills its box."""
        d = self.tex.eval(uvw)[0]
        if not self.per_length:
            return d, None, None
        return (d, self.mean_tex.eval(uvw)[0] * camera_reach(self.med, self.camera_position, p),
                self.steep_tex.eval(uvw)[0])

    def __call__(self, p, uvw, sig_k):
        """D̃ at world points ``p`` (their texture coordinates ``uvw``) for the extinction ``sig_k``."""
        return blended_depth(*self.parts(p, uvw), sig_k)


def _texture(values: np.ndarray):
    """A trilinear ``mi.Texture3f`` of voxel-centred values [nz, ny, nx]."""
    return mi.Texture3f(mi.TensorXf(np.ascontiguousarray(np.asarray(values, np.float32)[..., None])))


def blended_depth(depth, exact, steepness, sig_k):
    """The visibility weight's depth from :meth:`CameraDepth.parts` (numpy or Dr.Jit arrays): ``depth`` where
    ``exact`` is None, else ``exact`` where sig_k ``steepness`` <= :data:`EXACT_STEEPNESS` [0], ``depth`` from [1]
    on, linear between."""
    if exact is None:
        return depth
    lo, hi = EXACT_STEEPNESS
    x = (hi - sig_k * steepness) / (hi - lo)
    a = (abs(x) - abs(x - 1.0) + 1.0) / 2.0             # x clipped to [0, 1], for numpy and Dr.Jit arrays alike
    return depth + a * (exact - depth)


def visibility(depth: CameraDepth, p, uvw, sig_k):
    """w(x) = exp(-sig_k D̃(x)): the camera transmittance at world points ``p`` (texture coordinates ``uvw``), D̃
    the interpolated D_cam (:class:`CameraDepth`). The weight of every tally (:mod:`.photons`) and of the
    cache's denominator (:func:`weighted_voxel_integrals`)."""
    return dr.exp(-sig_k * depth(p, uvw, sig_k))


#: Gauss-Legendre nodes (2 per half voxel, in voxel units from the voxel's low corner): each half voxel lies
#: inside one patch of the cell-centred trilinear textures, where the integrand is smooth
_GL = np.array([0.25 - 0.25 / np.sqrt(3.0), 0.25 + 0.25 / np.sqrt(3.0), 0.75 - 0.25 / np.sqrt(3.0),
                0.75 + 0.25 / np.sqrt(3.0)])


def weighted_voxel_integrals(med, depth_vox: np.ndarray, camera_position, sig_k: float,
                             chunk: int = 1 << 17) -> np.ndarray:
    """∫_v rho(x) w(x) dV / voxel volume for every voxel v, float64 [nz, ny, nx], w the visibility
    (:func:`visibility`).

    4 x 4 x 4 Gauss-Legendre nodes per voxel (2 per half voxel and axis, :data:`_GL`): exact for the trilinear
    density alone, and within 0.2 % for a transmittance that falls by e^-3 across a voxel. Voxels the camera
    cannot see (w < 1e-8 everywhere in them) and voxels without density near them are left 0 (their tallies
    are weighted below 1e-8 too)."""
    from scipy.ndimage import binary_dilation, maximum_filter
    d = np.asarray(med.volume.density, np.float32)
    nz, ny, nx = d.shape
    out = np.zeros(d.shape, np.float64)
    reach = sig_k * (np.asarray(depth_vox, np.float64) - maximum_filter(d, size=3) * 2.0 * med.voxel)
    live = binary_dilation(d > 0, iterations=1) & (reach < VISIBLE_DEPTH)
    iz, iy, ix = np.nonzero(live)
    if iz.size == 0:
        return out
    depth = CameraDepth(med, depth_vox, camera_position)
    lo, ext = mi.ScalarPoint3f(*med.bbox_min), mi.ScalarVector3f(*(med.bbox_max - med.bbox_min))
    gl = mi.Float(_GL.astype(np.float32))
    for c0 in range(0, iz.size, chunk):
        sel = slice(c0, min(c0 + chunk, iz.size))
        n = iz[sel].size
        k = dr.arange(mi.UInt32, n * 64)
        v, o = k // 64, k % 64
        ox, oy, oz = dr.gather(mi.Float, gl, o % 4), dr.gather(mi.Float, gl, (o // 4) % 4), dr.gather(mi.Float, gl, o // 16)
        uvw = mi.Point3f((mi.Float(dr.gather(mi.UInt32, mi.UInt32(ix[sel].astype(np.uint32)), v)) + ox) / nx,
                         (mi.Float(dr.gather(mi.UInt32, mi.UInt32(iy[sel].astype(np.uint32)), v)) + oy) / ny,
                         (mi.Float(dr.gather(mi.UInt32, mi.UInt32(iz[sel].astype(np.uint32)), v)) + oz) / nz)
        f = dr.maximum(med.density_tex.eval(uvw)[0], 0.0) * visibility(depth, lo + uvw * ext, uvw, sig_k)
        out[iz[sel], iy[sel], ix[sel]] = np.asarray(dr.block_sum(f, 64), np.float64) / 64.0
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
    The in-scattered radiance is their ratio, S = C / Q; :func:`gather` interpolates C and Q separately and
    divides after the interpolation (normalised interpolation), so that a cell with little visible density
    weighs in by the little it holds, and a cell without density not at all.

    With ``guide`` (cz, cy, cx; the cells' optical depth toward the camera) and ``guide_width`` > 0, S is
    smoothed by a 3x3x3 cross-bilateral local-linear fit (:func:`_local_linear`): a [1, 2, 1] tent in space
    times exp(-(Δguide)² / (2 guide_width²)), so that it averages cells at the same optical depth from the
    camera (along the visible surface) but not across depth. The fit is local-linear, not a weighted mean: a
    weighted mean of S pulls the cells at the cloud's edge toward the denser interior, which brightened thin
    clouds by 5-20 % against Mitsuba; a local plane has no such first-order bias.
    """
    den = np.asarray(weighted_integrals, np.float64)
    # a cell the camera cannot see (Q = 0: :func:`weighted_voxel_integrals`) holds nothing: tallies that reached it
    # anyway would be divided by the interpolated Q of its neighbours, vanishing toward its centre
    num = np.where(den > 0, np.asarray(numerators, np.float64), 0.0)
    if guide is not None and guide_width > 0:
        num, den = _local_linear(num, den, np.asarray(guide, np.float64), float(guide_width))
    top = float(den.max()) if den.size else 0.0
    if top <= 0:
        return np.zeros(num.shape, np.float32), np.zeros(den.shape, np.float32)
    return (num / top).astype(np.float32), (den / top).astype(np.float32)


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
    ((C, cz, cy, cx) and (cz, cy, cx), :func:`cache_fields`), each interpolated trilinearly before the division.

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
    fields = np.concatenate([caches, np.asarray(denominators, np.float32)[None]])
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
