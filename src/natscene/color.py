"""
Colour-space conversions
========================

Defines the colour-space conversions of the project: the one module that does them (DESIGN §2), with
colour-science underneath:

-   :func:`srgb_to_linear`, :func:`linear_to_srgb`: the sRGB transfer function (IEC 61966-2-1) and its inverse.
-   :func:`luminance`, :data:`LUMA_709`: relative luminance Y of linear sRGB.
-   :func:`linear_srgb_to_xyz`, :func:`xyz_to_linear_srgb`, :func:`linear_srgb_to_lab`: CIE XYZ and CIE L*a*b*.
-   :func:`srgb_to_yiq`, :func:`yiq_to_srgb`: NTSC YIQ (Dong 2007, §3.5 works on display RGB).
-   :func:`cct_duv`: correlated colour temperature and Duv (Ohno's method).

Working space everywhere is linear sRGB / Rec. 709 primaries, D65 white, scene-referred float32.

References
----------
-   Dong, W. (2007). Rendering algorithms for natural scenes. PhD thesis, Université Henri Poincaré – Nancy 1.
-   IEC 61966-2-1:1999. Multimedia systems and equipment – Colour measurement and management – Part 2-1: Colour
    management – Default RGB colour space – sRGB.
-   Mansencal, T., Mauderer, M., Parsons, M., et al. Colour: Colour Science for Python (software).
    https://www.colour-science.org
-   Ohno, Y. (2014). Practical use and calculation of CCT and Duv. LEUKOS, 10(1), 47–55.
"""
from __future__ import annotations

import numpy as np

__all__ = ["srgb_to_linear", "linear_to_srgb", "luminance", "LUMA_709", "linear_srgb_to_xyz", "xyz_to_linear_srgb",
           "linear_srgb_to_lab", "srgb_to_yiq", "yiq_to_srgb", "cct_duv"]

#: Rec. 709 luminance weights of linear sRGB (the Y row of the sRGB -> XYZ matrix).
LUMA_709 = np.array([0.2126, 0.7152, 0.0722], dtype=np.float32)


def srgb_to_linear(encoded: np.ndarray) -> np.ndarray:
    """Decode sRGB-encoded values in [0, 1] to linear (IEC 61966-2-1 EOTF), float32."""
    import colour
    return np.asarray(colour.cctf_decoding(np.asarray(encoded, np.float64), function="sRGB"), np.float32)


def linear_to_srgb(linear: np.ndarray) -> np.ndarray:
    """Encode linear values to sRGB (inverse EOTF); values are clipped to [0, 1] first."""
    import colour
    x = np.clip(np.asarray(linear, np.float64), 0.0, 1.0)
    return np.asarray(colour.cctf_encoding(x, function="sRGB"), np.float32)


def luminance(rgb: np.ndarray) -> np.ndarray:
    """Relative luminance Y of linear sRGB (last axis = R, G, B)."""
    return np.asarray(rgb, np.float32)[..., :3] @ LUMA_709


def linear_srgb_to_xyz(rgb: np.ndarray) -> np.ndarray:
    """Linear sRGB -> CIE XYZ (D65)."""
    import colour
    return np.asarray(colour.RGB_to_XYZ(np.asarray(rgb, np.float64), colour.RGB_COLOURSPACES["sRGB"],
                                        apply_cctf_decoding=False), np.float32)


def xyz_to_linear_srgb(xyz: np.ndarray) -> np.ndarray:
    """CIE XYZ (D65) -> linear sRGB."""
    import colour
    return np.asarray(colour.XYZ_to_RGB(np.asarray(xyz, np.float64), colour.RGB_COLOURSPACES["sRGB"],
                                        apply_cctf_encoding=False), np.float32)


def linear_srgb_to_lab(rgb: np.ndarray) -> np.ndarray:
    """Linear sRGB -> CIE L*a*b* (D65 white)."""
    import colour
    xyz = linear_srgb_to_xyz(rgb)
    white = colour.CCS_ILLUMINANTS["CIE 1931 2 Degree Standard Observer"]["D65"]
    return np.asarray(colour.XYZ_to_Lab(xyz, white), np.float32)


#: NTSC 1953 RGB -> YIQ matrix (FCC; Y row = Rec. 601 luma), used by Dong 2007 §3.5 for recolouring.
#: colour-science 0.4.7 has no YIQ conversion, so the matrix is given here.
RGB_TO_YIQ = np.array([[0.299, 0.587, 0.114],
                       [0.595716, -0.274453, -0.321263],
                       [0.211456, -0.522591, 0.311135]])
YIQ_TO_RGB = np.linalg.inv(RGB_TO_YIQ)


def srgb_to_yiq(rgb: np.ndarray) -> np.ndarray:
    """RGB -> YIQ (NTSC), applied to the values given (Dong 2007 §3.5 works on display RGB)."""
    return (np.asarray(rgb, np.float64) @ RGB_TO_YIQ.T).astype(np.float32)


def yiq_to_srgb(yiq: np.ndarray) -> np.ndarray:
    """YIQ (NTSC) -> RGB, the exact inverse of :func:`srgb_to_yiq`."""
    return (np.asarray(yiq, np.float64) @ YIQ_TO_RGB.T).astype(np.float32)


def cct_duv(rgb) -> tuple[float, float]:
    """Correlated colour temperature (K) and Duv (signed distance from the Planckian locus in CIE 1960 uv;
    positive = greener) of a linear sRGB colour, by Ohno (2013) through colour-science.

    Daylight and direct sunlight sit close to the locus (|Duv| < 0.01): about 5000-7000 K at midday,
    2000-3500 K near sunset (CIE 15:2004; Wyszecki & Stiles 1982).
    """
    import colour
    import warnings

    xyz = linear_srgb_to_xyz(np.asarray(rgb, np.float32).reshape(3)).astype(np.float64)
    uv = colour.UCS_to_uv(colour.XYZ_to_UCS(xyz))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        cct, duv = colour.uv_to_CCT(uv, method="Ohno 2013")
    return float(cct), float(duv)
