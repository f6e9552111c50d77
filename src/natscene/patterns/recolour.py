"""
Recolouring a flower photograph
===============================

Defines the recolouring of a flower photograph with a pigment pattern (Dong 2007, §3.5, Fig. 3.8):

-   :func:`recolour_photo`: the whole §3.5 pipeline on one photo (config entry, :data:`DEFAULTS`).
-   :func:`recolour`: the YIQ recolouring of a photo with a colour texture.
-   :func:`flower_mask`: the petal shape of a photo.
-   :func:`standard_concentration`: C_0 of c = C / C_0.
-   :func:`vein_contrast`, :func:`mean_hue`: the diagnostics of the report.

"We split the original image in YIQ space, and extract the shape and venation information. Then we
redefine the I channel with user-appointed pigment, and replace the Q channel with the pigment
distribution map. The Y channel, which includes geometry detail, material property and lighting
environment, is also modified based on the pigment distribution map."

Here, with the colour texture C(x) of §3.4 (Eq. 3.9 evaluated on the pigment maps) and its base colour
C_0 (zero concentration), all in display-encoded sRGB as NTSC YIQ expects:

    Y_out = Y_photo * Y_C(x) / Y_C0          (detail of the photo, lightness of Eq. 3.10)
    I_out, Q_out = (I_C, Q_C)(x) * Y_out / Y_C(x)   (hue and saturation of the pigment colour)

outside the petal mask the photo is kept. Colour conversions go through natscene.color.

The pigment maps come from the venation-aware reaction-diffusion (§3.3) on the petal shape and the vein tree
extracted from the same photo (``venation.venation_from_photo``), normalised as c = C / C_0 (§3.3.2) with the
standard concentration C_0 chosen by the caller (the rule uses a high percentile of the map, see
``standard_concentration``, since the vein root is a one-cell Dirichlet supply spike).

Diagnostics for the report: ``vein_contrast`` (mean of a map on the vascular cells vs. between the veins) and
``mean_hue`` (chroma-weighted mean CIELAB hue angle of the flower pixels, to measure the hue shift).

``flower_mask`` extracts the petal shape: saturated, not-too-dark pixels (HSV saturation >= s_min and
value >= v_min of the encoded photo), cleaned by a morphological opening and hole filling.

References
----------
-   Dong, W. (2007). Rendering Algorithms for Natural Scenes. PhD thesis, Université Henri Poincaré - Nancy I.
"""
from __future__ import annotations

import numpy as np
from scipy import ndimage

from natscene.color import linear_srgb_to_lab, linear_to_srgb, srgb_to_linear, srgb_to_yiq, yiq_to_srgb
from natscene.config import section_defaults
from natscene.errors import InputError

__all__ = ["flower_mask", "standard_concentration", "vein_contrast", "mean_hue", "recolour", "DEFAULTS",
           "recolour_photo"]


def flower_mask(photo_linear: np.ndarray, s_min: float = 0.35, v_min: float = 0.08) -> np.ndarray:
    enc = linear_to_srgb(photo_linear[..., :3])
    mx, mn = enc.max(axis=-1), enc.min(axis=-1)
    sat = np.where(mx > 0, (mx - mn) / np.maximum(mx, 1e-6), 0.0)
    m = (sat >= s_min) & (mx >= v_min)
    m = ndimage.binary_opening(m, iterations=2)
    m = ndimage.binary_fill_holes(m)
    if m.sum() < 16:
        raise InputError("no flower found in the photo (no saturated pixels); lower 's_min' or give a mask")
    return m.astype(np.float32)


def standard_concentration(conc: np.ndarray, mask: np.ndarray, percentile: float = 99.0) -> float:
    """C_0 of c = C / C_0: the ``percentile`` of the concentration on the petal (100 = its maximum)."""
    inside = np.asarray(mask) > 0.5
    if not inside.any():
        raise InputError("standard_concentration: empty petal mask")
    return float(np.percentile(np.asarray(conc)[inside], percentile))


def vein_contrast(c: np.ndarray, vascular: np.ndarray, mask: np.ndarray, gap: int = 4) -> tuple[float, float]:
    """(mean of ``c`` on the vascular cells, mean of ``c`` on petal cells more than ``gap`` cells from any vein)."""
    vas = np.asarray(vascular, bool) & (np.asarray(mask) > 0.5)
    far = (np.asarray(mask) > 0.5) & ~ndimage.binary_dilation(vas, iterations=gap)
    return (float(c[vas].mean()) if vas.any() else float("nan"),
            float(c[far].mean()) if far.any() else float("nan"))


def mean_hue(rgb_linear: np.ndarray, mask: np.ndarray) -> tuple[float, float]:
    """Chroma-weighted mean CIELAB (D65) hue angle (degrees) and the mean chroma C*ab of the masked pixels."""
    lab = linear_srgb_to_lab(np.asarray(rgb_linear, np.float32)[..., :3])[np.asarray(mask) > 0.5]
    a, b = lab[:, 1].astype(float), lab[:, 2].astype(float)
    return float(np.degrees(np.arctan2(b.sum(), a.sum()))), float(np.hypot(a, b).mean())


def recolour(photo_linear: np.ndarray, colour_linear: np.ndarray, base_linear: np.ndarray,
             mask: np.ndarray, eps: float = 1e-4) -> np.ndarray:
    """The §3.5 YIQ recolouring; all inputs linear sRGB, returns linear sRGB (H, W, 3)."""
    if photo_linear.shape[:2] != colour_linear.shape[:2] or mask.shape != photo_linear.shape[:2]:
        raise InputError(f"photo {photo_linear.shape[:2]}, colour {colour_linear.shape[:2]} and mask "
                         f"{mask.shape} must have the same size")
    yiq_p = srgb_to_yiq(linear_to_srgb(photo_linear[..., :3]))
    yiq_c = srgb_to_yiq(linear_to_srgb(colour_linear[..., :3]))
    y0 = float(srgb_to_yiq(linear_to_srgb(np.asarray(base_linear, np.float32).reshape(1, 3)))[0, 0])
    y_out = yiq_p[..., 0] * yiq_c[..., 0] / max(y0, eps)
    ratio = y_out / np.maximum(yiq_c[..., 0], eps)
    out = np.stack([y_out, yiq_c[..., 1] * ratio, yiq_c[..., 2] * ratio], axis=-1)
    rgb = srgb_to_linear(np.clip(yiq_to_srgb(out), 0.0, 1.0))
    m = (np.asarray(mask) > 0.5)[..., None]
    return np.where(m, rgb, photo_linear[..., :3]).astype(np.float32)


#: defaults of a ``recolour`` config entry for library calls: the schema's, workflow/schemas/recolour.schema.yaml
DEFAULTS = section_defaults("recolour.schema.yaml", ("additionalProperties",))


def recolour_photo(photo_path, spec: dict, seed: int = 0, logger=None) -> dict:
    """The whole §3.5 pipeline on one photo (config entry ``spec``, see DEFAULTS): petal mask, vein tree,
    reaction-diffusion on a ``sim_width``-wide grid, pigment maps c = concentration * C / C_0 upsampled to the
    photo, colour expression (Eq. 3.9) and the YIQ recolouring. Returns a dict with ``photo``, ``result``,
    ``mask``, ``maps`` (sim grid), ``venation``, ``params`` (RDParams) and ``stats`` (diagnostics)."""
    from skimage.transform import resize

    from natscene.color import luminance
    from natscene.io import read_photo
    from natscene.patterns.expression import express_rgb, precompute
    from natscene.patterns.pigments import pigment
    from natscene.patterns.presets import rd_params
    from natscene.patterns.reaction_diffusion import normalise, simulate
    from natscene.patterns.venation import venation_from_photo

    spec = {**DEFAULTS, **spec}
    photo = read_photo(photo_path)
    if photo.shape[-1] < 3:
        raise InputError(f"{photo_path}: the photo must be RGB (got {photo.shape[-1]} channel(s))")
    h, w = photo.shape[:2]
    mask = flower_mask(photo, spec["s_min"], spec["v_min"])
    sw = int(spec["sim_width"])
    sh = max(4, round(h * sw / w))
    small = resize(photo, (sh, sw, 3), anti_aliasing=True).astype(np.float32)
    msmall = (resize(mask, (sh, sw), order=0) > 0.5).astype(np.float32)
    ven = venation_from_photo(luminance(small), msmall, tuple(spec["root"]))
    p = rd_params(spec["rd"], seed, sh, "recolour.*.rd")
    r = simulate(msmall, ven, p, logger=logger)
    pct = float(spec["c0_percentile"])
    maps = [normalise(x, msmall, standard_concentration(x, msmall, pct)) for x in (r.a, r.b)]
    k = float(spec["concentration"])
    conc = np.stack([resize(c, (h, w), order=1) for c in maps], -1) * k
    table = precompute([pigment(x) for x in spec["pigments"]])
    colour = express_rgb(table, conc)
    base = express_rgb(table, np.zeros(len(maps)))
    out = recolour(photo, colour, base, mask)
    inside = msmall > 0.5
    vein, inter = vein_contrast(maps[0], ven.vascular, msmall)
    h0, c0 = mean_hue(photo, mask)
    h1, c1 = mean_hue(out, mask)
    stats = dict(sim=[sw, sh], vein_cells=int(ven.vascular.sum()), vein_paths=len(ven.paths or []),
                 rd_steps=int(r.steps), rd_converged=bool(r.converged),
                 map0_vein=vein, map0_intervein=inter,
                 map0_range=[float(maps[0][inside].min()), float(maps[0][inside].max())],
                 hue_photo_deg=h0, hue_result_deg=h1, hue_shift_deg=float((h1 - h0 + 180.0) % 360.0 - 180.0),
                 chroma_photo=c0, chroma_result=c1)
    return dict(photo=photo, result=out, mask=mask, maps=maps, venation=ven, params=p, pigments=table.names,
                stats=stats)
