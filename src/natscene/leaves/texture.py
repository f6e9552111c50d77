"""
Leaf textures
=============

Defines the leaf textures of Dong (2007, §4.3.3, Fig. 4.6): "a basic map containing spatial variance information
such as the venation pattern is used to improve the final results".

-   :func:`leaf_texture`: the RGBA texture of a leaf for one date's concentrations.
-   :func:`maple_mask`, :func:`maple_venation`: the procedural maple outline and its primary veins.
-   :func:`base_map`: the colouring-order map and the luminance detail map.

Leaf shape: a procedural palmate (maple-like) outline, in polar coordinates around the petiole,
r(phi) = R * (base + (1 - base) * |cos(lobes * phi / 2)|^sharp), clipped to the upper half-plane
sector; five primary veins run from the petiole to the lobe tips (venation_from_nodes).
Base map m(x) in [0, 1]: how far each cell is along the colouring sequence: veins keep their
chlorophyll longest (the interveinal tissue and the margin colour first), plus smooth random variation
(seeded Gaussian-filtered noise). Per-cell pigments: c_ch(x) = c_ch * (1 - spread * (m(x) - 0.5)),
c_an(x) = c_an * (1 + spread * (m(x) - 0.5)). Colours come from PROSPECT-D (leaves.optics) evaluated
on a few levels of m and interpolated (vectorised), times a detail map (vein shading).

References
----------
-   Dong, W. (2007). Rendering Algorithms for Natural Scenes. PhD thesis, Université Henri Poincaré - Nancy I.
"""
from __future__ import annotations

import numpy as np
from scipy import ndimage

from natscene.leaves.optics import leaf_rgb
from natscene.patterns.venation import Venation, venation_from_nodes

__all__ = ["maple_mask", "maple_venation", "base_map", "leaf_texture"]


def maple_mask(size: int, lobes: int = 5, base: float = 0.45, sharp: float = 0.6) -> np.ndarray:
    yy, xx = np.mgrid[0:size, 0:size].astype(float)
    cx, cy = (size - 1) / 2, size * 0.78
    dx, dy = xx - cx, cy - yy
    r = np.hypot(dx, dy)
    phi = np.arctan2(dx, dy)  # 0 = up
    R = size * 0.5
    span = np.radians(120)
    s = np.clip(phi / span, -1, 1) * np.pi / 2  # lobes across +-120 deg
    outline = R * (base + (1 - base) * np.abs(np.cos(lobes * s / 2.0 * 2 / 2)) ** sharp)
    outline *= np.where(np.abs(phi) <= span, 1.0, 0.0)
    m = (r <= outline)
    stem = (np.abs(dx) <= max(1, size // 80)) & (yy >= cy) & (yy <= min(size - 1, cy + size * 0.2))
    return (m | stem).astype(np.float32)


def maple_venation(size: int, lobes: int = 5, vein_px: float = 2.0) -> Venation:
    root = (0.5, 0.78)
    nodes = []
    for k in range(lobes):
        a = np.radians(-120 + 240 * (k + 0.5) / lobes) * 0.8
        tip = (root[0] + 0.55 * np.sin(a), root[1] - 0.55 * np.cos(a))
        nodes.append({"xy": [float(tip[0]), float(tip[1])], "width": 0.3, "parent": -1})
    return venation_from_nodes((size, size), {"root": list(root), "root_width": 1.0, "nodes": nodes}, vein_px)


def base_map(mask: np.ndarray, venation: Venation, seed: int = 0, noise_sigma: float = 6.0) -> tuple:
    """(m, detail): colouring-order map in [0, 1] and a luminance detail map (veins lighter)."""
    inside = mask > 0.5
    edge = ndimage.distance_transform_edt(inside)
    vein_d = ndimage.distance_transform_edt(~venation.vascular)
    edge_n = 1.0 - np.clip(edge / max(edge.max(), 1.0), 0, 1)  # 1 at the margin
    vein_n = np.clip(vein_d / 8.0, 0, 1)                        # 0 on veins
    rng = np.random.default_rng(seed)
    noise = ndimage.gaussian_filter(rng.standard_normal(mask.shape), noise_sigma)
    noise = noise / (np.abs(noise).max() + 1e-9)
    m = np.clip(0.45 * edge_n + 0.35 * vein_n + 0.2 * (0.5 + 0.5 * noise), 0, 1)
    detail = 1.0 + 0.25 * np.exp(-vein_d ** 2 / 2.0) + 0.05 * noise
    return np.where(inside, m, 0).astype(np.float32), detail.astype(np.float32)


def leaf_texture(c_ch: float, c_ca: float, c_an: float, mask: np.ndarray, m: np.ndarray, detail: np.ndarray,
                 spread: float = 0.8, levels: int = 9, optics: dict | None = None) -> np.ndarray:
    """RGBA (H, W, 4) linear leaf texture for one date's concentrations; alpha = leaf mask."""
    optics = optics or {}
    ms = np.linspace(0, 1, levels)
    cols = np.array([leaf_rgb(max(c_ch * (1 - spread * (v - 0.5)), 0.0), c_ca,
                              max(c_an * (1 + spread * (v - 0.5)), 0.0), **optics) for v in ms])
    pos = m * (levels - 1)
    i0 = np.clip(np.floor(pos).astype(int), 0, levels - 2)
    f = (pos - i0)[..., None]
    rgb = (cols[i0] * (1 - f) + cols[i0 + 1] * f) * detail[..., None]
    a = (mask > 0.5).astype(np.float32)
    return np.concatenate([rgb * a[..., None], a[..., None]], axis=-1).astype(np.float32)
