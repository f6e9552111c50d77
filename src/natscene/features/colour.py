"""
Colour feature of a texture
===========================

Defines the colour feature of Dong (2007, §6.5): colour regions of a texture, their statistics, and colour
transfer:

-   :func:`segment`: the colour regions of an image by mean shift.
-   :func:`region_stats`: each region's size, mean and standard deviation in l-alpha-beta.
-   :func:`region_colours`: a colour map drawn in its regions' mean colours (the previews of Fig. 6.9 c, 6.15 c).
-   :func:`transfer`, :func:`transfer_to_largest`, :func:`recolour_regions`: Reinhard's colour transfer, to the
    largest region, or from saved statistics.
-   :func:`rgb_to_lab_rs`, :func:`lab_rs_to_rgb`: linear RGB to Reinhard's l-alpha-beta and back.

(1) the texture is segmented by colour with mean shift (Comaniciu & Meer 2002: OpenCV's
``pyrMeanShiftFiltering``, then the connected regions of equal filtered colour, small ones merged into their
largest neighbour); (2) a user may edit the label image; (3) optionally every region's colour is transferred to the
largest region's (Reinhard, Ashikhmin, Gooch & Shirley, *Color transfer between images*, 2001: per-axis mean and
standard deviation in l-alpha-beta); (4) each region's mean and standard deviation in l-alpha-beta are saved with
the colour map, so that a synthesised texture can be given back the regions' colours (Fig. 6.15(d)).

References
----------
-   Comaniciu, D., & Meer, P. (2002). Mean shift: A robust approach toward feature space analysis. IEEE
    Transactions on Pattern Analysis and Machine Intelligence, 24(5), 603–619.
-   Dong, W. (2007). Rendering Algorithms for Natural Scenes. PhD thesis, Université Henri Poincaré - Nancy I.
-   Reinhard, E., Ashikhmin, M., Gooch, B., & Shirley, P. (2001). Color transfer between images. IEEE Computer
    Graphics and Applications, 21(5), 34–41.
"""
from __future__ import annotations

import cv2
import numpy as np
from scipy import ndimage

from natscene.errors import InputError

__all__ = ["segment", "rgb_to_lab_rs", "lab_rs_to_rgb", "region_stats", "region_colours", "transfer",
           "transfer_to_largest", "recolour_regions"]

# Reinhard et al. 2001: linear RGB -> LMS, log10 LMS -> l-alpha-beta (their Eqs. 1-4)
_RGB2LMS = np.array([[0.3811, 0.5783, 0.0402], [0.1967, 0.7244, 0.0782], [0.0241, 0.1288, 0.8444]])
_LOG2LAB = np.diag([1 / np.sqrt(3), 1 / np.sqrt(6), 1 / np.sqrt(2)]) @ np.array([[1, 1, 1], [1, 1, -2], [1, -1, 0]])
_EPS = 1e-4


def rgb_to_lab_rs(rgb: np.ndarray) -> np.ndarray:
    """Linear RGB (..., 3) -> Reinhard's l-alpha-beta (decorrelated log-LMS)."""
    lms = np.maximum(np.asarray(rgb, np.float64) @ _RGB2LMS.T, _EPS)
    return np.log10(lms) @ _LOG2LAB.T


def lab_rs_to_rgb(lab: np.ndarray) -> np.ndarray:
    """Reinhard's l-alpha-beta -> linear RGB (the inverse of :func:`rgb_to_lab_rs`)."""
    lms = 10.0 ** (np.asarray(lab, np.float64) @ np.linalg.inv(_LOG2LAB).T)
    return lms @ np.linalg.inv(_RGB2LMS).T


def segment(rgb8: np.ndarray, spatial_radius: float = 12, colour_radius: float = 24, min_region: int = 400,
            smooth: float = 4.0) -> np.ndarray:
    """Colour regions (int32 labels 0..k-1, largest first) of an sRGB uint8 image by mean shift.

    The texture's own contrast (light and dark texels) is not a colour feature: the image is first blurred by a
    Gaussian of ``smooth`` pixels (about a texel), then mean-shift filtered (spatial and colour radii); pixels
    whose filtered colours fall in the same cell of ``colour_radius`` / 2 and touch form a region, touching
    regions whose mean colours differ by less than ``colour_radius`` / 2 merge, and regions under ``min_region``
    pixels join the neighbour they share most border with.
    """
    img = np.ascontiguousarray(rgb8[..., :3], np.uint8)
    if smooth > 0:
        img = cv2.GaussianBlur(img, (0, 0), smooth)
    filtered = cv2.pyrMeanShiftFiltering(img, spatial_radius, colour_radius)
    q = filtered.astype(np.int32) // max(1, int(colour_radius // 2))
    key = (q[..., 0] * 512 + q[..., 1]) * 512 + q[..., 2]
    labels = np.zeros(key.shape, np.int32)
    n = 0
    for k in np.unique(key):
        lab, m = ndimage.label(key == k)
        labels[lab > 0] = lab[lab > 0] + n
        n += m
    labels -= 1
    return _merge_small(_merge_similar(labels, filtered, colour_radius / 2), min_region)


def _merge_similar(labels: np.ndarray, colours: np.ndarray, tol: float) -> np.ndarray:
    """Touching regions whose mean colours differ by less than ``tol`` (Euclidean, 0..255) become one (the
    cells of the quantisation split a mean-shift mode that straddles a cell border)."""
    while True:
        k = int(labels.max()) + 1
        counts = np.bincount(labels.ravel(), minlength=k).astype(np.float64)
        mean = np.stack([np.bincount(labels.ravel(), colours[..., c].ravel().astype(np.float64), k)
                         for c in range(3)], -1) / np.maximum(counts, 1)[:, None]
        pairs = np.concatenate([np.stack([labels[:, :-1].ravel(), labels[:, 1:].ravel()], 1),
                                np.stack([labels[:-1].ravel(), labels[1:].ravel()], 1)])
        pairs = np.unique(np.sort(pairs[pairs[:, 0] != pairs[:, 1]], 1), axis=0)
        if not len(pairs):
            return labels
        d = np.linalg.norm(mean[pairs[:, 0]] - mean[pairs[:, 1]], axis=1)
        close = pairs[d < tol]
        if not len(close):
            return labels
        parent = np.arange(k)

        def root(i):
            while parent[i] != i:
                parent[i] = parent[parent[i]]
                i = parent[i]
            return i
        for a, b in close:
            ra, rb = root(a), root(b)
            if ra != rb:
                parent[max(ra, rb)] = min(ra, rb)
        roots = np.array([root(i) for i in range(k)])
        _, labels = np.unique(roots[labels], return_inverse=True)
        labels = labels.reshape(colours.shape[:2]).astype(np.int32)


def _merge_small(labels: np.ndarray, min_region: int) -> np.ndarray:
    """Regions under ``min_region`` pixels joined to the neighbour region they share most border with."""
    labels = labels.copy()
    while True:
        sizes = np.bincount(labels.ravel())
        small = [r for r in np.argsort(sizes) if 0 < sizes[r] < min_region]
        if not small or (sizes > 0).sum() <= 1:
            break
        r = small[0]
        ring = ndimage.binary_dilation(labels == r) & (labels != r)
        if not ring.any():
            break
        labels[labels == r] = np.bincount(labels[ring]).argmax()
    # relabel 0..k-1, largest region first
    ids, counts = np.unique(labels, return_counts=True)
    order = ids[np.argsort(-counts, kind="stable")]
    lut = np.zeros(labels.max() + 1, np.int32)
    lut[order] = np.arange(len(order))
    return lut[labels]


def region_stats(rgb: np.ndarray, labels: np.ndarray) -> list[dict]:
    """Per region (label order): pixel count, mean and standard deviation of l, alpha, beta."""
    lab = rgb_to_lab_rs(rgb).reshape(-1, 3)
    flat = labels.ravel()
    out = []
    for r in range(int(flat.max()) + 1):
        v = lab[flat == r]
        if len(v) == 0:
            raise InputError(f"colour map: region {r} has no pixel")
        out.append({"pixels": int(len(v)), "mean": v.mean(0).tolist(), "std": v.std(0).tolist()})
    return out


def region_colours(labels: np.ndarray, stats: list[dict]) -> np.ndarray:
    """Linear RGB (H, W, 3): each pixel of the colour map ``labels`` in its region's mean colour (``stats`` of
    :func:`region_stats`)."""
    if int(labels.max()) >= len(stats):
        raise InputError(f"colour map: region {int(labels.max())} has no saved statistics ({len(stats)} regions)")
    means = np.clip(lab_rs_to_rgb(np.array([r["mean"] for r in stats], np.float64)), 0.0, None)
    return means[labels]


def transfer(rgb: np.ndarray, source: dict, target: dict) -> np.ndarray:
    """Reinhard's transfer of pixels with statistics ``source`` to ``target`` (dicts with mean, std)."""
    lab = rgb_to_lab_rs(rgb)
    s_mean, s_std = np.asarray(source["mean"]), np.maximum(np.asarray(source["std"]), 1e-6)
    lab = (lab - s_mean) * (np.asarray(target["std"]) / s_std) + np.asarray(target["mean"])
    return np.clip(lab_rs_to_rgb(lab), 0.0, None)


def transfer_to_largest(rgb: np.ndarray, labels: np.ndarray) -> np.ndarray:
    """Step (3) of §6.5: every region recoloured to the largest region's statistics (a colour-consistent
    example)."""
    stats = region_stats(rgb, labels)
    out = np.array(rgb, np.float64, copy=True)
    for r in range(1, len(stats)):
        m = labels == r
        out[m] = transfer(rgb[m], stats[r], stats[0])
    return out


def recolour_regions(rgb: np.ndarray, labels: np.ndarray, stats: list[dict]) -> np.ndarray:
    """Fig. 6.15(d): the pixels of each region of a target colour map given that region's saved statistics."""
    out = np.array(rgb, np.float64, copy=True)
    for r in range(int(labels.max()) + 1):
        m = labels == r
        if not m.any():
            continue
        if r >= len(stats):
            raise InputError(f"colour map: region {r} has no saved statistics ({len(stats)} regions)")
        here = {"mean": rgb_to_lab_rs(rgb[m]).mean(0), "std": rgb_to_lab_rs(rgb[m]).std(0)}
        out[m] = transfer(rgb[m], here, stats[r])
    return out
