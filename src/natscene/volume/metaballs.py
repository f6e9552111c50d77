"""
Metaball clouds
===============

Defines coarse cloud shapes from metaballs, and the smooth generator :func:`generate_smooth` (the benchmark
baseline and the "before" previews; :mod:`natscene.volume.procedural` is the production modeller, which uses the
metaball field here for its coarse shapes):

-   :func:`metaball_field`: the sum of Wyvill falloffs on a grid; :data:`THRESHOLD`: the implicit surface's
    iso-value.
-   :func:`generate_smooth`: a smooth procedural density grid (cumulus or cumulonimbus).

The smooth generator, procedural in the style of Ebert et al. (implicit + turbulence):

1. **Implicit body.** Metaballs with Wyvill's soft falloff ``w (1 - r^2)^3`` (r = ellipsoidal distance / radius,
   0 for r >= 1) are summed into a field F. Cumulus: a flat-based heap of blobs, each new blob sitting on a
   random earlier one, up and outward, smaller than its parent (cauliflower turrets). Cumulonimbus: a tall
   tower of stacked blobs, a wide flat anvil of flattened ellipsoids spreading downwind at the top, and a broad
   base.
2. **Turbulence.** The field is domain-warped by a vector fBm (F(p + a * fbm3(p))), which breaks the blobs'
   symmetry into wisps.
3. **Billows and detail.** Worley F1 noise (two octaves) adds rounded cellular bumps on the surface, and
   scalar fBm adds internal variation.
4. **Soft edge.** density = smoothstep(0, softness, F_w - 0.3 + billow term + detail term), times a flat-base
   ramp; the result lies in [0, 1].

Everything is vectorised over the grid; the only Python loop is over the (tens of) metaballs, each
evaluated on its own bounding sub-box.

References
----------
-   Ebert, D. S., Musgrave, F. K., Peachey, D., & Perlin, K. (2009). Texturing and Modeling: A Procedural
    Approach (3rd ed.). Morgan Kaufmann.
-   Worley, S. (1996). A cellular texture basis function. Proceedings of ACM SIGGRAPH 1996, 291–294.
-   Wyvill, G., McPheeters, C., & Wyvill, B. (1986). Data structure for soft objects. The Visual Computer, 2(4),
    227–234.
"""
from __future__ import annotations

import numpy as np
from scipy import ndimage

from natscene.volume.noise import fbm, worley_f1

__all__ = ["THRESHOLD", "metaball_field", "generate_smooth"]

THRESHOLD = 0.3  # iso-value of the implicit surface (a lone blob reaches it at 0.57 of its radius)


def _smoothstep(e0, e1, x):
    t = np.clip((x - e0) / (e1 - e0), 0.0, 1.0)
    return t * t * (3 - 2 * t)


def cumulus_blobs(rng: np.random.Generator, ext: np.ndarray, n: int) -> list[tuple]:
    """Metaballs (centre (x, y, z), radii (rx, ry, rz), weight) of a cumulus heap in a box of extent ``ext``."""
    ex, ey, ez = ext
    blobs = []
    # A flat box (e.g. 402 x 66 x 402) holds a field of heaps rather than one: more, wider-spread base blobs.
    flat = ey < 0.35 * min(ex, ez)
    n_base = max(1, n // 2 if flat else n // 4)
    spread = 0.42 if flat else 0.28
    base_y = 0.22 * ey
    for _ in range(n_base):
        a = rng.uniform(0, 2 * np.pi)
        d = np.sqrt(rng.uniform(0, 1))
        r = rng.uniform(0.19, 0.26) * min(ex, ez) * (0.5 if flat else 1.0)
        c = (0.5 * ex + spread * ex * d * np.cos(a), base_y + rng.uniform(-0.03, 0.03) * ey,
             0.5 * ez + spread * ez * d * np.sin(a))
        blobs.append((np.array(c), np.array([r, min(0.75 * r, 0.3 * ey), r]), 1.0))
    while len(blobs) < n:
        parent = blobs[rng.integers(len(blobs))]
        pc, pr, _ = parent
        r = pr[0] * rng.uniform(0.65, 0.88)
        if r < 0.05 * min(ex, ez):
            continue
        direction = rng.normal(size=3)
        direction[1] = abs(direction[1]) * 1.6 + 0.3          # mostly upward
        direction /= np.linalg.norm(direction)
        c = pc + direction * pr[0] * rng.uniform(0.55, 0.85)
        ry = min(0.85 * r, 0.3 * ey)
        c = np.clip(c, [r, ry + 0.1 * ey, r], [ex - r, max(ey - ry, ry + 0.1 * ey), ez - r])
        blobs.append((c, np.array([r, ry, r]), 1.0))
    return blobs


def cumulonimbus_blobs(rng: np.random.Generator, ext: np.ndarray, n: int) -> list[tuple]:
    """Metaballs of a cumulonimbus: broad base, tall tower with side turrets, flat anvil spreading downwind (+x)."""
    ex, ey, ez = ext
    w = min(ex, ez)
    blobs = []
    cx, cz = 0.42 * ex, 0.5 * ez
    n_tower = max(3, n // 3)
    for i in range(n_tower):                                   # tower core, narrowing a little with height
        y = (0.12 + 0.66 * i / max(n_tower - 1, 1)) * ey
        r = max(w, 0.45 * ey) * (0.2 - 0.05 * i / n_tower) * rng.uniform(0.9, 1.1)
        c = (cx + rng.normal(0, 0.02) * ex, y, cz + rng.normal(0, 0.02) * ez)
        blobs.append((np.array(c), np.array([r, 0.8 * r, r]), 1.0))
    n_base = max(2, n // 6)
    for _ in range(n_base):                                    # broad flat base
        a = rng.uniform(0, 2 * np.pi)
        r = w * rng.uniform(0.14, 0.19)
        c = (cx + 0.24 * ex * np.cos(a) * rng.uniform(0.3, 1), 0.1 * ey, cz + 0.22 * ez * np.sin(a) * rng.uniform(0.3, 1))
        blobs.append((np.array(c), np.array([r, 0.5 * r, r]), 1.0))
    n_anvil = max(3, n // 4)
    for _ in range(n_anvil):                                   # anvil: wide, thin, biased downwind
        u = rng.uniform(-0.35, 1.0)
        c = (cx + u * 0.4 * ex, ey * rng.uniform(0.8, 0.88), cz + rng.normal(0, 0.14) * ez)
        r = w * rng.uniform(0.2, 0.28)
        blobs.append((np.array(c), np.array([r * 1.3, 0.1 * ey, r * 1.15]), 1.0))
    while len(blobs) < n:                                      # turrets on the tower's flanks
        i = rng.integers(n_tower)
        pc, pr, _ = blobs[i]
        r = pr[0] * rng.uniform(0.5, 0.75)
        a = rng.uniform(0, 2 * np.pi)
        c = pc + np.array([np.cos(a) * pr[0] * 0.9, rng.uniform(-0.2, 0.5) * pr[1], np.sin(a) * pr[0] * 0.9])
        blobs.append((c, np.array([r, 0.85 * r, r]), 0.9))
    out = []
    for c, radii, wgt in blobs:                                # keep every blob inside the box
        c = np.clip(c, radii + 1e-3, ext - radii - 1e-3)
        out.append((c, radii, wgt))
    return out


def metaball_field(shape, ext: np.ndarray, blobs) -> np.ndarray:
    """Sum of Wyvill falloffs ``w (1 - r^2)^3`` on a grid ``shape`` = (nz, ny, nx) spanning ``ext`` = (ex, ey, ez)."""
    nz, ny, nx = shape
    vox = ext / np.array([nx, ny, nz])
    axes = [(np.arange(n) + 0.5) * v for n, v in zip((nx, ny, nz), vox)]
    field = np.zeros(shape, np.float32)
    for c, radii, w in blobs:
        lo = np.maximum(np.floor((c - radii) / vox).astype(int), 0)
        hi = np.minimum(np.ceil((c + radii) / vox).astype(int) + 1, [nx, ny, nz])
        if np.any(hi <= lo):
            continue
        dx = ((axes[0][lo[0]:hi[0]] - c[0]) / radii[0]) ** 2
        dy = ((axes[1][lo[1]:hi[1]] - c[1]) / radii[1]) ** 2
        dz = ((axes[2][lo[2]:hi[2]] - c[2]) / radii[2]) ** 2
        r2 = dz[:, None, None] + dy[None, :, None] + dx[None, None, :]
        field[lo[2]:hi[2], lo[1]:hi[1], lo[0]:hi[0]] += (w * np.clip(1 - r2, 0, None) ** 3).astype(np.float32)
    return field


def generate_smooth(kind: str, resolution, seed: int = 1, blobs: int = 40, octaves: int = 5, lacunarity: float = 2.0,
             gain: float = 0.5, base_frequency: float = 4.0, warp: float = 0.06, billow: float = 0.35,
             worley_cells: float = 10.0, detail: float = 0.25, softness: float = 0.12) -> np.ndarray:
    """A procedural cloud density grid float32 [nz, ny, nx] in [0, 1] (``kind``: cumulus | cumulonimbus).

    ``resolution`` is (nx, ny, nz) with y up; the grid spans a box whose longest side is 1.
    """
    nx, ny, nz = (int(v) for v in resolution)
    shape = (nz, ny, nx)
    ext = np.array([nx, ny, nz], np.float64) / max(nx, ny, nz)            # (ex, ey, ez)
    ext_zyx = ext[::-1]
    rng = np.random.default_rng(seed)
    if kind == "cumulus":
        balls = cumulus_blobs(rng, ext, blobs)
    elif kind == "cumulonimbus":
        balls = cumulonimbus_blobs(rng, ext, blobs)
    else:
        raise ValueError(f"unknown procedural cloud kind {kind!r} (cumulus | cumulonimbus)")
    field = metaball_field(shape, ext, balls)

    # 2. domain warp by a vector fBm (coarse octaves only: the warp is a large-scale distortion)
    if warp > 0:
        warp_oct = max(1, min(3, octaves))
        disp = [fbm(shape, ext_zyx, base_frequency, warp_oct, lacunarity, gain, rng) for _ in range(3)]
        vox = ext_zyx / np.array(shape)
        coords = np.indices(shape, dtype=np.float32)
        for a in range(3):
            coords[a] += disp[a] * np.float32(warp / vox[a])
        field = ndimage.map_coordinates(field, coords, order=1, mode="nearest").reshape(shape)
        del coords, disp

    # 3. billows (two Worley octaves: bumps where feature points are) and fBm detail
    w1 = worley_f1(shape, ext_zyx, worley_cells, rng)
    w2 = worley_f1(shape, ext_zyx, 2 * worley_cells, rng)
    bumps = (1.0 - np.clip(w1, 0, 1)) * 0.65 + (1.0 - np.clip(w2, 0, 1)) * 0.35 - 0.5
    turb = fbm(shape, ext_zyx, 2 * base_frequency, octaves, lacunarity, gain, rng)
    v = field - THRESHOLD + np.float32(billow * 0.5) * bumps + np.float32(detail * 0.5) * turb

    # 4. soft edge and flat base
    y = (np.arange(ny) + 0.5) / ny * ext[1]
    base_y = min(blob[0][1] - blob[1][1] * 0.5 for blob in balls)
    base = _smoothstep(base_y, base_y + 0.04 * ext[1], y).astype(np.float32)
    density = _smoothstep(0.0, softness, v).astype(np.float32) * base[None, :, None]
    # the interior is not uniform either: fBm modulates the dense core a little
    density *= np.float32(1.0) - np.float32(0.3 * detail) * (turb + 1)
    return np.clip(density, 0.0, 1.0).astype(np.float32)
