"""
One texture entry from photo to synthesis
=========================================

Defines one ``textures.<name>`` entry from photo to feature maps to synthesis (the glue of the rules
``texture_features``, ``feature_synthesis`` and ``texture_completion``; Dong 2007 §6.3-6.7):

-   :func:`working_image`: the example at its working size.
-   :func:`analyse`: the example's feature maps (scale, types, colour regions).
-   :func:`feature_stack`, :func:`target_stack`: the example's and the output's feature channels of Eq. 6.3.
-   :func:`optimisation_settings`, :func:`quilting_settings`: the entry's settings of the two synthesis methods.

The example is worked on in display-encoded sRGB values in [0, 1] (the neighbourhood distances of texture
optimisation are perceptual there); the EXR products are linear.

References
----------
-   Dong, W. (2007). Rendering Algorithms for Natural Scenes. PhD thesis, Université Henri Poincaré - Nancy I.
"""
from __future__ import annotations

from dataclasses import replace

import cv2
import numpy as np

from natscene.color import srgb_to_linear
from natscene.config import settings_from_section
from natscene.errors import InputError
from natscene.features.colour import region_stats, segment
from natscene.features.maps import example_scale, resample_labels, target_scale
from natscene.features.optimisation import OptimisationSettings
from natscene.features.quilting import QuiltingSettings
from natscene.features.scale import grey_from_scale
from natscene.features.type_map import type_map

__all__ = ["working_image", "analyse", "feature_stack", "target_stack", "optimisation_settings", "quilting_settings"]


def working_image(img: np.ndarray, size, nearest: bool = False) -> np.ndarray:
    """``img`` resized to ``size`` [W, H] (None: unchanged)."""
    if size is None:
        return img
    interp = cv2.INTER_NEAREST if nearest else cv2.INTER_AREA
    out = cv2.resize(img, (int(size[0]), int(size[1])), interpolation=interp)
    return out.reshape(int(size[1]), int(size[0]), *img.shape[2:])


def analyse(srgb: np.ndarray, cfg: dict, mask: np.ndarray | None, labels: np.ndarray | None, key: str) -> dict:
    """The example's feature maps: ``scale`` (H, W) or None, ``types`` (H, W) int or None, ``colour`` (H, W) int
    region labels or None with ``colour_stats``."""
    grey8 = np.clip(np.round(srgb.mean(-1) * 255), 0, 255).astype(np.uint8)
    out = {"scale": example_scale(grey8, cfg["scale"], mask, f"{key}.scale"), "types": None, "colour": None,
           "colour_stats": None}
    if labels is not None:
        out["types"] = type_map(labels, srgb.shape[:2], f"config key '{key}.types.labels'")
    if cfg["colour"]["segment"]:
        c = cfg["colour"]
        regions = segment(np.clip(np.round(srgb * 255), 0, 255).astype(np.uint8), c["spatial_radius"],
                          c["colour_radius"], c["min_region"], c["smooth"])
        out["colour"] = regions
        out["colour_stats"] = region_stats(srgb_to_linear(srgb), regions)
    return out


def _grey_labels(labels: np.ndarray, top: int) -> np.ndarray:
    return (labels / max(top, 1)).astype(np.float32)


def feature_stack(maps: dict) -> tuple[np.ndarray | None, list[str]]:
    """The example's feature channels of Eq. 6.3 (H, W, k) in grey units and their names."""
    chans, names = [], []
    if maps["scale"] is not None:
        chans.append(grey_from_scale(maps["scale"]))
        names.append("scale")
    if maps["colour"] is not None:
        chans.append(_grey_labels(maps["colour"], int(maps["colour"].max())))
        names.append("colour")
    return (np.stack(chans, -1) if chans else None), names


def target_stack(maps: dict, out_cfg: dict, size, scale_image, colour_image, key: str
                 ) -> tuple[np.ndarray | None, dict]:
    """The output's feature channels (H, W, k) matching :func:`feature_stack`, and the target label maps
    (``scale``, ``colour``) for the previews."""
    W, H = int(size[0]), int(size[1])
    chans, out = [], {}
    if maps["scale"] is not None or out_cfg["scale"]["kind"] != "resample":
        if maps["scale"] is None:
            raise InputError(f"config key '{key}.output.scale': a target scale map needs the example's scale "
                             f"feature ('{key}.scale.from' is none)")
        s = target_scale(maps["scale"], out_cfg["scale"], (W, H), scale_image, f"{key}.output.scale")
        out["scale"] = s
        chans.append(grey_from_scale(s))
    if maps["colour"] is not None:
        top = int(maps["colour"].max())
        c = resample_labels(maps["colour"], (W, H)) if colour_image is None else type_map(colour_image, (H, W),
                                                                                           f"{key}.output.colour")
        if c.max() > top:
            raise InputError(f"config key '{key}.output.colour': region {int(c.max())} is not one of the "
                             f"example's {top + 1} colour regions")
        out["colour"] = c
        chans.append(_grey_labels(c, top))
    return (np.stack(chans, -1) if chans else None), out


def _with_type_mode(cls, entry: dict, section: str, key: str):
    """The settings ``cls`` of ``entry[section]`` with the entry's ``types.mode``."""
    return replace(settings_from_section(cls, entry[section], f"{key}.{section}"), type_mode=entry["types"]["mode"])


def optimisation_settings(entry: dict, key: str) -> OptimisationSettings:
    return _with_type_mode(OptimisationSettings, entry, "optimisation", key)


def quilting_settings(entry: dict, key: str) -> QuiltingSettings:
    return _with_type_mode(QuiltingSettings, entry, "quilting", key)
