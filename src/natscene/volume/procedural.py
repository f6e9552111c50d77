"""The production cloud modeller: a coarse shape eroded and displaced by multi-octave Perlin-Worley noise.

The method of production cloud tools, after Schneider's Nubis ("The real-time volumetric cloudscapes of Horizon:
Zero Dawn", SIGGRAPH 2015 course; "Nubis: authoring real-time volumetric cloudscapes", 2017) and Wrenninge's
pyroclastic displacement ("Production Volume Rendering", 2012, §10.5 / Magnus Wrenninge, SIGGRAPH 2011 course):

1. **Coarse shape.** A low-frequency body on a coarse grid (at most ``COARSE_MAX`` voxels per side): metaballs
   (:mod:`natscene.volume.metaballs`) for ``cumulus`` (a flat-based heap of turrets) and ``cumulonimbus`` (tower,
   broad base, anvil spreading downwind), many heaps with a common flat base (the lifting condensation level) for
   ``cumulus_field``, and a layer broken by a low-frequency cellular coverage field for ``stratocumulus``. Its
   inside is turned into a signed distance d (positive inside, box units; exact Euclidean distance transform).
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
"""
from __future__ import annotations

from dataclasses import dataclass

import numba as nb
import numpy as np
from scipy import ndimage

from natscene.volume import metaballs
from natscene.volume.noise import perlin_tile, perlin_worley_tile, worley_fbm_tile

KINDS = ("cumulus", "cumulonimbus", "stratocumulus", "cumulus_field")
COARSE_MAX = 128        # longest side of the coarse shape grid
TILE = 64               # texels per side of the periodic noise tiles
TILE_CELLS = 4          # noise cells per tile side


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
    coverage: float = 0.6           # stratocumulus / cumulus_field: fraction of the sky covered
    thickness: float = 0.5          # stratocumulus: mean layer thickness, fraction of the box height


DEFAULTS = {
    "cumulus": Shape(billow=1.1, erosion=0.5),
    "cumulonimbus": Shape(base_frequency=5.0, billow=1.0, erosion=0.5),
    "stratocumulus": Shape(base_frequency=8.0, billow=0.8, edge=0.45, erosion=0.5, warp=0.35,
                           coverage=0.7, thickness=0.55),
    "cumulus_field": Shape(blobs=14, base_frequency=14.0, coverage=0.35),
}


def shape_params(kind: str, **overrides) -> Shape:
    """The kind's default :class:`Shape` with ``overrides`` (None values ignored)."""
    if kind not in DEFAULTS:
        raise ValueError(f"unknown procedural cloud kind {kind!r} (one of {', '.join(KINDS)})")
    base = DEFAULTS[kind]
    kw = {k: v for k, v in overrides.items() if v is not None and k in Shape.__dataclass_fields__}
    return Shape(**{**base.__dict__, **kw})


def _smoothstep(e0, e1, x):
    t = np.clip((x - e0) / (e1 - e0), 0.0, 1.0)
    return t * t * (3 - 2 * t)


# ------------------------------------------------------------------------------------------- coarse shapes
def _coarse_grid(res, ext):
    """Coarse grid shape (nz, ny, nx) and its voxel size (box units) for a fine grid ``res`` = (nx, ny, nz)."""
    k = max(1, int(np.ceil(max(res) / COARSE_MAX)))
    cn = [max(4, int(np.ceil(r / k))) for r in res]               # (cnx, cny, cnz)
    return (cn[2], cn[1], cn[0]), ext / np.array(cn, np.float64)


def _field_blobs(rng, ext, p: Shape, margin: float):
    """Metaball heaps of a cumulus field: heaps of random size placed by dart throwing (no two overlapping),
    all with the same flat base (the condensation level), until ``coverage`` of the box floor is reached."""
    ex, ey, ez = ext
    area, covered, blobs, placed = ex * ez, 0.0, [], []
    base_y = margin + 0.06 * ey
    for _ in range(4000):
        if covered >= p.coverage * area:
            break
        w = min(ex, ez) * rng.uniform(0.07, 0.2)                   # heap diameter
        h = min(ey - base_y - margin, w * rng.uniform(0.45, 0.9))   # heap height (humilis .. mediocris)
        cx, cz = rng.uniform(margin + w / 2, ex - margin - w / 2), rng.uniform(margin + w / 2, ez - margin - w / 2)
        if any((cx - x) ** 2 + (cz - z) ** 2 < (0.5 * (w + v)) ** 2 * 0.8 for x, z, v in placed):
            continue
        placed.append((cx, cz, w))
        covered += np.pi * (w / 2) ** 2
        sub = np.array([w, h, w])
        for c, radii, wgt in metaballs.cumulus_blobs(rng, sub, max(4, p.blobs // 2)):
            blobs.append((c + np.array([cx - w / 2, base_y - 0.22 * h * 0.0, cz - w / 2]), radii, wgt))
    return blobs


def coarse_occupancy(kind: str, res, ext, p: Shape, rng, margin: float) -> tuple[np.ndarray, np.ndarray, float]:
    """Inside/outside of the coarse body on the coarse grid: (bool (nz, ny, nx), coarse voxel size, base y).

    ``margin`` (box units) is kept free along every face so the displaced billows are not cut by the box."""
    cshape, cvox = _coarse_grid(res, ext)
    inner = ext - 2 * margin
    if kind in ("cumulus", "cumulonimbus"):
        make = metaballs.cumulus_blobs if kind == "cumulus" else metaballs.cumulonimbus_blobs
        blobs = [(c + margin, r, w) for c, r, w in make(rng, inner, p.blobs)]
    elif kind == "cumulus_field":
        blobs = _field_blobs(rng, ext, p, margin)
    else:
        blobs = None
    if blobs is not None:
        field = metaballs.metaball_field(cshape, ext, blobs)
        occ = field > metaballs.THRESHOLD
        base_y = min(c[1] - 0.5 * r[1] for c, r, _ in blobs)
        base_y = max(base_y, margin)
        return occ, cvox, float(base_y)
    # stratocumulus: a layer between a flat-ish base and an undulating top, broken into cells where a
    # low-frequency cellular field is below the coverage quantile
    cnz, cny, cnx = cshape
    f2 = perlin_worley_tile(TILE, TILE_CELLS, rng)[TILE // 2]            # a 2-D slice: cellular, billowy
    zz = (np.arange(cnz) + 0.5) * cvox[2]
    xx = (np.arange(cnx) + 0.5) * cvox[0]
    cell_freq = p.base_frequency / 4.0                                   # cells across the box
    u = (xx * cell_freq / TILE_CELLS * TILE) % TILE
    v = (zz * cell_freq / TILE_CELLS * TILE) % TILE
    cov = ndimage.map_coordinates(f2, np.meshgrid(v, u, indexing="ij"), order=1, mode="grid-wrap")
    thresh = np.quantile(cov, 1 - p.coverage) if p.coverage < 1 else -np.inf
    yy = (np.arange(cny) + 0.5) * cvox[1]
    base_y = margin + 0.15 * (ext[1] - 2 * margin)
    thick = p.thickness * (ext[1] - 2 * margin)
    # thicker where the cell field is high (cells dome up in their middles)
    dome = np.clip((cov - thresh) / max(float(cov.max() - thresh), 1e-6), 0, 1) if np.isfinite(thresh) \
        else (cov - cov.min()) / max(float(np.ptp(cov)), 1e-6)
    top = base_y + thick * (0.55 + 0.6 * dome)
    occ = (yy[None, :, None] >= base_y) & (yy[None, :, None] <= top[:, None, :]) & (cov[:, None, :] > thresh)
    return occ, cvox, float(base_y)


def signed_distance(occ: np.ndarray, cvox: np.ndarray) -> np.ndarray:
    """Signed Euclidean distance (box units, positive inside) of a coarse occupancy grid, lightly smoothed."""
    sampling = tuple(cvox[::-1])                                         # (z, y, x)
    inside = ndimage.distance_transform_edt(occ, sampling=sampling)
    outside = ndimage.distance_transform_edt(~occ, sampling=sampling)
    sd = np.where(occ, inside - 0.5 * cvox.min(), -(outside - 0.5 * cvox.min()))
    return ndimage.gaussian_filter(sd, 0.7, mode="nearest").astype(np.float32)


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
def _kernel(out, z0, nx, ny, nz, vox, sd, cvox, pw, wf, wx, wy, wz, freq, amp, off, fw, warp, f_er, off_er,
         f_in, off_in, edge, erosion, interior, base_y, base_soft, height, flat_base, window, reach):
    tscale = pw.shape[0] / 4.0                                     # texels per noise cycle (TILE_CELLS)
    nzc = out.shape[0]
    no = freq.shape[0]
    for kz in nb.prange(nzc):
        z = (z0 + kz + 0.5) * vox
        for j in range(ny):
            y = (j + 0.5) * vox
            for i in range(nx):
                x = (i + 0.5) * vox
                d = _coarse(sd, x / cvox[0], y / cvox[1], z / cvox[2])
                if d < -reach:
                    out[kz, j, i] = 0.0
                    continue
                # domain warp (low-frequency vector noise, in [-1, 1] per axis)
                tw = fw * wx.shape[0] / 4.0
                qx = x + warp * _tex(wx, x * tw, y * tw, z * tw)
                qy = y + warp * _tex(wy, x * tw + 17.3, y * tw + 5.1, z * tw)
                qz = z + warp * _tex(wz, x * tw, y * tw + 11.7, z * tw + 3.9)
                # pyroclastic displacement by Perlin-Worley fBm
                h = d
                for o in range(no):
                    s = freq[o] * tscale
                    h += amp[o] * (_tex(pw, qx * s + off[o, 0], qy * s + off[o, 1], qz * s + off[o, 2]) - 0.5)
                if h <= 0.0:
                    out[kz, j, i] = 0.0
                    continue
                t = h / edge
                ramp = 1.0 if t >= 1.0 else t * t
                # Nubis erosion: wispy (e) at the bottom, billowy (1 - e) at the top
                s = f_er * tscale
                e = _tex(wf, qx * s + off_er[0], qy * s + off_er[1], qz * s + off_er[2])
                hb = min(max(y / height, 0.0), 1.0)
                er = erosion * (e * (1.0 - hb) + (1.0 - e) * hb)
                rho = (ramp - er) / (1.0 - er)
                if rho <= 0.0:
                    out[kz, j, i] = 0.0
                    continue
                s = f_in * tscale
                rho *= 1.0 - interior + interior * _tex(pw, x * s + off_in[0], y * s + off_in[1], z * s + off_in[2])
                if flat_base:
                    b = (y - base_y) / base_soft
                    if b <= 0.0:
                        rho = 0.0
                    elif b < 1.0:
                        rho *= b * b * (3.0 - 2.0 * b)
                # window: zero at the box faces (the last `window` of each side)
                wmin = min(min(x, nx * vox - x), min(min(y, ny * vox - y), min(z, nz * vox - z)))
                if wmin < window + vox:
                    a = (wmin - vox) / window                   # the outermost voxel layer is empty
                    rho = 0.0 if a <= 0.0 else rho * a * a * (3.0 - 2.0 * a)
                out[kz, j, i] = min(rho, 1.0)



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
    ext = np.array([nx, ny, nz], np.float64) / max(nx, ny, nz)
    vox = 1.0 / max(nx, ny, nz)
    rng = np.random.default_rng(seed)
    f0 = float(p.base_frequency)
    freq = np.array([f0 * p.lacunarity ** o for o in range(p.octaves)], np.float64)
    amp = np.array([p.billow * p.gain ** o / f0 for o in range(p.octaves)], np.float64)
    reach = 0.5 * float(amp.sum()) + 1e-6
    warp = p.warp / f0
    margin = min(0.45 * reach + 0.3 * warp + 2 * vox, 0.2 * ext.min())
    if kind == "stratocumulus" or kind == "cumulus_field":
        margin = min(margin, 0.25 * ext[1])
    occ, cvox, base_y = coarse_occupancy(kind, (nx, ny, nz), ext, p, rng, margin)
    if not occ.any():
        return np.zeros((nz, ny, nx), np.float32)
    sd = signed_distance(occ, cvox)
    pw = perlin_worley_tile(TILE, TILE_CELLS, rng)
    wf = worley_fbm_tile(TILE, TILE_CELLS, rng)
    wx, wy, wz = (perlin_tile(32, TILE_CELLS, rng) for _ in range(3))
    off = rng.uniform(0, TILE, (p.octaves, 3))
    off_er, off_in = rng.uniform(0, TILE, 3), rng.uniform(0, TILE, 3)
    f_er = float(freq[-1]) * 0.5 if p.octaves > 1 else 2 * f0
    out = np.empty((nz, ny, nx), np.float32)
    kern = _kernel
    if threads:
        import numba
        numba.set_num_threads(max(1, min(int(threads), numba.config.NUMBA_NUM_THREADS)))
    flat = kind != "stratocumulus"
    args = (nx, ny, nz, vox, sd, cvox, pw, wf, wx, wy, wz, freq, amp, off, f0 * 0.5, warp, f_er, off_er,
            f0 * 0.5, off_in, p.edge / f0, float(p.erosion), float(p.interior), base_y, 3 * vox,
            float(ext[1]), flat, 2.5 * vox, reach)
    for z0 in range(0, nz, chunk):
        kern(out[z0:z0 + chunk], z0, *args)
        if progress:
            progress(min(z0 + chunk, nz), nz)
    m = float(out.max())
    if m > 0:
        out /= np.float32(m)
    return out


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
