"""
Contact sheet of the tables
===========================

Defines the contact sheet of the precomputed tables (Dobashi et al. 2012, §4.3) for a person to look at:

-   :func:`contact_sheet`: the sheet as one uint8 image.

Rows: S_sun, S_amb, T at three extinction nodes; then, for ``transport: dobashi``, one row per order k of
E_m^(k) at the middle node for three g values, and for ``all_orders`` one row of the sun's multiple scattering
(every order >= 2 at beta = 0.99) and one of the skylight (the dome's R, G, B at beta = 0.99, in colour). Every tile is tone-mapped on its own (auto exposure, :func:`natscene.io.to_srgb8`) and
labelled, so the tile shows the pattern, not the absolute level.

References
----------
-   Dobashi, Y., Iwasaki, W., Ono, A., Yamamoto, T., Yue, Y., & Nishita, T. (2012). An inverse problem approach
    for automatically adjusting the parameters for rendering clouds using photographs. ACM Transactions on
    Graphics, 31(6).
"""
from __future__ import annotations

import numpy as np

from natscene.io import to_srgb8
from natscene.preview import label
from natscene.scatter.transport import of

__all__ = ["contact_sheet"]


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
    gis = [_nearest(tables.g, g) for g in gs]
    for row in of(tables).preview_rows(tables, si, gis):
        rows.append(np.concatenate([label(to_srgb8(img), f"{name} g={tables.g[gi]:g} e={tables.extinction[si]:g}/m",
                                          "table") for (name, img), gi in zip(row, gis)], axis=1))
    return np.concatenate(rows, axis=0)
