"""
Coarse cloud shapes
===================

Defines the coarse cloud shapes of the production modeller (:mod:`natscene.volume.procedural`), on a coarse grid:

-   :func:`cumulus`, :func:`cumulonimbus`, :func:`field` (``cumulus_field``), :func:`stratocumulus`: the
    builders, each returning a :class:`Coarse`.

Each builder returns a :class:`Coarse`: the inside/outside of the low-frequency body, and three per-voxel factors
the fine kernel reads, ``amp`` (scales the pyroclastic displacement: billowy turrets 1, a smooth anvil less, a
small heap of a field in proportion to its size, a thin deck in proportion to its depth), ``edge`` (scales the
width of the density ramp) and ``erosion`` (scales the edge erosion), plus the height of the flat base and,
for an anvil, a ceiling. All lengths are box units (the longest side of the box is 1), arrays are
``[z, y, x]`` on the coarse grid of voxel size ``cvox`` (x, y, z).

- ``cumulus``: a core on a flat base and turrets of several heights rising from it, carrying turrets that carry
  turrets (:func:`heap_blobs`): a cauliflower heap.
- ``cumulonimbus``: the classic incus (WMO *International Cloud Atlas*, Cumulonimbus capillatus incus): a
  narrow, slightly leaning cauliflower tower of rising thermal bubbles on a broad flat base, an overshooting
  dome on its top, a flanking line of smaller towers stepping down on the upwind side, and at the top a flat,
  wide anvil (the tropopause) spreading downwind (+x) in a widening fan, thick near the tower and thinning
  toward its overhanging edges; the anvil is smoother than the tower (``amp`` 0.15 at its top near the tower,
  up to ~0.8 underneath and at its far edges, where its erosion grows too: ragged, fibrous edges).
- ``cumulus_field``: fair-weather cumulus (humilis / mediocris) with one flat base (the lifting condensation
  level), the heaps' diameters drawn from the power law N(D) ~ D^-2 observed for cumulus fields (Plank 1969;
  Benner & Curry 1998) between ``d_min`` and ``d_max`` (``heap_min``, ``heap_max``), heights 0.4-0.9 of the diameter, placed without
  overlap until the covered share of the floor reaches ``coverage``; each heap's displacement and edge scale
  with its diameter, so small heaps keep their shape.
- ``stratocumulus``: a layer broken into closed convective cells (Rayleigh-Benard-like; Agee 1984): a 2-D
  Worley F2 - F1 field is high in the cells and low on the lanes between them; cloud where it is above the
  ``1 - coverage`` quantile, the top domed in each cell's middle, each cell a little thicker or thinner.

References
----------
-   Agee, E. M. (1984). Observations from space and thermal convection: a historical perspective. Bulletin of
    the American Meteorological Society, 65(9), 938–949.
-   Benner, T. C., & Curry, J. A. (1998). Characteristics of small tropical cumulus clouds and their impact on
    the environment. Journal of Geophysical Research, 103(D22), 28753–28767.
-   Plank, V. G. (1969). The size distribution of cumulus clouds in representative Florida populations. Journal
    of Applied Meteorology, 8(1), 46–67.
-   World Meteorological Organization. International Cloud Atlas. https://cloudatlas.wmo.int
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import ndimage

from natscene.volume import metaballs

__all__ = ["Coarse", "cumulus", "cumulonimbus", "field", "stratocumulus"]

THRESHOLD = metaballs.THRESHOLD


@dataclass
class Coarse:
    """A coarse body: occupancy [z, y, x] (bool); displacement, edge-ramp and erosion factors [z, y, x] (read on
    the body; :func:`natscene.volume.procedural.extend_factors` carries each outside voxel the value of the
    nearest body voxel); flat-base height."""

    occ: np.ndarray
    amp: np.ndarray
    edge: np.ndarray
    erosion: np.ndarray
    base_y: float
    ceiling: float = np.inf     # density fades out above this height where the displacement is damped (anvil)


def _axes(shape, cvox):
    nz, ny, nx = shape
    return ((np.arange(nx) + 0.5) * cvox[0], (np.arange(ny) + 0.5) * cvox[1], (np.arange(nz) + 0.5) * cvox[2])


def _ones(shape):
    return np.ones(shape, np.float32)


def cumulus(rng, shape, cvox, ext, margin, blobs: int) -> Coarse:
    """One cumulus heap (:func:`heap_blobs`, ``blobs`` / 4 turrets of three generations) filling ~70 % of the
    box's width and most of its height, its flat base near the floor."""
    ex, ey, ez = ext
    base_y = margin + 0.03 * ey
    d = 0.6 * (min(ex, ez) - 2 * margin)
    h = 0.92 * (ey - margin - base_y)
    balls = heap_blobs(rng, 0.5 * ex - 0.05 * d, 0.5 * ez, d, h, base_y, max(4, blobs // 4), levels=3)
    occ = metaballs.metaball_field(shape, ext, balls) > THRESHOLD
    return Coarse(occ, _ones(shape), _ones(shape), _ones(shape), float(base_y))


# ------------------------------------------------------------------------------------------ cumulonimbus
def _tower(rng, axis_x, axis_z, y0, y1, radius, lean, n, grow=1.0):
    """Metaball bubbles of a convective tower from y0 to y1: the bubbles' heights are random (no regular
    stacking, which would band the tower, but one per height stratum, so no gap opens), their radii such that the tower's width is about 2 ``radius``, their centres jittered
    around an axis that leans downwind by ``lean`` over the height; the top bubble caps the tower."""
    out = []
    radius = radius / 0.57                    # a lone metaball reaches the iso-surface at 0.57 of its radius
    lo, hi = y0 + 0.2 * radius, y1 - 0.6 * radius
    ys = lo + (np.arange(n) + rng.uniform(0.15, 0.85, n)) / n * (hi - lo)     # stratified: no gaps, no rows
    for y in ys:
        f = (y - y0) / max(y1 - y0, 1e-9)
        r = radius * rng.uniform(0.55, 0.75) * (grow + (1 - grow) * f)
        a = rng.uniform(0, 2 * np.pi)
        j = rng.uniform(0.0, 0.35) * radius
        c = np.array([axis_x + lean * f + j * np.cos(a), y, axis_z + j * np.sin(a)])
        out.append((c, np.array([r, 0.9 * r, r]), 1.0))
    # the cap and the turrets around it (the cauliflower top of the tower)
    top = np.array([axis_x + lean, y1 - 0.55 * radius, axis_z])
    out.append((top, np.array([0.8, 0.7, 0.8]) * radius, 1.0))
    for _ in range(max(2, n // 3)):
        a = rng.uniform(0, 2 * np.pi)
        r = radius * rng.uniform(0.35, 0.55)
        c = top + np.array([0.55 * radius * np.cos(a), rng.uniform(-0.4, 0.25) * radius, 0.55 * radius * np.sin(a)])
        out.append((c, np.array([r, 0.9 * r, r]), 1.0))
    return out


def cumulonimbus(rng, shape, cvox, ext, margin, blobs: int) -> Coarse:
    """Tower + overshooting top + flanking line + anvil (see the module docstring)."""
    ex, ey, ez = ext
    x0, x1, y0, y1, z0, z1 = margin, ex - margin, margin, ey - margin, margin, ez - margin
    W, H, zc = x1 - x0, y1 - y0, 0.5 * ez
    R = 0.11 * min(W, z1 - z0)                                         # tower radius
    xc = x0 + 0.3 * W + rng.uniform(-0.03, 0.03) * W                 # the tower stands upwind
    top = y0 + 0.97 * H                                               # the anvil's flat top (tropopause)
    a_thick = (0.3 + rng.uniform(-0.03, 0.03)) * H                   # anvil thickness at the tower
    lean = 0.04 * W
    n = max(8, blobs // 2)
    balls = _tower(rng, xc, zc, y0, top - 0.25 * a_thick, R, lean, n, grow=1.15)
    # broad base: wider bubbles along the bottom of the tower (the rain-free base)
    for _ in range(max(3, blobs // 10)):
        a = rng.uniform(0, 2 * np.pi)
        r = R * rng.uniform(0.8, 1.0)
        c = np.array([xc + 0.7 * R * np.cos(a), y0 + 0.3 * r, zc + 0.7 * R * np.sin(a)])
        balls.append((c, np.array([r, 0.5 * r, r]), 1.0))
    # overshooting top: a dome above the anvil over the tower
    balls.append((np.array([xc + lean, top - 0.15 * R, zc]), np.array([0.9, 0.55, 0.9]) * R, 1.0))
    # the neck: the tower's top spreads into the anvil (wide, flattened bubbles below the anvil's base)
    for _ in range(4):
        a = rng.uniform(0, 2 * np.pi)
        r = R * rng.uniform(0.9, 1.2)
        c = np.array([xc + lean + 0.6 * R * np.cos(a) + 0.4 * R, top - a_thick * rng.uniform(0.7, 1.0),
                      zc + 0.6 * R * np.sin(a)])
        balls.append((c, np.array([1.3 * r, 0.45 * r, 1.2 * r]), 0.9))
    # flanking line: smaller towers stepping down upwind (-x), a little off the axis
    xf, rf = xc - 1.0 * R, 0.65 * R
    for k, hf in enumerate((0.5, 0.32, 0.2)):
        xf -= 1.6 * rf
        if xf - rf < x0:
            break
        zf = zc + rng.uniform(-0.4, 0.4) * R
        balls += _tower(rng, xf, zf, y0, y0 + hf * H, rf, 0.2 * rf, max(3, n // (3 + 2 * k)))
        rf *= 0.8
    field = metaballs.metaball_field(shape, ext, balls)
    tower = field > THRESHOLD
    # anvil: between a flat top and a bottom that rises downwind, inside a fan widening downwind with a lobed
    # outline; it overhangs the tower upwind a little
    X, Y, Z = np.meshgrid(*_axes(shape, cvox), indexing="ij")           # [x, y, z]
    X, Y, Z = (a.transpose(2, 1, 0) for a in (X, Y, Z))                # [z, y, x]
    xu, xd = xc - 2.0 * R, x1 - 0.02 * W
    s = np.clip(np.where(X > xc, (X - xc) / (xd - xc), (xc - X) / (xc - xu)), 0, 1)  # 0 at the tower, 1 at an end
    thick = a_thick * (1 - 0.75 * s ** 0.8)           # thins outward: the underside rises toward the edges
    # lobes: a smooth random function of the angle around the tower, and of the downwind distance
    ang = np.arctan2(Z - zc, X - xc)
    lobes = sum(rng.uniform(0.03, 0.08) * np.cos(k * ang + rng.uniform(0, 2 * np.pi)) for k in (2, 3, 5))
    half = (1.7 * R + 0.55 * np.maximum(X - xc, 0)) * (1 + lobes)
    half = np.minimum(half, 0.5 * (z1 - z0))
    cap = np.sqrt(np.clip(1 - np.clip((s - 0.6) / 0.4, 0, 1) ** 2, 0, 1))    # rounded ends
    plan = (s < 1) & (np.abs(Z - zc) <= half * cap)
    anvil = plan & (Y <= top) & (Y >= top - thick)
    occ = tower | anvil
    # factors: a billowy tower (1); a smoother anvil, smoothest at its flat top over the tower (0.15),
    # lumpier underneath (the lumpy underside, mammatus) and toward its far edges, where the erosion also
    # grows (a closed sheet near the tower, ragged and fibrous at its edges); its edge ramp narrower
    only_anvil = anvil & ~tower
    depth = np.clip((top - Y) / np.maximum(thick, 1e-9), 0, 1)
    amp = np.where(only_anvil, 0.15 + 0.35 * depth + 0.3 * s, 1.0).astype(np.float32)
    edge = np.where(only_anvil, 0.6, 1.0).astype(np.float32)
    ero = np.where(only_anvil, 0.3 + 0.6 * s, 1.0).astype(np.float32)
    base_y = max(y0, margin)
    return Coarse(occ, amp, edge, ero, float(base_y), float(top))


# ---------------------------------------------------------------------------------------- cumulus field
def heap_blobs(rng, x, z, d, h, base_y, n, levels: int = 2, shear: float = 0.1):
    """Metaballs of one cumulus heap of footprint diameter ``d`` and height ``h`` on a flat base at ``base_y``:
    a core (an ellipsoid centred on the base, cut by it) and ``n`` turrets rising from it to heights of their
    own, the central ones tallest (a heap of towers, not one smooth dome), each carrying smaller turrets in
    turn (``levels`` generations, radii halving: the cauliflower's billows on billows); the turrets lean
    downwind (+x) by ``shear`` x their height. A lone metaball reaches the iso-surface at 0.57 of its radius,
    hence the 1/0.57 factors."""
    k = 1 / 0.57
    out = [(np.array([x, base_y, z]), np.array([0.3 * d, 0.35 * h, 0.3 * d]) * k, 1.0)]     # the core
    parents = []
    for _ in range(n):
        # a turret rising from the core to its own height, the central ones tallest (a congested heap of
        # towers of several heights, not one smooth dome)
        a = rng.uniform(0, 2 * np.pi)
        u = np.sqrt(rng.uniform(0, 1))                                  # 0: centre .. 1: the heap's rim
        rr = 0.33 * d * u
        r = rng.uniform(0.15, 0.26) * d
        top = h * (1 - 0.55 * u * u) * rng.uniform(0.6, 1.0)            # the turret's top
        yc = max(base_y + 0.57 * r * k * 0.6, base_y + top - 0.57 * r * k)
        c = np.array([x + rr * np.cos(a) + shear * (yc - base_y), yc, z + rr * np.sin(a)])
        out.append((c, np.array([r, 0.9 * r, r]) * k, 0.9))
        # a stem below it, down to the core
        if yc - base_y > 0.5 * h:
            stem = np.array([c[0] - 0.5 * shear * (yc - base_y), base_y + 0.5 * (yc - base_y), c[2]])
            out.append((stem, np.array([0.9 * r, 0.5 * (yc - base_y) / 0.57, 0.9 * r]) * np.array([k, 1, k]), 0.7))
        parents.append((c, r))
    for _ in range(levels - 1):
        children = []
        for c, r in parents:
            for _ in range(rng.integers(1, 4)):
                a = rng.uniform(0, 2 * np.pi)
                el = rng.uniform(0.3, 1.2)                           # elevation above the horizontal (rad)
                rc = 0.5 * r * rng.uniform(0.8, 1.2)
                cc = c + np.array([np.cos(a) * np.cos(el), np.sin(el), np.sin(a) * np.cos(el)]) * 0.85 * r
                if cc[1] + 0.57 * rc * k > base_y + h:
                    continue
                out.append((cc, np.array([rc, 0.85 * rc, rc]) * k, 0.7))
                children.append((cc, rc))
        parents = children
    return out


def field(rng, shape, cvox, ext, margin, blobs: int, coverage: float, d_min: float, d_max: float) -> Coarse:
    """Heaps of power-law diameters (box units) with a common flat base (see the module docstring)."""
    ex, ey, ez = ext
    base_y = margin + 0.04 * ey
    h_max = ey - margin - base_y
    area, covered = ex * ez, 0.0
    heaps = []                                        # (x, z, diameter)
    # diameters by inverse-CDF sampling of N(D) ~ D^-2 on [d_min, d_max]; largest first (they need room)
    ds = []
    while sum(np.pi * (d / 2) ** 2 for d in ds) < coverage * area and len(ds) < 4000:
        u = rng.uniform()
        ds.append(1.0 / (1.0 / d_min - u * (1.0 / d_min - 1.0 / d_max)))
    grid = {}
    cell = d_max
    for d in sorted(ds, reverse=True):
        for _ in range(30):
            x = rng.uniform(margin + d / 2, ex - margin - d / 2)
            z = rng.uniform(margin + d / 2, ez - margin - d / 2)
            gx, gz = int(x / cell), int(z / cell)
            near = [h for i in (-1, 0, 1) for k in (-1, 0, 1) for h in grid.get((gx + i, gz + k), ())]
            if all((x - hx) ** 2 + (z - hz) ** 2 >= (0.5 * (d + hd) * 0.92) ** 2 for hx, hz, hd in near):
                heaps.append((x, z, d))
                grid.setdefault((gx, gz), []).append((x, z, d))
                covered += np.pi * (d / 2) ** 2
                break
    balls = []
    for x, z, d in heaps:
        balls += heap_blobs(rng, x, z, d, min(h_max, d * rng.uniform(0.4, 0.9)), base_y, blobs,
                            levels=2 if d > 0.3 * d_max else 1)
    occ = metaballs.metaball_field(shape, ext, balls) > THRESHOLD
    # per-column size factor: each heap's diameter over the largest, spread over its footprint
    nz, ny, nx = shape
    xs, _, zs = _axes(shape, cvox)
    num, den = np.zeros((nz, nx), np.float32), np.full((nz, nx), 1e-6, np.float32)
    for x, z, d in heaps:
        k = np.exp(-((xs[None, :] - x) ** 2 + (zs[:, None] - z) ** 2) / (2 * (0.6 * d) ** 2)).astype(np.float32)
        num += k * np.float32(d / d_max)
        den += k
    size = np.clip(num / den, 0.2, 1.0)
    amp = np.broadcast_to(size[:, None, :], shape).astype(np.float32)
    return Coarse(occ, amp, amp.copy(), _ones(shape), float(base_y))


# ---------------------------------------------------------------------------------------- stratocumulus
def worley_2d(n_out, cells: int, rng) -> tuple[np.ndarray, np.ndarray]:
    """Periodic 2-D Worley noise on an (n_out[0], n_out[1]) grid with ``cells`` x ``cells`` jittered feature
    points: (F2 - F1 in cell units, index of the nearest feature point)."""
    pts = rng.uniform(0, 1, (cells, cells, 2))
    v = (np.arange(n_out[0]) + 0.5) / n_out[0] * cells
    u = (np.arange(n_out[1]) + 0.5) / n_out[1] * cells
    iv, iu = np.floor(v).astype(int), np.floor(u).astype(int)
    d2, ids = [], []
    for dv in (-1, 0, 1):
        for du in (-1, 0, 1):
            cv, cu = (iv + dv) % cells, (iu + du) % cells
            p = pts[cv[:, None], cu[None, :]]                               # (n0, n1, 2)
            ddv = iv[:, None] + dv + p[..., 0] - v[:, None]
            ddu = iu[None, :] + du + p[..., 1] - u[None, :]
            d2.append(ddv ** 2 + ddu ** 2)
            ids.append(cv[:, None] * cells + cu[None, :])
    d2, ids = np.stack(d2), np.stack(ids)
    order = np.argsort(d2, axis=0)
    f1 = np.sqrt(np.take_along_axis(d2, order[:1], 0)[0])
    f2 = np.sqrt(np.take_along_axis(d2, order[1:2], 0)[0])
    return f2 - f1, np.take_along_axis(ids, order[:1], 0)[0]


def stratocumulus(rng, shape, cvox, ext, margin, coverage: float, thickness: float, cells: float,
                  frequency: float, ramp: float, relief: float = 1.0) -> Coarse:
    """A layer broken into closed cells (see the module docstring). The displacement and the edge ramp are
    scaled to the layer's thickness: the first octave's amplitude is ``billow`` x 0.7 x the thickness (the
    factor ``0.7 thickness frequency`` on ``billow / frequency``, ``frequency`` the first octave's), and the
    ramp at most a third of it (``ramp``: its width, box units): a thin deck gets billows a fraction of its
    depth (its top textured, not torn apart). ``relief`` scales the thickness variation between and within the cells (1: the cells' domes and their
    depths vary by a factor ~3; 0: a flat-topped layer broken only by the lanes)."""
    nz, ny, nx = shape
    ncell = max(2, int(round(cells)))
    f, ids = worley_2d((nz, nx), ncell, rng)
    f = ndimage.gaussian_filter(f, 0.6, mode="wrap")
    thresh = np.quantile(f, 1 - coverage) if coverage < 1 else -np.inf
    inside = f > thresh
    hi = float(f.max())
    dome = np.clip((f - thresh) / max(hi - thresh, 1e-6), 0, 1) if np.isfinite(thresh) else f / max(hi, 1e-6)
    per_cell = rng.uniform(0.75, 1.25, ncell * ncell)[ids]                 # cells differ in depth
    _, ys, _ = _axes(shape, cvox)
    base_y = margin + 0.05 * (ext[1] - 2 * margin)
    thick = thickness * (ext[1] - 2 * margin)
    form = per_cell * (0.45 + 0.75 * np.sqrt(dome))                      # domed cells, mean ~1
    top = base_y + thick * np.maximum(1 + relief * (form - 1), 0.2)
    occ = (ys[None, :, None] >= base_y) & (ys[None, :, None] <= top[:, None, :]) & inside[:, None, :]
    amp = np.full(shape, 0.7 * thick * frequency, np.float32)             # first octave: billow x 0.7 x depth
    edge = np.full(shape, min(1.0, 0.35 * thick / max(ramp, 1e-9)), np.float32)
    return Coarse(occ, amp, edge, _ones(shape), float(base_y))
