"""
Preview labels
==============

Defines the text labels on preview images (contact sheets, pattern sheets): the one label painter of the project:

-   :func:`label`: paint a line of text on an 8-bit RGB image in one of :data:`STYLES`.

:func:`label` paints a line of text with OpenCV's Hershey simplex font (anti-aliased) on an 8-bit RGB image, in
one of three looks:

- ``"outlined"`` (default): white text in a black outline a pixel wide (the text's own shape grown by a 3 x 3
  dilation), readable on any tile;
  the font scale grows with the image height, max(0.4, H / 600), the stroke with the scale (the fit's contact
  sheet, :mod:`natscene.fit.report`);
- ``"table"``: thin yellow text, font scale max(0.3, W / 640) from the image width (the contact sheet of the
  precomputed tables, :mod:`natscene.scatter.contact`);
- ``"caption"``: thin white text at scale 0.5, vertically centred, for a caption cell beside a row (the
  pattern sheet, ``scripts/pattern_sheet.py``).
"""
from __future__ import annotations

import numpy as np

__all__ = ["label", "STYLES"]

STYLES = ("outlined", "table", "caption")
WHITE, BLACK, YELLOW = (255, 255, 255), (0, 0, 0), (255, 255, 0)


def label(image: np.ndarray, text: str, style: str = "outlined") -> np.ndarray:
    """``image`` (H, W, 3) uint8 with ``text`` painted near its top-left corner (``caption``: its left middle).

    Painted in place when ``image`` is C-contiguous (else on a contiguous copy); the painted array is returned."""
    import cv2

    if style not in STYLES:
        raise ValueError(f"unknown label style {style!r} (one of {', '.join(STYLES)})")
    out = np.ascontiguousarray(image)
    h, w = out.shape[:2]
    font, aa = cv2.FONT_HERSHEY_SIMPLEX, cv2.LINE_AA
    if style == "outlined":
        scale = max(0.4, h / 600.0)
        thick = max(1, int(round(2 * scale)))
        org = (5, int(24 * scale) + 5)
        # the black outline is the white text grown by a pixel (a thicker putText advances its glyphs further,
        # so its letters drift right of the white ones, a ghost letter at the end)
        text_mask = np.zeros((h, w), np.uint8)
        cv2.putText(text_mask, text, org, font, scale, 255, thick, aa)
        outline = cv2.dilate(text_mask, np.ones((3, 3), np.uint8))
        for mask, colour in ((outline, BLACK), (text_mask, WHITE)):
            a = mask[..., None].astype(np.float32) / 255.0
            out[...] = np.round(out * (1.0 - a) + np.asarray(colour, np.float32) * a).astype(np.uint8)
    elif style == "table":
        scale = max(0.3, w / 640)
        cv2.putText(out, text, (3, int(28 * scale)), font, scale, YELLOW, 1, aa)
    else:
        cv2.putText(out, text, (6, h // 2 + 5), font, 0.5, WHITE, 1, aa)
    return out
