"""
Type feature of a texture
=========================

Defines the type feature of Dong (2007, §6.4): the type map of a texture from the user's label image:

-   :func:`type_map`: the type map of a label image; :func:`type_preview`: its grey image.
-   :func:`check_types`, :func:`soft_type_channels`: the example's and the target's type maps checked, and
    appended to their feature channels (soft constraint).

T(p) = m_p: 0 for the background, 1..b for the b type features (a different material, a region of interest, a
foreground object). Label images are read as integers: a grey or palette PNG whose values are the labels, or an
RGB image whose distinct colours become labels 1..b in order of first appearance (black is the background).

References
----------
-   Dong, W. (2007). Rendering Algorithms for Natural Scenes. PhD thesis, Université Henri Poincaré - Nancy I.
"""
from __future__ import annotations

import numpy as np

from natscene.errors import InputError

__all__ = ["type_map", "type_preview", "check_types", "soft_type_channels"]


def type_map(labels: np.ndarray, shape: tuple | None = None, source: str = "type map") -> np.ndarray:
    """An int32 type map from a label image (H, W) of integers or (H, W, 3) colours; ``shape`` (H, W) that it must
    have (the texture's)."""
    a = np.asarray(labels)
    if a.ndim == 3:
        rgb = a[..., :3].reshape(-1, 3)
        colours, inverse = np.unique(rgb, axis=0, return_inverse=True)
        black = np.flatnonzero((colours == 0).all(1))
        ids = np.zeros(len(colours), np.int32)
        order = [c for c in range(len(colours)) if c not in black]
        ids[order] = np.arange(1, len(order) + 1)
        t = ids[inverse.ravel()].reshape(a.shape[:2])
    elif a.ndim == 2:
        if np.issubdtype(a.dtype, np.floating) and not np.allclose(a, np.round(a)):
            raise InputError(f"{source}: labels must be whole numbers (0 = background, 1..b = types)")
        t = np.round(a).astype(np.int32)
    else:
        raise InputError(f"{source}: expected a label image (H, W) or (H, W, 3), got shape {a.shape}")
    if shape is not None and t.shape != tuple(shape[:2]):
        raise InputError(f"{source}: {t.shape[1]}x{t.shape[0]}, but its texture is {shape[1]}x{shape[0]}")
    if t.min() < 0:
        raise InputError(f"{source}: negative label {t.min()}")
    return t


def type_preview(types: np.ndarray) -> np.ndarray:
    """Grey levels as the thesis shows type maps: the background black, types 1..b evenly brighter."""
    b = max(int(types.max()), 1)
    return (types / b).astype(np.float32)


def check_types(example_types: np.ndarray, target_types: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The two type maps as int64, after checking that every type of the target is one of the example's."""
    te, tt = np.asarray(example_types, np.int64), np.asarray(target_types, np.int64)
    missing = sorted(set(np.unique(tt).tolist()) - set(np.unique(te).tolist()))
    if missing:
        raise InputError(f"type map: the target's types {missing} are not in the example's type map")
    return te, tt


def soft_type_channels(example_features: np.ndarray, target_features: np.ndarray, example_types: np.ndarray,
                       target_types: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The soft-constraint mode (§6.4): the type maps appended to the example's and the target's feature channels
    (H, W, k) in the grey units of the thesis' type images (:func:`type_preview`)."""
    te, tt = check_types(example_types, target_types)
    b = max(int(te.max()), 1)
    return (np.concatenate([example_features, (te / b)[..., None].astype(np.float32)], -1),
            np.concatenate([target_features, (tt / b)[..., None].astype(np.float32)], -1))
