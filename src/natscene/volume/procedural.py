"""
Procedural cloud modeller
=========================

Defines the production cloud modeller: a coarse shape eroded and displaced by multi-octave Perlin-Worley noise:

-   :func:`generate`: a procedural density grid of a kind (:data:`KINDS`).
-   :func:`shape_params`: a kind's parameters (:class:`Shape`) with overrides.
-   :func:`octave_weights`: the band limit of the displacement fBm.
-   :func:`despeckle`: remove isolated specks.
-   :func:`statistics`: the summary numbers of a grid for meta.yaml.

The method of production cloud tools, after Schneider's Nubis ("The real-time volumetric cloudscapes of Horizon:
Zero Dawn", SIGGRAPH 2015 course; "Nubis: authoring real-time volumetric cloudscapes", 2017) and Wrenninge's
pyroclastic displacement ("Production Volume Rendering", 2012, §10.5 / Magnus Wrenninge, SIGGRAPH 2011 course):

1. **Coarse shape.** A low-frequency body on a coarse grid (at most ``COARSE_MAX`` voxels per side,
   :mod:`natscene.volume.shapes`): a heap of turreted towers for ``cumulus``, tower + flanking line + flat anvil
   spreading downwind for ``cumulonimbus``, heaps of power-law sizes with one flat base (the lifting
   condensation level) for ``cumulus_field``, a layer broken into closed cells for ``stratocumulus``, with
   per-surface factors of the displacement, edge ramp and erosion (:func:`extend_factors`). Its inside is
   turned into a signed distance d (positive inside, box units; exact Euclidean distance transform).
2. **Pyroclastic displacement** (Wrenninge): the surface is displaced along the distance field by an fBm of
   Perlin-Worley noise, ``h = d + sum_o A_o (PW(f_o q + s_o) - 1/2)``, ``f_o = base_frequency * lacunarity^o``,
   ``A_o = billow * gain^o / base_frequency``: with ``gain = 1/lacunarity`` every octave is displaced by the
   same fraction of its own wavelength, so billows on billows appear at every scale (a self-similar, fractal
   boundary). ``q`` is the position domain-warped by a low-frequency vector noise (``warp``, in base
   wavelengths), which shears the billows into rolls and streaks.
3. **Density ramp.** Density rises from 0 at the displaced surface over ``edge`` base wavelengths as
   ``t^2`` (``t = h / edge_width``), so it falls off toward the edge instead of stopping.
4. **Erosion** (Nubis): ``rho = remap(ramp, e, 1, 0, 1)`` with a high-frequency inverted-Worley fBm ``e``
   (``erosion`` strength) that, where the ramp is thin, eats the edge into wisps and leaves the core intact;
   Nubis' height blend uses the wispy noise ``e`` at the bottom and the billowy ``1 - e`` at the top.
5. **Interior** variation by a low-frequency Perlin-Worley factor (``interior``), a flat base that fades over a
   few voxels (cumulus, cumulonimbus, field), and a window that takes the density to 0 at the box faces.

Steps 2-5 run in one compiled kernel (numba, ``prange`` over z slices) that reads only the small coarse distance
grid and four 64^3 periodic noise tiles (:mod:`natscene.volume.noise`), so memory is the output grid alone
(float32; 4 GiB at 1024^3) and the grid is filled in z chunks. Every voxel is computed independently: the same
seed gives the same bytes whatever the thread count.

References
----------
-   Schneider, A. (2017). Nubis: authoring real-time volumetric cloudscapes with the Decima engine. SIGGRAPH 2017
    course Advances in Real-Time Rendering in Games.
-   Schneider, A., & Vos, N. (2015). The real-time volumetric cloudscapes of Horizon: Zero Dawn. SIGGRAPH 2015
    course Advances in Real-Time Rendering in Games.
-   Wrenninge, M. (2012). Production Volume Rendering: Design and Implementation. CRC Press.
-   Wrenninge, M., et al. (2011). Production volume rendering. SIGGRAPH 2011 course.
"""
from __future__ import annotations

from dataclasses import dataclass

import numba as nb
import numpy as np
from scipy import ndimage

from natscene.volume import shapes
from natscene.volume.noise import perlin_tile, perlin_worley_tile, worley_fbm_tile

__all__ = ["KINDS", "generate", "Shape", "shape_params", "octave_weights", "despeckle", "statistics"]

KINDS = ("cumulus", "cumulonimbus", "stratocumulus", "cumulus_field")
COARSE_MAX = 128        # longest side of the coarse shape grid
TILE = 64               # texels per side of the periodic noise tiles
TILE_CELLS = 4          # noise cells per tile side
MAX_OCTAVES = 10        # the schema's maximum
LAM_FULL, LAM_OFF = 6.0, 3.0   # band limit: octaves of wavelength >= LAM_FULL voxels whole, <= LAM_OFF gone


@dataclass(frozen=True)
class Shape:
    """Per-kind modelling parameters (defaults; any can be set in the config)."""

    blobs: int = 40
    octaves: int = 6
    lacunarity: float = 2.0
    gain: float = 0.7               # amplitude ratio of successive octaves (> 1/lacunarity: rougher when finer)
    base_frequency: float = 3.0     # cycles across the longest side of the box (first billow octave)
    billow: float = 1.2             # displacement amplitude of the first octave, in its wavelengths
    warp: float = 0.25              # domain warp, in base wavelengths
    edge: float = 0.45              # density ramp width, in base wavelengths
    erosion: float = 0.6            # strength of the high-frequency edge erosion
    interior: float = 0.35          # low-frequency density variation inside
    streak: float = 2.0             # erosion noise stretched along the wind (x) by this factor: streaky wisps
    coverage: float = 0.6           # stratocumulus / cumulus_field: fraction of the sky covered
    thickness: float = 0.5          # stratocumulus: mean layer thickness, fraction of the box height
    cells: float = 6.0              # stratocumulus: convective cells across the longest side
    relief: float = 1.0             # stratocumulus: thickness variation of the cells (0: flat top)
    heap_min: float = 0.025         # cumulus_field: smallest heap diameter, fraction of the longest side
    heap_max: float = 0.2           # cumulus_field: largest heap diameter


DEFAULTS = {
    "cumulus": Shape(billow=1.1, gain=0.8, erosion=0.4, streak=1.5),
    "cumulonimbus": Shape(base_frequency=5.0, billow=0.85, gain=0.8, erosion=0.5, streak=1.0),
    "stratocumulus": Shape(base_frequency=8.0, billow=0.8, edge=0.45, erosion=0.5, warp=0.35,
                           coverage=0.7, thickness=0.55),
    "cumulus_field": Shape(blobs=8, base_frequency=14.0, coverage=0.6, streak=1.5),
}


def shape_params(kind: str, **overrides) -> Shape:
    """The kind's default :class:`Shape` with ``overrides`` (None values ignored)."""
    if kind not in DEFAULTS:
        raise ValueError(f"unknown procedural cloud kind {kind!r} (one of {', '.join(KINDS)})")
    base = DEFAULTS[kind]
    kw = {k: v for k, v in overrides.items() if v is not None and k in Shape.__dataclass_fields__}
    return Shape(**{**base.__dict__, **kw})


def _coarse_grid(res, ext):
    """Coarse grid shape (nz, ny, nx) and its voxel size (box units) for a fine grid ``res`` = (nx, ny, nz)."""
    k = max(1, int(np.ceil(max(res) / COARSE_MAX)))
    cn = [max(4, int(np.ceil(r / k))) for r in res]               # (cnx, cny, cnz)
    return (cn[2], cn[1], cn[0]), ext / np.array(cn, np.float64)


def coarse_shape(kind: str, res, ext, p: Shape, rng, margin: float) -> tuple[shapes.Coarse, np.ndarray]:
    """The kind's coarse body (:mod:`natscene.volume.shapes`) on the coarse grid, and the coarse voxel size.

    ``margin`` (box units) is kept free along every face so the displaced billows are not cut by the box."""
    cshape, cvox = _coarse_grid(res, ext)
    if kind == "cumulus":
        body = shapes.cumulus(rng, cshape, cvox, ext, margin, p.blobs)
    elif kind == "cumulonimbus":
        body = shapes.cumulonimbus(rng, cshape, cvox, ext, margin, p.blobs)
    elif kind == "cumulus_field":
        body = shapes.field(rng, cshape, cvox, ext, margin, p.blobs, p.coverage, p.heap_min, p.heap_max)
    else:
        body = shapes.stratocumulus(rng, cshape, cvox, ext, margin, p.coverage, p.thickness, p.cells,
                                    p.base_frequency, p.edge / p.base_frequency, p.relief)
    return body, cvox


def signed_distance(occ: np.ndarray, cvox: np.ndarray) -> np.ndarray:
    """Signed Euclidean distance (box units, positive inside) of a coarse occupancy grid, lightly smoothed."""
    sampling = tuple(cvox[::-1])                                         # (z, y, x)
    inside = ndimage.distance_transform_edt(occ, sampling=sampling)
    outside = ndimage.distance_transform_edt(~occ, sampling=sampling)
    sd = np.where(occ, inside - 0.5 * cvox.min(), -(outside - 0.5 * cvox.min()))
    return ndimage.gaussian_filter(sd, 0.7, mode="nearest").astype(np.float32)


def extend_factors(occ: np.ndarray, cvox: np.ndarray, grids) -> list[np.ndarray]:
    """The per-voxel factors of a coarse body, defined on the body, carried outside: every voxel takes the
    value of the nearest body voxel (the feature transform of the exact Euclidean distance transform), so the
    displacement that grows a billow out of a surface is the one of that surface, however far it reaches;
    then lightly smoothed so the factors do not jump between surfaces."""
    idx = ndimage.distance_transform_edt(~occ, sampling=tuple(cvox[::-1]), return_distances=False,
                                         return_indices=True)
    out = []
    for g in grids:
        g = np.asarray(g, np.float32)
        if np.all(g == g.flat[0]):
            out.append(np.ascontiguousarray(g))
            continue
        out.append(np.ascontiguousarray(ndimage.gaussian_filter(g[idx[0], idx[1], idx[2]], 1.0), np.float32))
    return out


# ---------------------------------------------------------------------------------------- fine-grid kernel
@nb.njit(inline="always", fastmath=True, cache=True)
def _tex(t, x, y, z):
    """Trilinear lookup of a periodic tile at texel coordinates (x, y, z)."""
    n = t.shape[0]
    x -= 0.5
    y -= 0.5
    z -= 0.5
    fx, fy, fz = np.floor(x), np.floor(y), np.floor(z)
    ax, ay, az = x - fx, y - fy, z - fz
    ix, iy, iz = int(fx) % n, int(fy) % n, int(fz) % n
    jx, jy, jz = (ix + 1) % n, (iy + 1) % n, (iz + 1) % n
    c00 = t[iz, iy, ix] * (1 - ax) + t[iz, iy, jx] * ax
    c01 = t[iz, jy, ix] * (1 - ax) + t[iz, jy, jx] * ax
    c10 = t[jz, iy, ix] * (1 - ax) + t[jz, iy, jx] * ax
    c11 = t[jz, jy, ix] * (1 - ax) + t[jz, jy, jx] * ax
    return (c00 * (1 - ay) + c01 * ay) * (1 - az) + (c10 * (1 - ay) + c11 * ay) * az


@nb.njit(inline="always", fastmath=True, cache=True)
def _coarse(sd, x, y, z):
    """Trilinear lookup of the coarse distance grid at coarse-voxel coordinates, clamped."""
    nz, ny, nx = sd.shape
    x = min(max(x - 0.5, 0.0), nx - 1.000001)
    y = min(max(y - 0.5, 0.0), ny - 1.000001)
    z = min(max(z - 0.5, 0.0), nz - 1.000001)
    ix, iy, iz = int(x), int(y), int(z)
    ax, ay, az = x - ix, y - iy, z - iz
    c00 = sd[iz, iy, ix] * (1 - ax) + sd[iz, iy, ix + 1] * ax
    c01 = sd[iz, iy + 1, ix] * (1 - ax) + sd[iz, iy + 1, ix + 1] * ax
    c10 = sd[iz + 1, iy, ix] * (1 - ax) + sd[iz + 1, iy, ix + 1] * ax
    c11 = sd[iz + 1, iy + 1, ix] * (1 - ax) + sd[iz + 1, iy + 1, ix + 1] * ax
    return (c00 * (1 - ay) + c01 * ay) * (1 - az) + (c10 * (1 - ay) + c11 * ay) * az


@nb.njit(parallel=True, cache=True, fastmath=True)
def _kernel(out, z0, nx, ny, nz, vox, sd, ampg, edgeg, erog, cvox, pw, wf, wx, wy, wz, freq, amp, off, fw, warp, f_er,
            off_er, streak, f_in, off_in, edge, erosion, interior, base_y, base_soft, ceiling, ceil_soft, height,
            window, reach):
    tscale = pw.shape[0] / 4.0                                     # texels per noise cycle (TILE_CELLS)
    nzc = out.shape[0]
    no = freq.shape[0]
    for kz in nb.prange(nzc):
        z = (z0 + kz + 0.5) * vox
        for j in range(ny):
            y = (j + 0.5) * vox
            for i in range(nx):
                x = (i + 0.5) * vox
                cx, cy, cz = x / cvox[0], y / cvox[1], z / cvox[2]
                d = _coarse(sd, cx, cy, cz)
                if d < -reach:
                    out[kz, j, i] = 0.0
                    continue
                a_loc = _coarse(ampg, cx, cy, cz)
                # domain warp (low-frequency vector noise, in [-1, 1] per axis)
                tw = fw * wx.shape[0] / 4.0
                qx = x + warp * _tex(wx, x * tw, y * tw, z * tw)
                qy = y + warp * _tex(wy, x * tw + 17.3, y * tw + 5.1, z * tw)
                qz = z + warp * _tex(wz, x * tw, y * tw + 11.7, z * tw + 3.9)
                # pyroclastic displacement by a band-limited Perlin-Worley fBm
                h = 0.0
                for o in range(no):
                    if amp[o] == 0.0:
                        continue
                    s = freq[o] * tscale
                    h += amp[o] * (_tex(pw, qx * s + off[o, 0], qy * s + off[o, 1], qz * s + off[o, 2]) - 0.5)
                h = d + a_loc * h
                if h <= 0.0:
                    out[kz, j, i] = 0.0
                    continue
                t = h / (edge * _coarse(edgeg, cx, cy, cz))
                ramp = 1.0 if t >= 1.0 else t * t
                # Nubis erosion, streaked along the wind (x): wispy (e) at the bottom, billowy (1 - e) at the top
                s = f_er * tscale
                e = _tex(wf, qx * s / streak + off_er[0], qy * s + off_er[1], qz * s + off_er[2])
                hb = min(max(y / height, 0.0), 1.0)
                er = erosion * _coarse(erog, cx, cy, cz) * (e * (1.0 - hb) + (1.0 - e) * hb)
                rho = (ramp - er) / (1.0 - er)
                if rho <= 0.0:
                    out[kz, j, i] = 0.0
                    continue
                s = f_in * tscale
                rho *= 1.0 - interior + interior * _tex(pw, x * s + off_in[0], y * s + off_in[1], z * s + off_in[2])
                # flat base (the condensation level), soft over a few voxels
                b = (y - base_y) / base_soft
                if b <= 0.0:
                    rho = 0.0
                elif b < 1.0:
                    rho *= b * b * (3.0 - 2.0 * b)
                # ceiling (an anvil's flat top at the tropopause): only where the displacement is damped (a_loc < 1)
                if y > ceiling - ceil_soft:
                    c = min((y - ceiling + ceil_soft) / (2.0 * ceil_soft), 1.0)
                    keep = min(max((a_loc - 0.6) / 0.4, 0.0), 1.0)
                    rho *= keep + (1.0 - keep) * (1.0 - c * c * (3.0 - 2.0 * c))
                # window: zero at the box faces (the last `window` of each side)
                wmin = min(min(x, nx * vox - x), min(min(y, ny * vox - y), min(z, nz * vox - z)))
                if wmin < window + vox:
                    a = (wmin - vox) / window                   # the outermost voxel layer is empty
                    rho = 0.0 if a <= 0.0 else rho * a * a * (3.0 - 2.0 * a)
                out[kz, j, i] = min(rho, 1.0)


def octave_weights(freq: np.ndarray, max_res: int) -> np.ndarray:
    """Band limit of the displacement fBm: octave ``f`` (cycles per longest side) has a wavelength of
    ``max_res / f`` voxels; it is kept whole above 6 voxels, faded out by a smoothstep to 0 at 3 voxels (and
    beyond): the grid cannot hold it, and sampled anyway it turns into per-voxel noise (isolated specks)."""
    lam = max_res / np.asarray(freq, np.float64)
    t = np.clip((lam - LAM_OFF) / (LAM_FULL - LAM_OFF), 0.0, 1.0)
    return t * t * (3 - 2 * t)


def generate(kind: str, resolution, seed: int = 1, chunk: int = 64, threads: int | None = None,
             progress=None, **params) -> np.ndarray:
    """A procedural cloud density grid float32 [nz, ny, nx] in [0, 1].

    ``kind``: cumulus | cumulonimbus | stratocumulus | cumulus_field; ``resolution`` (nx, ny, nz), y up, each
    1..1024; the grid spans a box whose longest side is 1 (world size is applied by the caller). ``params``
    override the kind's :class:`Shape` defaults. ``chunk``: z slices per kernel call (``progress(done, nz)``
    is called after each); ``threads``: numba threads (default: numba's)."""
    p = shape_params(kind, **params)
    nx, ny, nz = (int(v) for v in resolution)
    if min(nx, ny, nz) < 1 or max(nx, ny, nz) > 1024:
        raise ValueError(f"resolution {resolution} must be 3 integers in 1..1024")
    n_max = max(nx, ny, nz)
    ext = np.array([nx, ny, nz], np.float64) / n_max
    vox = 1.0 / n_max
    rng = np.random.default_rng(seed)
    f0 = float(p.base_frequency)
    freq = np.array([f0 * p.lacunarity ** o for o in range(p.octaves)], np.float64)
    amp = np.array([p.billow * p.gain ** o / f0 for o in range(p.octaves)], np.float64)
    amp *= octave_weights(freq, n_max)
    reach = 0.5 * float(amp.sum()) + 1e-6
    warp = p.warp / f0
    margin = min(0.3 * reach + 0.3 * warp + 2 * vox, 0.2 * ext.min())
    if kind == "stratocumulus" or kind == "cumulus_field":
        margin = min(margin, 0.12 * ext[1] + 2 * vox)           # a flat box: keep its height for the layer
    body, cvox = coarse_shape(kind, (nx, ny, nz), ext, p, rng, margin)
    if not body.occ.any():
        return np.zeros((nz, ny, nx), np.float32)
    reach *= max(float(body.amp.max()), 1e-6)
    sd = signed_distance(body.occ, cvox)
    factors = extend_factors(body.occ, cvox, (body.amp, body.edge, body.erosion))
    pw = perlin_worley_tile(TILE, TILE_CELLS, rng)
    wf = worley_fbm_tile(TILE, TILE_CELLS, rng)
    wx, wy, wz = (perlin_tile(32, TILE_CELLS, rng) for _ in range(3))
    off = rng.uniform(0, TILE, (MAX_OCTAVES, 3))[: p.octaves]   # same stream whatever the octave count
    off_er, off_in = rng.uniform(0, TILE, 3), rng.uniform(0, TILE, 3)
    # erosion noise: half the finest octave's frequency, but no finer than the grid holds (its Worley fBm
    # carries content up to 4x its frequency: at max_res / 12 that is a 3-voxel wavelength)
    f_er = min(float(freq[-1]) * 0.5 if p.octaves > 1 else 2 * f0, n_max / 12.0)
    out = np.empty((nz, ny, nx), np.float32)
    if threads:
        import numba
        numba.set_num_threads(max(1, min(int(threads), numba.config.NUMBA_NUM_THREADS)))
    args = (nx, ny, nz, vox, sd, *factors, cvox, pw, wf, wx, wy, wz, freq, amp, off, f0 * 0.5, warp,
            f_er, off_er, float(p.streak), f0 * 0.5, off_in, p.edge / f0, float(p.erosion), float(p.interior),
            body.base_y, 3 * vox, body.ceiling, max(3 * vox, 0.02 * ext[1]), float(ext[1]), 2.5 * vox, reach)
    for z0 in range(0, nz, chunk):
        _kernel(out[z0:z0 + chunk], z0, *args)
        if progress:
            progress(min(z0 + chunk, nz), nz)
    m = float(out.max())
    if m > 0:
        out /= np.float32(m)
    despeckle(out)
    return out


def despeckle(density: np.ndarray, level: float = 0.05, min_voxels: int = 27, halo: float = 0.01) -> np.ndarray:
    """Remove isolated specks in place (as production tools delete small islands of a VDB by connectivity):
    the visible specks, 26-connected components of ``density > level`` with fewer than ``min_voxels`` voxels
    (a 3x3x3 block), are set to 0, and so is every component of ``density > halo`` left without a visible
    body (a speck's faint halo, or a faint fleck on its own). With the band-limited noise they are a few per
    thousand of the cloud's voxels; what stays (connected to the cloud, or larger) are the coherent wisps."""
    cube = np.ones((3, 3, 3), bool)
    visible = density > level
    lab, n = ndimage.label(visible, structure=cube)
    if n == 0:
        return density
    sizes = np.bincount(lab.ravel())
    small = sizes < min_voxels
    small[0] = False
    speck = small[lab]
    body = visible & ~speck
    density[speck] = 0.0
    lab, n = ndimage.label(density > halo, structure=cube)
    has_body = np.bincount(lab[body], minlength=n + 1) > 0
    has_body[0] = True
    density[~has_body[lab]] = 0.0
    return density


def statistics(density: np.ndarray) -> dict:
    """Summary numbers for meta.yaml."""
    filled = density > 1e-3
    cloud = density > 0
    return {
        "fill_fraction": float(filled.mean()),
        "mean_density_in_cloud": float(density[filled].mean()) if filled.any() else 0.0,
        "max_density": float(density.max()),
        "thin_edge_fraction": float(((density > 0) & (density < 0.2)).sum() / max(int(cloud.sum()), 1)),
    }
