"""
Feature maps of a texture entry
===============================

Defines the feature maps of one ``textures.<name>`` entry (Dong 2007, §6.3-6.6): the example's, from its settings,
and the output's, resampled from the example's (§6.6.1) or given by the user (§6.6.2):

-   :func:`example_scale`, :func:`target_scale`: the example's and the output's scale maps.
-   :func:`resample_labels`: a label map stretched to another size.

Feature maps are carried in the grey units the thesis draws them in, so that Eq. 6.3 compares them with pixel
values in [0, 1]: scale as 0.5 + 0.5 log2(S) (:func:`natscene.features.scale.grey_from_scale`), types as t / b,
colour regions as r / (k - 1).

References
----------
-   Dong, W. (2007). Rendering Algorithms for Natural Scenes. PhD thesis, Université Henri Poincaré - Nancy I.
"""
from __future__ import annotations

import cv2
import numpy as np

from natscene.errors import InputError
from natscene.features.scale import copy_region, scale_from_angles, scale_from_grey, scale_from_mask, scale_region

__all__ = ["example_scale", "target_scale", "resample_labels"]


def example_scale(photo_grey8: np.ndarray, cfg: dict, mask: np.ndarray | None, key: str) -> np.ndarray | None:
    """The example's scale map (H, W) from ``textures.<name>.scale`` (``cfg``), or None (``from: none``);
    ``mask`` the feature mask image when the config names one."""
    h, w = photo_grey8.shape
    kind = cfg.get("from", "none")
    if kind == "none":
        return None
    if kind == "angles":
        s = scale_from_angles(w, h, float(cfg["slant"]), float(cfg["tilt"]))
    else:
        if mask is None:
            t = float(cfg["threshold"])
            mask = cv2.Canny(photo_grey8, t, 2.5 * t) > 0
        elif mask.shape != (h, w):
            raise InputError(f"config key '{key}.mask': the mask is {mask.shape[1]}x{mask.shape[0]}, the photo "
                             f"{w}x{h}")
        if not np.any(mask):
            what = f"'{key}.mask'" if cfg.get("mask") else f"'{key}.threshold' (no Canny edge at {cfg['threshold']})"
            raise InputError(f"config key {what}: the feature mask is empty")
        s = scale_from_mask(mask, int(cfg["n"]), int(cfg["gaussian"]))
    for i, e in enumerate(cfg.get("edits") or []):
        where = f"{key}.edits[{i}]"
        if e["op"] == "scale":
            if "region" not in e or "factor" not in e:
                raise InputError(f"config key '{where}': op scale needs region [x, y, w, h] and factor")
            x, y, rw, rh = e["region"]
            region = np.zeros((h, w), bool)
            region[y:y + rh, x:x + rw] = True
            s = scale_region(s, region, float(e["factor"]))
        else:
            if "source" not in e or "target" not in e:
                raise InputError(f"config key '{where}': op copy needs source [x, y, w, h] and target [x, y]")
            s = copy_region(s, e["source"], e["target"])
    return s


def target_scale(example: np.ndarray | None, cfg: dict, size: tuple, image: np.ndarray | None, key: str
                 ) -> np.ndarray | None:
    """The output's scale map (H, W) from ``textures.<name>.output.scale`` (``cfg``); ``size`` (W, H)."""
    W, H = int(size[0]), int(size[1])
    kind = cfg.get("kind", "resample")
    if kind == "resample":
        if example is None:
            return None
        return cv2.resize(example, (W, H), interpolation=cv2.INTER_LINEAR)
    if kind == "constant":
        return np.full((H, W), float(cfg["value"]), np.float32)
    if kind == "gradient":
        a, b = np.log2(float(cfg["from"])), np.log2(float(cfg["to"]))
        if cfg.get("axis", "y") == "x":
            ramp = np.broadcast_to(np.linspace(a, b, W), (H, W))
        else:  # y from the bottom row up, as the thesis' image plane
            ramp = np.broadcast_to(np.linspace(b, a, H)[:, None], (H, W))
        return (2.0 ** ramp).astype(np.float32)
    if image is None:
        raise InputError(f"config key '{key}.image': kind image needs a scale-map image")
    g = image.astype(np.float32) / (255.0 if image.dtype == np.uint8 else 1.0)
    return scale_from_grey(cv2.resize(g, (W, H), interpolation=cv2.INTER_LINEAR))


def resample_labels(labels: np.ndarray, size: tuple) -> np.ndarray:
    """A label map stretched to ``size`` (W, H), nearest neighbour."""
    return cv2.resize(labels.astype(np.int32), (int(size[0]), int(size[1])), interpolation=cv2.INTER_NEAREST)
