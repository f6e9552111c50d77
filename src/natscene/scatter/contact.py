"""Contact sheet of the precomputed tables (Dobashi 2012 §4.3) for a person to look at.

Rows: S_sun, S_amb, T at three extinction nodes; then, for ``transport: dobashi``, one row per order k of
E_m^(k) at the middle node for three g values, and for ``all_orders`` one row of the sun's multiple scattering
(every order >= 2 at beta = 0.99) and one of the skylight (the dome's R, G, B at beta = 0.99, in colour). Every tile is tone-mapped on its own (auto exposure, :func:`natscene.io.to_srgb8`) and
labelled, so the tile shows the pattern, not the absolute level.
"""
from __future__ import annotations

import numpy as np

from natscene.io import to_srgb8
from natscene.preview import label


def _nearest(grid, x) -> int:
    return int(np.argmin(np.abs(np.asarray(grid) - x)))


def contact_sheet(tables, gs=(0.0, 0.5, 0.9)) -> np.ndarray:
    """uint8 (rows*H, 3*W, 3) sheet: S_sun, S_amb and T at the quarter, middle and last of the extinction
    nodes above 0, then the multiple scattering at the middle node for the g nearest ``gs``."""
    H, W = tables.t_c.shape
    nodes = np.flatnonzero(np.asarray(tables.extinction) > 0)
    if nodes.size == 0:
        nodes = np.arange(len(tables.extinction))
    picks = [int(nodes[len(nodes) // 4]), int(nodes[len(nodes) // 2]), int(nodes[-1])]
    rows = []
    for name, arr in (("S_sun", tables.s_sun), ("S_amb", tables.s_amb), ("T", tables.transmittance)):
        tiles = []
        for i in picks:
            exp = 1.0 if name == "T" else "auto"
            tiles.append(label(to_srgb8(arr[i], exp), f"{name} e={tables.extinction[i]:g}/m", "table"))
        rows.append(np.concatenate(tiles, axis=1))
    si = picks[1]
    if getattr(tables, "transport", "dobashi") == "all_orders":
        from natscene.scatter.bands import band_weights
        for name in ("sun", "sky"):
            tiles = []
            for g in gs:
                gi = _nearest(tables.g, g)
                if name == "sun":
                    w = band_weights(tables.sun_bands, tables.sun_ratios[gi, si], 0.99)[0]
                    img = np.tensordot(w, tables.sun_ms[:, gi, si], 1)
                else:
                    w = band_weights(tables.sky_bands, tables.sky_ratios[gi, si], 0.99)[0]
                    img = np.moveaxis(np.tensordot(w, tables.sky_ms[:3, :, gi, si], (0, 1)), 0, -1)
                tiles.append(label(to_srgb8(img), f"{name} all orders g={tables.g[gi]:g} e={tables.extinction[si]:g}/m",
                                   "table"))
            rows.append(np.concatenate(tiles, axis=1))
        return np.concatenate(rows, axis=0)
    for ki, k in enumerate(tables.orders):
        tiles = []
        for g in gs:
            gi = _nearest(tables.g, g)
            tiles.append(label(to_srgb8(tables.multiple[ki, gi, si]),
                               f"E{k} g={tables.g[gi]:g} e={tables.extinction[si]:g}/m", "table"))
        rows.append(np.concatenate(tiles, axis=1))
    return np.concatenate(rows, axis=0)
