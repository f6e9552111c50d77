"""
Cloud / sky segmentation
========================

Defines the cloud / sky classification of a photograph by chroma (Dobashi et al. 2012, §4.1, after Dobashi et
al. 2010):

-   :data:`SKY`, :data:`CLOUD`, :data:`NEITHER`, :data:`AUTO`: the labels.
-   :func:`check_colour_photo`: the photo as float32, refusing a greyscale photo.
-   :func:`saturation`: the CIE 1976 saturation s_ab and the lightness L*.
-   :func:`otsu_threshold`: Otsu's threshold of a 1-D sample.
-   :func:`decode_hand_mask`: a hand-painted mask to labels.
-   :func:`classify`: label every pixel.
-   :func:`soft_alpha`: the cloud opacity α.

§4.1: "each pixel in the input photograph is classified into either a cloud pixel or a sky pixel depending
on the chroma of each pixel ... If the above method does not work very well, our system allows the user to
verify and modify the result by hand."

The sky is chromatic (blue), clouds are achromatic and bright. The measure is the CIE 1976 saturation
``s_ab = C*_ab / L*`` of CIE L*a*b* (D65), computed through :mod:`natscene.color` (colour-science); a pixel
is cloud when ``s_ab < t`` and ``L* >= min_lightness``. The threshold ``t`` is Otsu's (1979) on the
histogram of ``s_ab`` unless the config gives one. The cloud mask is cleaned by a morphological opening
then closing (elliptical structuring element of radius ``morphology_radius`` px) and by removing cloud
islands and sky holes smaller than ``min_region_fraction`` of the image.

Labels: 0 = sky, 1 = cloud, 2 = neither (ground, buildings, a kite: counted as neither sky nor cloud).

A hand-painted mask (same size as the photo) overrides the classifier pixel by pixel:
white (grey ≥ 0.75) = cloud, black (grey ≤ 0.25) = sky, mid-grey = decide automatically,
red (R ≥ 0.5, G ≤ 0.25, B ≤ 0.25) = neither; a transparent pixel (alpha < 0.5) = decide automatically.

Soft alpha: a cloud pixel is modelled as ``P = α·w·c_in + (1 − α)·L_sky`` (a cloud of the incident
light's colour c_in, unknown brightness w, in front of the sky). Projecting onto the plane orthogonal to
c_in removes the unknown ``w``: ``(1 − α) = <P⊥, S⊥> / |S⊥|²`` with ``S = L_sky``; α is clipped to [0, 1].

References
----------
-   Dobashi, Y., Shinzo, Y., & Yamamoto, T. (2010). Modeling of clouds from a single photograph. Computer
    Graphics Forum, 29(7), 2083–2090.
-   Dobashi, Y., Iwasaki, W., Ono, A., Yamamoto, T., Yue, Y., & Nishita, T. (2012). An inverse problem approach
    for automatically adjusting the parameters for rendering clouds using photographs. ACM Transactions on
    Graphics, 31(6).
-   Otsu, N. (1979). A threshold selection method from gray-level histograms. IEEE Transactions on Systems, Man,
    and Cybernetics, 9(1), 62–66.
"""
from __future__ import annotations

import cv2
import numpy as np

from natscene.color import linear_srgb_to_lab
from natscene.errors import InputError

__all__ = ["SKY", "CLOUD", "NEITHER", "AUTO", "check_colour_photo", "saturation", "otsu_threshold",
           "decode_hand_mask", "classify", "soft_alpha"]

SKY, CLOUD, NEITHER = 0, 1, 2
LABEL_NAMES = {SKY: "sky", CLOUD: "cloud", NEITHER: "neither"}
AUTO = -1  # hand-mask value: let the classifier decide


def check_colour_photo(photo: np.ndarray, name: str = "photo") -> np.ndarray:
    """The photo as float32 (H, W, 3); a greyscale photo (chroma undefined) raises InputError."""
    a = np.asarray(photo, np.float32)
    if a.ndim != 3 or a.shape[-1] not in (1, 3):
        raise InputError(f"{name}: expected an RGB image, got shape {a.shape}")
    if not np.all(np.isfinite(a)):
        raise InputError(f"{name}: contains NaN or infinite pixels; fix the image")
    if a.shape[-1] == 1 or float(np.max(np.ptp(a, axis=-1))) <= 1e-6:
        raise InputError(f"{name}: greyscale photo: sky/cloud classification works on chroma (blue sky vs "
                         f"white cloud), which a grey image does not have. Use the colour original, or "
                         f"paint a mask (photos.<name>.mask) giving every pixel as cloud or sky.")
    return a


def saturation(photo: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """CIE 1976 saturation ``s_ab = C*_ab / L*`` and lightness L* of a linear sRGB photo."""
    lab = linear_srgb_to_lab(np.clip(photo, 0.0, None))
    L = lab[..., 0]
    chroma = np.hypot(lab[..., 1], lab[..., 2])
    return (chroma / np.maximum(L, 1.0)).astype(np.float32), L.astype(np.float32)


def otsu_threshold(values: np.ndarray, nbins: int = 256) -> float:
    """Otsu's (1979) threshold of a 1-D sample: the histogram split maximising the between-class variance.

    Returned as the bin *edge* between the two classes, so that ``values < t`` is exactly the lower class
    (skimage's ``threshold_otsu`` returns a bin centre, which misplaces values inside the boundary bin).
    InputError when the sample has a single value.
    """
    v = np.asarray(values, np.float64).ravel()
    v = v[np.isfinite(v)]
    if v.size == 0 or np.ptp(v) == 0:
        raise InputError("cannot choose a threshold automatically: all candidate pixels have the same value")
    hist, edges = np.histogram(v, bins=nbins)
    centres = 0.5 * (edges[:-1] + edges[1:])
    w0 = np.cumsum(hist)[:-1].astype(np.float64)
    w1 = v.size - w0
    s0 = np.cumsum(hist * centres)[:-1]
    m0 = s0 / np.maximum(w0, 1)
    m1 = (np.sum(hist * centres) - s0) / np.maximum(w1, 1)
    between = w0 * w1 * (m0 - m1) ** 2
    k = int(np.argmax(between))
    return float(edges[k + 1])


def decode_hand_mask(mask: np.ndarray, shape: tuple[int, int], name: str = "mask") -> np.ndarray:
    """Hand-painted mask (H, W[, C]) in [0, 1] -> int8 (H, W) with SKY / CLOUD / NEITHER / AUTO."""
    m = np.asarray(mask, np.float32)
    if m.ndim == 2:
        m = m[..., None]
    if m.shape[:2] != tuple(shape):
        raise InputError(f"{name}: mask is {m.shape[1]}x{m.shape[0]} but the photo is {shape[1]}x{shape[0]}; "
                         f"paint the mask at the photo's size")
    c = m.shape[-1]
    alpha = m[..., 3] if c >= 4 else (m[..., 1] if c == 2 else None)
    rgb = m[..., :3] if c >= 3 else np.repeat(m[..., :1], 3, axis=-1)
    grey = rgb.mean(axis=-1)
    out = np.full(shape, AUTO, np.int8)
    out[grey >= 0.75] = CLOUD
    out[grey <= 0.25] = SKY
    red = (rgb[..., 0] >= 0.5) & (rgb[..., 1] <= 0.25) & (rgb[..., 2] <= 0.25)
    out[red] = NEITHER
    if alpha is not None:
        out[alpha < 0.5] = AUTO
    return out


def _remove_small(mask: np.ndarray, min_area: int) -> np.ndarray:
    """Drop 8-connected components of ``mask`` smaller than ``min_area`` pixels."""
    if min_area <= 1 or not mask.any():
        return mask
    n, lab, stats, _ = cv2.connectedComponentsWithStats(mask.astype(np.uint8), connectivity=8)
    keep = stats[:, cv2.CC_STAT_AREA] >= min_area
    keep[0] = False
    return keep[lab]


def clean_mask(cloud: np.ndarray, radius: int, min_area: int) -> np.ndarray:
    """Opening then closing with an elliptical element of ``radius`` px; small islands and holes removed."""
    m = cloud.astype(np.uint8)
    if radius > 0:
        k = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * radius + 1, 2 * radius + 1))
        m = cv2.morphologyEx(m, cv2.MORPH_OPEN, k, borderType=cv2.BORDER_REPLICATE)
        m = cv2.morphologyEx(m, cv2.MORPH_CLOSE, k, borderType=cv2.BORDER_REPLICATE)
    m = _remove_small(m.astype(bool), min_area)
    m = ~_remove_small(~m, min_area)  # holes of sky inside cloud
    return m


def classify(photo: np.ndarray, threshold: float | None = None, min_lightness: float = 20.0,
             morphology_radius: int = 2, min_region_fraction: float = 1e-4,
             hand_mask: np.ndarray | None = None) -> tuple[np.ndarray, dict]:
    """Label every pixel SKY / CLOUD / NEITHER.

    Returns ``(labels uint8 (H, W), info)`` with info: threshold, threshold_source ('otsu' or 'config'),
    hand-mask pixel counts.
    """
    photo = np.asarray(photo, np.float32)
    h, w = photo.shape[:2]
    forced = np.full((h, w), AUTO, np.int8) if hand_mask is None else np.asarray(hand_mask, np.int8)
    auto = forced == AUTO
    if auto.any():
        photo = check_colour_photo(photo)
    s, L = saturation(photo)
    if threshold is None:
        if not auto.any():
            t, source = float("nan"), "mask"
        else:
            t, source = otsu_threshold(s[auto]), "otsu"
    else:
        t, source = float(threshold), "config"
    cloud = (s < t) & (L >= min_lightness) if np.isfinite(t) else np.zeros((h, w), bool)
    min_area = int(round(min_region_fraction * h * w))
    cloud = clean_mask(cloud, int(morphology_radius), min_area)
    labels = np.where(cloud, CLOUD, SKY).astype(np.uint8)
    labels[~auto] = forced[~auto].astype(np.uint8)
    info = {"threshold": t, "threshold_source": source, "measure": "CIE 1976 saturation s_ab = C*ab / L*",
            "hand_mask_pixels": {"cloud": int((forced == CLOUD).sum()), "sky": int((forced == SKY).sum()),
                                 "neither": int((forced == NEITHER).sum()), "auto": int(auto.sum())}}
    return labels, info


def soft_alpha(photo: np.ndarray, sky: np.ndarray, labels: np.ndarray, c_in: np.ndarray) -> np.ndarray:
    """Cloud opacity α in [0, 1] from ``P = α·w·c_in + (1 − α)·L_sky`` (module docstring); 0 off cloud."""
    c = np.asarray(c_in, np.float64)
    c = c / np.linalg.norm(c)
    P = photo.astype(np.float64)
    S = sky.astype(np.float64)
    Pp = P - (P @ c)[..., None] * c
    Sp = S - (S @ c)[..., None] * c
    den = np.einsum("...c,...c->...", Sp, Sp)
    num = np.einsum("...c,...c->...", Pp, Sp)
    ok = den > 1e-12
    one_minus = np.where(ok, num / np.where(ok, den, 1.0), 0.0)
    alpha = np.clip(1.0 - one_minus, 0.0, 1.0)
    alpha[labels != CLOUD] = 0.0
    return alpha.astype(np.float32)
