"""
Plausibility of a cloud photo
=============================

Defines the plausibility checks of the sky stage's result (Dobashi et al. 2012, §4.1): is this a cloud photo
the method can use?

-   :func:`measure`: the numbers the checks compare; :func:`negative_values`: the negative values of a linear
    photo.
-   :func:`findings`: what is implausible about a measured segmentation, against :class:`PlausibilityLimits`.

§4.1 classifies pixels by chroma (blue sky, achromatic cloud) and takes the sunlight colour c_in from the
bright cloud pixels. On a photo that is not a daytime cloud photo the classifier still splits the pixels in
two (Otsu always finds a threshold), and every later stage runs on nonsense: an orange flower gives an
orange "sun", a garden's green background becomes "cloud". These checks measure what the segmentation
found and compare it with what a daytime cloud photograph looks like:

=============================  =========================================================================
check                          measure (limits: ``sky.checks``, defaults below)
=============================  =========================================================================
linear values                  no negative values (linear EXR/HDR photos); non-finite values are always
                               an error
enough sky                     sky pixels >= ``min_sky_fraction`` (0.05) of the image: the Laplace
                               solve needs sky around the clouds
enough cloud                   cloud pixels >= ``min_cloud_fraction`` (0.01) of the image
cloud is cloud-coloured        median CIE saturation s_ab = C*ab/L* of the cloud pixels <=
                               ``max_cloud_to_sky_saturation`` (0.4) x that of the sky pixels: clouds
                               are far less saturated than the sky they stand in
sky is sky-coloured            median s_ab of the sky pixels >= ``min_sky_saturation`` (0.2) and its
                               CIELAB hue angle (of the median a*, b*) in ``sky_hue_deg`` (180-330 deg:
                               cyan to violet; a clear sky is blue, Rayleigh scattering)
sunlight colour                c_in within ``max_sun_duv`` (0.02) of the Planckian locus (CIE 1960 uv)
                               and its CCT in ``sun_cct_k`` (2000-15000 K: sunset to blue-sky-lit cloud)
=============================  =========================================================================

The limits are calibrated on cases built from the bundled photos (``tests/test_sky_plausibility.py``; the
measures of each case: docs/stages/sky.md, "Which photos are refused").

A refused photo stops the job with what was found and what to do (a hand-painted mask, another photo),
unless ``photos.<name>.accept_unusual: true``: then the findings become warnings in sun.yaml and the fit.

References
----------
-   Dobashi, Y., Iwasaki, W., Ono, A., Yamamoto, T., Yue, Y., & Nishita, T. (2012). An inverse problem approach
    for automatically adjusting the parameters for rendering clouds using photographs. ACM Transactions on
    Graphics, 31(6).
-   Otsu, N. (1979). A threshold selection method from gray-level histograms. IEEE Transactions on Systems, Man,
    and Cybernetics, 9(1), 62–66.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from natscene.color import cct_duv, linear_srgb_to_lab
from natscene.sky.segmentation import CLOUD, SKY, saturation

__all__ = ["PlausibilityLimits", "negative_values", "measure", "findings"]


@dataclass
class PlausibilityLimits:
    """Limits of the checks (config ``sky.checks``; no defaults here: workflow/schemas/sky.schema.yaml's are the
    only ones, :func:`natscene.config.settings_from_section`)."""

    min_sky_fraction: float
    min_cloud_fraction: float
    max_cloud_to_sky_saturation: float
    min_sky_saturation: float
    sky_hue_deg: tuple
    sun_cct_k: tuple
    max_sun_duv: float

    SCHEMA = (("sky.schema.yaml", ("checks",)),)


def negative_values(photo: np.ndarray) -> dict | None:
    """Counts of negative values of a linear photo (None when there are none)."""
    a = np.asarray(photo)
    neg = a < 0
    if not neg.any():
        return None
    px = neg.any(axis=-1) if a.ndim == 3 else neg
    return {"pixels": int(px.sum()), "fraction": float(px.mean()), "min": float(a.min())}


def measure(photo: np.ndarray, labels: np.ndarray, c_in: np.ndarray) -> dict:
    """The numbers the checks compare (also written to sun.yaml under ``plausibility``)."""
    photo = np.clip(np.asarray(photo, np.float32), 0.0, None)
    sky, cloud = labels == SKY, labels == CLOUD
    n = labels.size
    s, _ = saturation(photo)
    out = {"sky_fraction": float(sky.sum() / n), "cloud_fraction": float(cloud.sum() / n)}
    if sky.any():
        out["sky_saturation"] = float(np.median(s[sky]))
        lab = linear_srgb_to_lab(photo[sky])
        a, b = float(np.median(lab[:, 1])), float(np.median(lab[:, 2]))
        out["sky_hue_deg"] = float(np.degrees(np.arctan2(b, a)) % 360.0)
    if cloud.any():
        out["cloud_saturation"] = float(np.median(s[cloud]))
    if sky.any() and cloud.any():
        out["cloud_to_sky_saturation"] = out["cloud_saturation"] / max(out["sky_saturation"], 1e-6)
    cct, duv = cct_duv(c_in)
    out["sun_cct_k"], out["sun_duv"] = cct, duv
    return out


def _in(value, lo_hi) -> bool:
    return lo_hi[0] <= value <= lo_hi[1]


def findings(m: dict, limits: PlausibilityLimits, hand_labelled: bool = False) -> list[str]:
    """What is implausible about a measured segmentation (empty: a usable cloud photo).

    ``hand_labelled``: every pixel was labelled by a hand-painted mask, so the colour of the classes is
    the user's decision and only the fractions and the sunlight colour are checked.
    """
    out = []
    L = limits
    if m["sky_fraction"] < L.min_sky_fraction:
        out.append(f"too little sky: {100 * m['sky_fraction']:.1f}% of the image is sky (at least "
                   f"{100 * L.min_sky_fraction:g}% is needed to interpolate the sky behind the clouds)")
    if m["cloud_fraction"] < L.min_cloud_fraction:
        out.append(f"too little cloud: {100 * m['cloud_fraction']:.2f}% of the image is cloud (at least "
                   f"{100 * L.min_cloud_fraction:g}%)")
    if not hand_labelled:
        r = m.get("cloud_to_sky_saturation")
        if r is not None and r > L.max_cloud_to_sky_saturation:
            out.append(f"the 'cloud' pixels are not cloud-coloured: their median saturation C*ab/L* is "
                       f"{m['cloud_saturation']:.2f}, {r:.2f}x the sky's (a cloud is at most "
                       f"{L.max_cloud_to_sky_saturation:g}x; the photo may show no cloud, or the sky was split "
                       f"in two)")
        if "sky_saturation" in m and m["sky_saturation"] < L.min_sky_saturation:
            out.append(f"the 'sky' pixels are grey (median saturation C*ab/L* {m['sky_saturation']:.2f} < "
                       f"{L.min_sky_saturation:g}): no blue sky is visible, e.g. an overcast sky, so the sky "
                       f"cannot be told from the cloud by its chroma")
        elif "sky_hue_deg" in m and not _in(m["sky_hue_deg"], L.sky_hue_deg):
            out.append(f"the 'sky' pixels are not sky-coloured: their CIELAB hue is {m['sky_hue_deg']:.0f} deg "
                       f"(a clear sky lies in {L.sky_hue_deg[0]:g}-{L.sky_hue_deg[1]:g} deg, cyan to violet)")
    if abs(m["sun_duv"]) > L.max_sun_duv or not _in(m["sun_cct_k"], L.sun_cct_k):
        out.append(f"the sunlight colour c_in is far from daylight or sunset light: CCT {m['sun_cct_k']:.0f} K, "
                   f"Duv {m['sun_duv']:+.3f} (sunlight: {L.sun_cct_k[0]:g}-{L.sun_cct_k[1]:g} K within "
                   f"{L.max_sun_duv:g} of the Planckian locus)")
    return out
