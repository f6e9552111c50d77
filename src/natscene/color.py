"""Colour-space conversions: the one module that does them (DESIGN §2), with colour-science underneath.

Working space everywhere is linear sRGB / Rec. 709 primaries, D65 white, scene-referred float32.
"""
from __future__ import annotations

import colour
import numpy as np

#: Rec. 709 luminance weights of linear sRGB (the Y row of the sRGB -> XYZ matrix).
LUMA_709 = np.array([0.2126, 0.7152, 0.0722], dtype=np.float32)


def srgb_to_linear(encoded: np.ndarray) -> np.ndarray:
    """Decode sRGB-encoded values in [0, 1] to linear (IEC 61966-2-1 EOTF), float32."""
    return np.asarray(colour.cctf_decoding(np.asarray(encoded, np.float64), function="sRGB"), np.float32)


def linear_to_srgb(linear: np.ndarray) -> np.ndarray:
    """Encode linear values to sRGB (inverse EOTF); values are clipped to [0, 1] first."""
    x = np.clip(np.asarray(linear, np.float64), 0.0, 1.0)
    return np.asarray(colour.cctf_encoding(x, function="sRGB"), np.float32)


def luminance(rgb: np.ndarray) -> np.ndarray:
    """Relative luminance Y of linear sRGB (last axis = R, G, B)."""
    return np.asarray(rgb, np.float32)[..., :3] @ LUMA_709


def linear_srgb_to_xyz(rgb: np.ndarray) -> np.ndarray:
    """Linear sRGB -> CIE XYZ (D65)."""
    return np.asarray(colour.RGB_to_XYZ(np.asarray(rgb, np.float64), colour.RGB_COLOURSPACES["sRGB"],
                                        apply_cctf_decoding=False), np.float32)


def xyz_to_linear_srgb(xyz: np.ndarray) -> np.ndarray:
    """CIE XYZ (D65) -> linear sRGB."""
    return np.asarray(colour.XYZ_to_RGB(np.asarray(xyz, np.float64), colour.RGB_COLOURSPACES["sRGB"],
                                        apply_cctf_encoding=False), np.float32)


def linear_srgb_to_lab(rgb: np.ndarray) -> np.ndarray:
    """Linear sRGB -> CIE L*a*b* (D65 white)."""
    xyz = linear_srgb_to_xyz(rgb)
    white = colour.CCS_ILLUMINANTS["CIE 1931 2 Degree Standard Observer"]["D65"]
    return np.asarray(colour.XYZ_to_Lab(xyz, white), np.float32)


def srgb_to_yiq(rgb: np.ndarray) -> np.ndarray:
    """RGB -> YIQ (NTSC) as used by Dong 2007 §3.5 for recolouring."""
    return np.asarray(colour.RGB_to_YIQ(np.asarray(rgb, np.float64)), np.float32)


def yiq_to_srgb(yiq: np.ndarray) -> np.ndarray:
    """YIQ (NTSC) -> RGB."""
    return np.asarray(colour.YIQ_to_RGB(np.asarray(yiq, np.float64)), np.float32)
