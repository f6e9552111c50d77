"""Contact sheet of the precomputed tables (Dobashi 2012 §4.3) for a person to look at.

Rows: S_sun, S_amb, T at three sigma_t values; then, for ``transport: dobashi``, one row per order k of
E_m^(k) at a middle sigma_t for three g values, and for ``all_orders`` one row of the sun's multiple scattering
(every order >= 2 at beta = 0.99) and one of the skylight (the dome's R, G, B at beta = 0.99, in colour). Every tile is tone-mapped on its own (auto exposure, :func:`natscene.io.to_srgb8`) and
labelled, so the tile shows the pattern, not the absolute level.
"""
from __future__ import annotations

import numpy as np

from natscene.io import to_srgb8
from natscene.preview import label


def _nearest(grid, x) -> int:
    return int(np.argmin(np.abs(np.asarray(grid) - x)))


def contact_sheet(tables, sigmas=(0.2, 0.5, 1.0), gs=(0.0, 0.5, 0.9)) -> np.ndarray:
    """uint8 (rows*H, 3*W, 3) sheet."""
    H, W = tables.t_c.shape
    rows = []
    for name, arr in (("S_sun", tables.s_sun), ("S_amb", tables.s_amb), ("T", tables.transmittance)):
        tiles = []
        for s in sigmas:
            i = _nearest(tables.sigma_t, s)
            exp = 1.0 if name == "T" else "auto"
            tiles.append(label(to_srgb8(arr[i], exp), f"{name} s={tables.sigma_t[i]:g}", "table"))
        rows.append(np.concatenate(tiles, axis=1))
    si = _nearest(tables.sigma_t, 0.5)
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
                tiles.append(label(to_srgb8(img), f"{name} all orders g={tables.g[gi]:g} s={tables.sigma_t[si]:g}",
                                   "table"))
            rows.append(np.concatenate(tiles, axis=1))
        return np.concatenate(rows, axis=0)
    for ki, k in enumerate(tables.orders):
        tiles = []
        for g in gs:
            gi = _nearest(tables.g, g)
            tiles.append(label(to_srgb8(tables.multiple[ki, gi, si]),
                               f"E{k} g={tables.g[gi]:g} s={tables.sigma_t[si]:g}", "table"))
        rows.append(np.concatenate(tiles, axis=1))
    return np.concatenate(rows, axis=0)
