"""
Sky extraction
==============

Defines the sky stage on one photo (Dobashi et al. 2012, §4.1): classify cloud / sky / neither, interpolate the
sky behind the clouds (∇²L_sky = 0), estimate the sunlight colour c_in, and the soft cloud alpha:

-   :func:`extract_sky`: the whole stage on a linear RGB photo, a :class:`SkyResult`.
-   :class:`SkySettings`: the stage's parameters (config ``sky``, ``photos.<name>``).
-   :func:`preview_panels`: the preview mosaic (photo | mask | sky | c_in swatch).

The result is checked for plausibility (:mod:`natscene.sky.plausibility`): a photo that does not look like a
daytime cloud photo stops the job with what was found and what to do, unless the photo's config accepts it
(``accept_unusual``), in which case the findings become warnings.

The Laplace solve treats every non-sky pixel (cloud and neither) as unknown, grown by ``solve_margin``
pixels (a dilation with a 3x3 cross, repeated) so that the bright, semi-transparent cloud fringe that the
classifier left in the sky class does not leak into L_sky; L_sky equals the photo on all other pixels.

References
----------
-   Dobashi, Y., Iwasaki, W., Ono, A., Yamamoto, T., Yue, Y., & Nishita, T. (2012). An inverse problem approach
    for automatically adjusting the parameters for rendering clouds using photographs. ACM Transactions on
    Graphics, 31(6).
"""
from __future__ import annotations

from dataclasses import asdict, dataclass, field

import cv2
import numpy as np

from natscene.config import default_settings, settings_from_section
from natscene.errors import InputError
from natscene.sky.laplace import solve_laplace
from natscene.sky.plausibility import PlausibilityLimits, findings, measure, negative_values
from natscene.sky.segmentation import AUTO, CLOUD, NEITHER, SKY, check_colour_photo, classify, soft_alpha
from natscene.sky.sun_colour import SunColour, sun_colour

__all__ = ["SkySettings", "SkyResult", "extract_sky", "preview_panels"]


@dataclass
class SkySettings:
    """Parameters of the stage (config ``sky``; no defaults here: workflow/schemas/sky.schema.yaml's are the only
    ones, :func:`natscene.config.settings_from_section`)."""

    threshold: float | None  # s_ab threshold; None = Otsu
    min_lightness: float
    morphology_radius: int
    min_region_fraction: float
    solve_margin: int
    clip_level: float
    grey_chroma: float
    overcast_cloud_fraction: float
    checks: dict  # the PlausibilityLimits (sky.checks)
    accept_unusual: bool  # photos.<name>.accept_unusual: implausible findings warn instead of stopping

    SCHEMA = (("sky.schema.yaml", ()), ("photos.schema.yaml", ("additionalProperties",)))


@dataclass
class SkyResult:
    photo: np.ndarray  # (H, W, 3) linear
    labels: np.ndarray  # (H, W) uint8: 0 sky, 1 cloud, 2 neither
    alpha: np.ndarray  # (H, W) float32 soft cloud alpha
    sky: np.ndarray  # (H, W, 3) L_sky
    solved: np.ndarray  # (H, W) bool: pixels interpolated by the Laplace solve
    sun: SunColour
    classify_info: dict
    settings: SkySettings
    warnings: list = field(default_factory=list)
    plausibility: dict = field(default_factory=dict)

    def summary(self) -> dict:
        """The sun.yaml content."""
        lab = self.labels
        h, w = lab.shape
        return {
            "c_in": [float(x) for x in self.sun.c_in],
            "c_in_normalisation": "mean linear RGB of the brighter cloud pixels divided by its Rec.709 "
                                  "luminance (Y(c_in) = 1)",
            "c_in_mean_rgb": [float(x) for x in self.sun.mean_rgb],
            "c_in_chroma": self.sun.chroma,
            "thresholds": {"saturation": self.classify_info["threshold"],
                           "saturation_source": self.classify_info["threshold_source"],
                           "saturation_measure": self.classify_info["measure"],
                           "brightness": self.sun.grey_threshold,
                           "brightness_measure": "Rec.709 luminance of linear RGB, Otsu over cloud pixels"},
            "pixels": {"width": w, "height": h, "sky": int((lab == SKY).sum()), "cloud": int((lab == CLOUD).sum()),
                       "neither": int((lab == NEITHER).sum()), "solved": int(self.solved.sum()),
                       **self.sun.counts},
            "hand_mask_pixels": self.classify_info["hand_mask_pixels"],
            "overcast": self.sun.overcast,
            "plausibility": dict(self.plausibility),
            "warnings": list(self.warnings),
            "settings": asdict(self.settings),
        }


def solve_region(labels: np.ndarray, margin: int) -> np.ndarray:
    """Non-sky pixels grown by ``margin`` px (4-connected), but never the whole image when sky exists."""
    unknown = labels != SKY
    if margin > 0 and unknown.any():
        k = cv2.getStructuringElement(cv2.MORPH_CROSS, (3, 3))
        grown = cv2.dilate(unknown.astype(np.uint8), k, iterations=int(margin)).astype(bool)
        if not grown.all():
            unknown = grown
    return unknown


def extract_sky(photo: np.ndarray, settings: SkySettings | None = None,
                hand_mask: np.ndarray | None = None, name: str = "photo", key: str = "photos.<name>") -> SkyResult:
    """Run §4.1 on a linear RGB photo (H, W, 3); ``hand_mask`` from :func:`decode_hand_mask` or None.

    ``name`` names the photo in messages (its file), ``key`` its config entry (``photos.kite``).
    InputError when the photo is implausible (:mod:`natscene.sky.plausibility`) and
    ``settings.accept_unusual`` is False.
    """
    st = settings or default_settings(SkySettings)
    warnings = []
    neg = negative_values(photo)
    if neg is not None:
        what = (f"{neg['pixels']} pixels ({100 * neg['fraction']:.2f}%) have negative linear values (min "
                f"{neg['min']:.4g})")
        if not st.accept_unusual:
            raise InputError(f"{name}: {what}. Light is never negative: the EXR was made by a colour transform or "
                             f"filter that undershoots. Clamp it at 0 where it was made, or set "
                             f"{key}.accept_unusual: true to clamp them to 0 here")
        warnings.append(f"{what}; clamped to 0 ({key}.accept_unusual)")
        photo = np.maximum(np.asarray(photo, np.float32), 0.0)
    if hand_mask is not None and not (np.asarray(hand_mask) == AUTO).any():
        photo = np.asarray(photo, np.float32)  # fully painted: no chroma needed, a grey photo is fine
        photo = np.repeat(photo, 3, -1) if photo.shape[-1] == 1 else photo
    else:
        photo = check_colour_photo(photo, name)
    try:
        labels, info = classify(photo, st.threshold, st.min_lightness, st.morphology_radius,
                                st.min_region_fraction, hand_mask)
    except InputError as e:
        raise InputError(f"{name}: {e}; set photos.<name>.threshold or paint a mask") from None
    if not (labels == SKY).any():
        raise InputError(f"{name}: no sky pixels found (threshold {info['threshold']:.4g}, "
                         f"{info['threshold_source']}): the sky behind the clouds cannot be interpolated. Use "
                         f"a photo with some blue sky, set photos.<name>.threshold, or paint sky (black) in a mask")
    if not (labels == CLOUD).any():
        raise InputError(f"{name}: no cloud pixels found (threshold {info['threshold']:.4g}, "
                         f"{info['threshold_source']}): set photos.<name>.threshold higher or paint cloud (white) "
                         f"in a mask")
    sun = sun_colour(photo, labels, st.clip_level, st.grey_chroma, st.overcast_cloud_fraction)
    hand_labelled = hand_mask is not None and not (np.asarray(hand_mask) == AUTO).any()
    measured = measure(photo, labels, sun.c_in)
    found = findings(measured, settings_from_section(PlausibilityLimits, st.checks, "sky.checks"), hand_labelled)
    if found and not st.accept_unusual:
        raise InputError(
            f"{name}: this does not look like a daytime cloud photo the sky stage can use:\n  - "
            + "\n  - ".join(found)
            + f"\nWhat to do: if the classification is wrong, paint a mask ({key}.mask: white = cloud, black = sky, "
              f"red = neither); otherwise use another photo (blue sky with white or grey clouds); or set "
              f"{key}.accept_unusual: true to fit it anyway (the findings then become warnings in sun.yaml and "
              f"the fit's params.yaml). Limits: sky.checks")
    warnings += [f"unusual photo ({key}.accept_unusual): {f}" for f in found]
    solved = solve_region(labels, st.solve_margin)
    sky = solve_laplace(photo, solved)
    alpha = soft_alpha(photo, sky, labels, sun.c_in)
    return SkyResult(photo, labels, alpha, sky, solved, sun, info, st, warnings + list(sun.warnings), measured)


def preview_panels(res: SkyResult) -> np.ndarray:
    """Linear preview mosaic: photo | mask (cloud alpha grey, sky dark blue, neither red) | sky | c_in swatch."""
    h, w = res.labels.shape
    mask = np.repeat(res.alpha[..., None], 3, -1).astype(np.float32)
    mask = np.where((res.labels == CLOUD)[..., None], np.maximum(mask, 0.05), mask)
    mask[res.labels == SKY] = (0.0, 0.0, 0.08)
    mask[res.labels == NEITHER] = (0.6, 0.0, 0.0)
    sw = max(8, w // 4)
    swatch = np.broadcast_to((res.sun.c_in / res.sun.c_in.max()).astype(np.float32), (h, sw, 3))
    gap = np.ones((h, max(2, w // 160), 3), np.float32)
    return np.concatenate([res.photo, gap, mask, gap, res.sky, gap, swatch], axis=1)
