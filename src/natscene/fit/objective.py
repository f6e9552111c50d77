"""
Objective function of the fit
=============================

Defines the objective O of Dobashi et al. (2012, Eq. 2) and the alternatives their §5.1 and §6 tried:

-   :func:`objective`: O between a synthetic image and the photograph over their cloud pixels.
-   :class:`Levels`: linear values to the n_L intensity levels of an encoding (:data:`ENCODINGS`).
-   :func:`histograms`: the normalised level histograms.
-   :func:`channel_distance`: the per-channel distance of two histograms by a metric (:data:`METRICS`,
    :data:`HISTOGRAM_METRICS`).

Eq. 2: ``O = 1/3 sum_{lambda=R,G,B} sum_{n=0}^{n_L-1} |h_cg(n, lambda) - h_usr(n, lambda)|`` where h_cg and
h_usr are the n_L-level histograms of the cloud pixels of the synthetic image and of the photograph, each
normalised by its number of pixels (so O is in [0, 2]).

Encoding (both images the same): by default a pixel's level is its 8-bit sRGB code,
``n = round(sRGB_encode(clip(L, 0, 1)) * (n_L - 1))`` with n_L = 256 — the levels an 8-bit photograph
stores, so the photo's histogram is exactly the histogram of its JPEG codes. ``encoding="linear"`` uses
``round(clip(L, 0, 1) * (n_L - 1))`` instead. Values are scene-linear in the photo's units (L_in scales the
synthetic image to them); values above 1 saturate to the top level as in a camera.

For speed the level of a value is looked up in a table indexed by ``sqrt(L)`` quantised to
``lut_size`` cells (fine where the sRGB curve is steep); a cell that straddles a level boundary takes the
level of its centre, so a value within ~1/(2*lut_size) (in sqrt scale) of a boundary may fall in the
neighbouring level. 8-bit photo codes sit at level centres and are always exact.

Metrics (all per channel, then averaged over R, G, B; all are distances: 0 = identical):
``difference`` (Eq. 2), the OpenCV ``compareHist`` metrics of §6 — ``correlation`` (1 - HISTCMP_CORREL),
``chi_square`` (HISTCMP_CHISQR with the photo as H1), ``intersection`` (1 - HISTCMP_INTERSECT),
``bhattacharyya`` (HISTCMP_BHATTACHARYYA) — ``emd`` (Earth Mover's Distance, ground distance |n - m| /
(n_L - 1), equal to ``cv2.EMD`` with DIST_L1 on 1-D signatures), and ``pixel_ssd``: the §5.1 pixel-by-pixel
squared difference of encoded values in [0, 1], averaged over the synthetic cloud pixels (only meaningful
when the target is an image of the same clouds, e.g. a synthetic target).

References
----------
-   Dobashi, Y., Iwasaki, W., Ono, A., Yamamoto, T., Yue, Y., & Nishita, T. (2012). An inverse problem approach
    for automatically adjusting the parameters for rendering clouds using photographs. ACM Transactions on
    Graphics, 31(6).
"""
from __future__ import annotations

import numpy as np

from natscene.color import linear_to_srgb

__all__ = ["ENCODINGS", "HISTOGRAM_METRICS", "METRICS", "Levels", "histograms", "channel_distance", "objective"]

ENCODINGS = ("srgb", "linear")
HISTOGRAM_METRICS = ("difference", "correlation", "chi_square", "intersection", "bhattacharyya", "emd")
METRICS = HISTOGRAM_METRICS + ("pixel_ssd",)


class Levels:
    """Map linear values to integer intensity levels 0..n_levels-1 in the chosen encoding (vectorised)."""

    def __init__(self, n_levels: int = 256, encoding: str = "srgb", lut_size: int = 8192):
        if encoding not in ENCODINGS:
            raise ValueError(f"encoding must be one of {ENCODINGS}, got {encoding!r}")
        if not 2 <= int(n_levels) <= 65536:
            raise ValueError(f"n_levels must be in 2..65536, got {n_levels}")
        self.n_levels = int(n_levels)
        self.encoding = encoding
        self.lut_size = int(lut_size)
        centres = ((np.arange(self.lut_size + 1) + 0.5) / self.lut_size) ** 2  # linear value at cell centres
        self.lut = self.exact(np.minimum(centres, 1.0)).astype(np.int32)

    def exact(self, linear: np.ndarray) -> np.ndarray:
        """The level by the encoding's formula, computed exactly (slow path, reference for tests)."""
        x = np.clip(np.asarray(linear, np.float64), 0.0, 1.0)
        e = linear_to_srgb(x).astype(np.float64) if self.encoding == "srgb" else x
        return np.rint(e * (self.n_levels - 1)).astype(np.int64)

    def __call__(self, linear: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
        """Levels (int32) of linear values via the sqrt-domain lookup table. ``linear`` is not modified."""
        v = np.clip(np.asarray(linear, np.float32), 0.0, 1.0)
        np.sqrt(v, out=v)
        v *= self.lut_size
        return np.take(self.lut, v.astype(np.int32), out=out)

    def encode(self, linear: np.ndarray) -> np.ndarray:
        """Encoded values in [0, 1] (level / (n_levels - 1))."""
        return self(linear).astype(np.float32) / (self.n_levels - 1)


def histograms(levels: np.ndarray, n_levels: int) -> np.ndarray:
    """Normalised histograms over the last axis: levels (..., N) int -> (..., n_levels) float64 summing to 1."""
    lv = np.asarray(levels)
    lead = lv.shape[:-1]
    n = lv.shape[-1]
    if n == 0:
        raise ValueError("histogram of zero pixels")
    m = int(np.prod(lead)) if lead else 1
    offs = (np.arange(m, dtype=np.int64) * n_levels).reshape(lead + (1,)) if lead else 0
    h = np.bincount((lv + offs).ravel(), minlength=m * n_levels).astype(np.float64)
    return h.reshape(lead + (n_levels,)) / n


def channel_distance(h: np.ndarray, target: np.ndarray, metric: str = "difference") -> np.ndarray:
    """Distance between normalised histograms ``h`` (..., n_L) and ``target`` (n_L,) (broadcast), per row.

    The photo's histogram is the ``target`` (H1 of OpenCV's compareHist).
    """
    h = np.asarray(h, np.float64)
    t = np.asarray(target, np.float64)
    if metric == "difference":
        return np.abs(h - t).sum(-1)
    if metric == "correlation":
        hc = h - h.mean(-1, keepdims=True)
        tc = t - t.mean(-1, keepdims=True)
        den = np.sqrt((hc * hc).sum(-1) * (tc * tc).sum(-1))
        num = (hc * tc).sum(-1)
        with np.errstate(divide="ignore", invalid="ignore"):
            corr = np.where(den > 0, num / np.where(den > 0, den, 1.0), 1.0)
        return 1.0 - corr
    if metric == "chi_square":
        nz = t > 0
        safe = np.where(nz, t, 1.0)
        return np.where(nz, (h - t) ** 2 / safe, 0.0).sum(-1)
    if metric == "intersection":
        return 1.0 - np.minimum(h, t).sum(-1)
    if metric == "bhattacharyya":
        n = h.shape[-1]
        s = np.sqrt(h * t).sum(-1)
        norm = np.sqrt(h.mean(-1) * t.mean(-1)) * n
        with np.errstate(divide="ignore", invalid="ignore"):
            r = np.where(norm > 0, s / np.where(norm > 0, norm, 1.0), 0.0)
        return np.sqrt(np.maximum(1.0 - r, 0.0))
    if metric == "emd":
        n = h.shape[-1]
        return np.abs(np.cumsum(h, -1) - np.cumsum(t, -1)).sum(-1) / (n - 1)
    raise ValueError(f"unknown histogram metric {metric!r}; choose one of {HISTOGRAM_METRICS}")


def objective(synthetic: np.ndarray, photo: np.ndarray, levels: Levels | None = None,
              metric: str = "difference") -> float:
    """O of Eq. 2 (or another metric) between the cloud pixels of two images: (N, 3) and (M, 3) linear RGB.

    For ``pixel_ssd`` both must hold the same N pixels in the same order.
    """
    levels = levels or Levels()
    s = np.asarray(synthetic, np.float32).reshape(-1, 3)
    p = np.asarray(photo, np.float32).reshape(-1, 3)
    if metric == "pixel_ssd":
        if s.shape != p.shape:
            raise ValueError("pixel_ssd needs the same pixels in both images")
        d = levels.encode(s) - levels.encode(p)
        return float((d.astype(np.float64) ** 2).mean())
    hs = histograms(levels(s.T), levels.n_levels)
    hp = histograms(levels(p.T), levels.n_levels)
    return float(channel_distance(hs, hp, metric).mean())
