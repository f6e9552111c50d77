"""
Maple leaves of the set
=======================

Defines the maple leaves for the set: a parametric palmate outline, the season colour map warped onto it, and the
curled leaf lying on the ground:

-   :class:`MapleOutline`: the outline's lobes and teeth.
-   :func:`warp_season_map`: a season map warped onto the outline; :func:`season_margin`, :func:`extend_colours`:
    its own margin and its colours continued past it (:data:`SEASON_ROOT`, :data:`SEASON_VEINS_DEG`,
    :data:`SEASON_VEIN_LENGTH`: where its veins are).
-   :func:`leaf_mesh`: a fallen leaf; :func:`leaf_cells`, :func:`drop_transparent_cells`, :func:`cell_keep`: the
    faces that hold any of the texture's alpha.

Outline (Acer saccharum / platanoides, five lobes): in polar coordinates (r, φ) around the petiole, φ = 0
toward the leaf tip, the margin is the smooth maximum (log-sum-exp, sharpness ``k``) of a small palm disc
and one pointed lobe per main lobe and per marginal tooth,

    r_k(φ) = L_k · max(0, 1 − |φ − φ_k| / w_k)^p_k,

then a fine serration ``r · (1 + s · tri(N φ))`` (tri: a triangle wave in [−1, 1]). Defaults: the central lobe
at 0° (length 0.46 of the image), two upper lobes at ±52° (0.43), two small lower lobes at ±112° (0.22),
each main lobe with two coarse teeth per side; sinuses between lobes reach about 40 % of the lobe length.

Colour: the season stage (``leaves/<leaf>/<case>/<date>.exr``, Dong 2007 Ch. 4) paints its five primary veins
from a root at (0.5, 0.78) of the image at ±38.4° and ±76.8° (:func:`natscene.leaves.texture.maple_venation`).
The map is warped in polar coordinates around that root so that its veins run to the new lobe tips
(piecewise-linear in φ between lobe and vein angles, radius scaled by vein length / lobe length), after its
colours were extended past its own outline by nearest-pixel fill; the outline's antialiased mask is the alpha.

References
----------
-   Dong, W. (2007). Rendering Algorithms for Natural Scenes. PhD thesis, Université Henri Poincaré - Nancy I.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import cv2
import numpy as np
from scipy import ndimage

from natscene.composite.mesh import TriMesh, grid_surface

__all__ = ["SEASON_ROOT", "SEASON_VEINS_DEG", "SEASON_VEIN_LENGTH", "MapleOutline", "extend_colours",
           "warp_season_map", "season_margin", "leaf_mesh", "leaf_cells", "drop_transparent_cells", "cell_keep"]

#: root (petiole attachment) of the season map, (x, y) normalised, y down; its vein angles (deg) and length
SEASON_ROOT = (0.5, 0.78)
SEASON_VEINS_DEG = (-76.8, -38.4, 0.0, 38.4, 76.8)
SEASON_VEIN_LENGTH = 0.55


@dataclass
class MapleOutline:
    """Lobes (angle deg, length as a fraction of the image side, half-width deg); teeth per lobe side."""

    lobes: list = field(default_factory=lambda: [(0.0, 0.46, 37.0), (-54.0, 0.43, 34.0), (54.0, 0.43, 34.0),
                                                 (-112.0, 0.24, 30.0), (112.0, 0.24, 30.0)])
    palm: float = 0.12
    lobe_power: float = 0.55
    teeth_per_side: int = 2
    tooth_length: float = 0.07  # how far a tooth tip stands out of the lobe (fraction of the lobe length)
    tooth_width: float = 0.45  # tooth half-width / the lobe's half-width
    serration: float = 0.012
    serration_count: int = 110
    sharpness: float = 60.0
    root: tuple = (0.5, 0.66)
    petiole: float = 0.22  # length of the petiole below the root
    petiole_width: float = 0.012

    def radius(self, phi: np.ndarray) -> np.ndarray:
        """Margin radius (fraction of the image side) toward angles ``phi`` (radians, 0 = tip, wrap-around)."""
        phi = np.asarray(phi, np.float64)
        terms = [np.full_like(phi, self.palm)]
        for ang, L, w in self.lobes:
            a, wr = np.radians(ang), np.radians(w)
            terms.append(self._lobe(phi, a, L, wr, self.lobe_power))
            # coarse teeth on both sides of the lobe, tips tooth_length * L outside its envelope
            for j in range(1, self.teeth_per_side + 1):
                for side in (-1, 1):
                    ta = a + side * wr * (0.25 + 0.5 * j / (self.teeth_per_side + 1))
                    env = L * max(0.0, 1 - abs(ta - a) / wr) ** self.lobe_power
                    terms.append(self._lobe(phi, ta, env + self.tooth_length * L,
                                            wr * self.tooth_width, 1.0))
        T = np.stack(terms)
        k = self.sharpness / max(self.palm, 1e-3)
        m = T.max(0)
        r = m + np.log(np.exp(k * (T - m)).sum(0)) / k  # smooth maximum: rounded sinuses
        tri = 2 * np.abs((self.serration_count * phi / (2 * np.pi)) % 1.0 - 0.5) * 2 - 1
        return r * (1 + self.serration * tri)

    @staticmethod
    def _lobe(phi, a, L, w, p):
        d = np.abs((phi - a + np.pi) % (2 * np.pi) - np.pi)
        return L * np.clip(1 - d / w, 0, None) ** p

    def mask(self, size: int) -> np.ndarray:
        """Antialiased alpha (size, size) of the leaf blade and petiole (the root at ``root``, tip up)."""
        yy, xx = (np.mgrid[0:size, 0:size] + 0.5) / size
        dx, dy = xx - self.root[0], self.root[1] - yy
        rho = np.hypot(dx, dy)
        phi = np.arctan2(dx, dy)
        r = self.radius(phi)
        blade = np.clip((r - rho) * size + 0.5, 0, 1)
        pet = np.clip((self.petiole_width / 2 - np.abs(dx)) * size + 0.5, 0, 1) * \
            ((yy >= self.root[1]) & (yy <= self.root[1] + self.petiole))
        return np.maximum(blade, pet).astype(np.float32)


def extend_colours(rgb: np.ndarray, alpha: np.ndarray) -> np.ndarray:
    """Colours of ``rgb`` continued past its alpha > 0.5 region by the nearest inside pixel."""
    inside = alpha > 0.5
    if not inside.any():
        return rgb.copy()
    idx = ndimage.distance_transform_edt(~inside, return_distances=False, return_indices=True)
    return rgb[idx[0], idx[1]]


def warp_season_map(season_rgba: np.ndarray, outline: MapleOutline, size: int) -> np.ndarray:
    """RGBA (size, size, 4) maple leaf: the season map's colours warped so that its veins follow the
    outline's lobes, alpha = the outline's mask. Colour is premultiplied by nothing (albedo, alpha separate)."""
    src = np.asarray(season_rgba, np.float32)
    a_src = src[..., 3] if src.shape[-1] >= 4 else np.ones(src.shape[:2], np.float32)
    # the season texture stores rgb * alpha: un-premultiply inside, extend outside
    rgb = src[..., :3] / np.maximum(a_src[..., None], 1e-6)
    rgb = extend_colours(np.where(a_src[..., None] > 0.5, rgb, 0), a_src)
    hs, ws = rgb.shape[:2]
    # polar coordinates of the output pixels around the new root
    yy, xx = (np.mgrid[0:size, 0:size] + 0.5) / size
    dx, dy = xx - outline.root[0], outline.root[1] - yy
    rho = np.hypot(dx, dy)
    phi = np.degrees(np.arctan2(dx, dy))
    lobes = sorted(outline.lobes)
    # vein angle for every lobe angle: the nearest of the season map's veins to 0.74 x the lobe angle (the
    # upper lobes take the inner veins, the lower lobes the outer ones)
    ang_l = [l[0] for l in lobes]
    ang_v = [SEASON_VEINS_DEG[int(np.argmin([abs(v - np.clip(a * 0.74, -76.8, 76.8)) for v in SEASON_VEINS_DEG]))]
             for a in ang_l]
    phi_v = np.interp(phi, [-180.0] + ang_l + [180.0], [-180.0] + ang_v + [180.0])
    # radius: the new margin onto the season map's own margin (its margin band colours first, Dong §4.3.3)
    r_v = rho * season_margin(a_src, phi_v) / np.maximum(outline.radius(np.radians(phi)), 1e-3)
    sx = SEASON_ROOT[0] + r_v * np.sin(np.radians(phi_v))
    sy = SEASON_ROOT[1] - r_v * np.cos(np.radians(phi_v))
    # the petiole keeps its straight line below the root
    below = (yy > outline.root[1]) & (np.abs(dx) < 2 * outline.petiole_width)
    sx = np.where(below, SEASON_ROOT[0] + dx, sx)
    sy = np.where(below, SEASON_ROOT[1] + (yy - outline.root[1]), sy)
    out = cv2.remap(rgb, (sx * ws - 0.5).astype(np.float32), (sy * hs - 0.5).astype(np.float32),
                    cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
    return np.concatenate([out, outline.mask(size)[..., None]], -1).astype(np.float32)


def season_margin(alpha: np.ndarray, phi_deg: np.ndarray, n_angles: int = 720, n_steps: int = 400) -> np.ndarray:
    """Radius (fraction of the image side) of the season map's own blade margin around ``SEASON_ROOT`` toward
    angles ``phi_deg`` (0 = up): the farthest alpha > 0.5 sample along each of ``n_angles`` rays, interpolated."""
    h, w = alpha.shape
    ang = np.linspace(-180.0, 180.0, n_angles + 1)
    r = np.linspace(0.0, 0.75, n_steps)
    A, R = np.meshgrid(np.radians(ang), r, indexing="ij")
    x = np.clip(((SEASON_ROOT[0] + R * np.sin(A)) * w).astype(int), 0, w - 1)
    y = np.clip(((SEASON_ROOT[1] - R * np.cos(A)) * h).astype(int), 0, h - 1)
    inside = alpha[y, x] > 0.5
    last = np.where(inside.any(1), n_steps - 1 - np.argmax(inside[:, ::-1], 1), 0)
    rm = np.maximum(r[last], 2.0 / max(h, w))
    return np.interp(phi_deg, ang, rm)


def leaf_mesh(texture_alpha: np.ndarray, length: float, curl: float = 0.25, cup: float = 0.12,
              n: int = 14) -> TriMesh:
    """A fallen leaf over its texture square (side ``length`` metres, tip toward +z, root at the origin of
    the leaf's frame), lying on y = 0 with its margin curled up: height ``curl`` · length · (r/R)² toward the
    lobe tips and a ``cup`` across the midrib. Cells whose texels are all transparent are dropped
    (``texture_alpha``: the alpha (h, w), or a precomputed (F,) face mask of :func:`cell_keep`)."""
    uu, vv = np.meshgrid(np.linspace(0, 1, n), np.linspace(0, 1, n))
    x = (uu - 0.5) * length
    z = (vv - (1 - MapleOutline().root[1])) * length
    r = np.hypot(x, z) / (0.5 * length)
    y = length * (curl * r ** 2 + cup * (x / (0.5 * length)) ** 2) * 0.5
    y -= y.min()
    m = grid_surface(np.stack([x, y, z], -1), np.stack([uu, vv], -1))
    return m.keep_faces(texture_alpha if texture_alpha.ndim == 1 else cell_keep(m, texture_alpha))


def leaf_cells(alpha: np.ndarray, n: int = 14) -> np.ndarray:
    """The face mask of :func:`leaf_mesh`'s n x n grid that keeps the cells holding any of ``alpha`` (the same
    for every leaf cut from one texture: compute it once, pass it as ``texture_alpha``)."""
    full = leaf_mesh(np.ones((1,), bool).repeat(2 * (n - 1) ** 2), 1.0, 0.0, 0.0, n)
    return cell_keep(full, alpha)


def drop_transparent_cells(m: TriMesh, alpha: np.ndarray, threshold: float = 0.02) -> TriMesh:
    """Remove faces whose texture-space bounding box holds no alpha above ``threshold`` (the alpha test still
    cuts the exact outline; this only spares the ray caster empty triangles)."""
    return m.keep_faces(cell_keep(m, alpha, threshold))


def cell_keep(m: TriMesh, alpha: np.ndarray, threshold: float = 0.02) -> np.ndarray:
    """(F,) whether each face's texture-space bounding box holds alpha above ``threshold``."""
    h, w = alpha.shape[:2]
    a = (np.asarray(alpha).reshape(h, w) > threshold).astype(np.int64)
    S = np.pad(a.cumsum(0).cumsum(1), ((1, 0), (1, 0)))  # summed-area table
    uv = m.uv[m.faces]  # (F, 3, 2)
    lo, hi = uv.min(1), uv.max(1)
    x0 = np.clip(np.floor(lo[:, 0] * w).astype(int) - 1, 0, w)
    x1 = np.clip(np.ceil(hi[:, 0] * w).astype(int) + 1, 0, w)
    y0 = np.clip(np.floor((1 - hi[:, 1]) * h).astype(int) - 1, 0, h)
    y1 = np.clip(np.ceil((1 - lo[:, 1]) * h).astype(int) + 1, 0, h)
    count = S[y1, x1] - S[y0, x1] - S[y1, x0] + S[y0, x0]
    return count > 0
