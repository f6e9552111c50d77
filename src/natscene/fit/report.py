"""
Reports of a fit
================

What a person looks at after a fit (Dobashi et al. 2012, §1, §4, Fig. 6): the photo beside the ranked
synthetic images (the user picks one, §1) and the convergence of the objective (best and mean O per
iteration, Fig. 6).

-   :func:`contact_sheet`: the photo and the ranked images, labelled, as one image.
-   :func:`convergence_plot`: the plot of the best and mean O per iteration.
-   :func:`convergence_csv`: the same as CSV text.

The contact sheet shows every image with the same exposure (1: the photo's own linear units, which are the
units the objective compares), through the shared preview tone map (``natscene.io.to_srgb8``), each tile
labelled with its rank and O.

References
----------
-   Dobashi, Y., Iwasaki, W., Ono, A., Yamamoto, T., Yue, Y., & Nishita, T. (2012). An inverse problem approach
    for automatically adjusting the parameters for rendering clouds using photographs. ACM Transactions on
    Graphics, 31(6).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from natscene.io import atomic_path, to_srgb8
from natscene.preview import label

__all__ = ["contact_sheet", "convergence_plot", "convergence_csv"]


def contact_sheet(photo: np.ndarray, images: list, labels: list, columns: int = 4, exposure: float = 1.0,
                  gap: int = 4, min_width: int = 240) -> np.ndarray:
    """uint8 (H', W', 3): the photo then the ranked images in a grid, same exposure, labelled.

    Tiles smaller than ``min_width`` pixels are enlarged (nearest neighbour) so the labels stay readable.
    """
    tiles = [to_srgb8(photo, exposure)] + [to_srgb8(im, exposure) for im in images]
    h, w = tiles[0].shape[:2]
    f = max(1, int(np.ceil(min_width / w)))
    tiles = [np.repeat(np.repeat(t, f, 0), f, 1) for t in tiles]
    tiles = [label(t, s) for t, s in zip(tiles, ["photo"] + list(labels))]
    h, w = h * f, w * f
    cols = min(columns, len(tiles))
    rows = int(np.ceil(len(tiles) / cols))
    sheet = np.full((rows * h + (rows + 1) * gap, cols * w + (cols + 1) * gap, 3), 32, np.uint8)
    for i, t in enumerate(tiles):
        r, c = divmod(i, cols)
        y, x = gap + r * (h + gap), gap + c * (w + gap)
        sheet[y:y + h, x:x + w] = t
    return sheet


def convergence_plot(path, best: np.ndarray, mean: np.ndarray, title: str = "", epsilon_o: float | None = None):
    """Write a PNG of best and mean O per iteration (atomically)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 3.6), dpi=100)
    it = np.arange(len(best))
    ax.plot(it, mean, color="0.6", label="population mean O")
    ax.plot(it, best, color="C0", lw=2, label="best O")
    if epsilon_o and epsilon_o > 0:
        ax.axhline(epsilon_o, color="C3", ls=":", lw=1, label=f"epsilon_O = {epsilon_o:g}")
    ax.set_xlabel("iteration")
    ax.set_ylabel("objective O (Eq. 2)")
    ax.set_ylim(bottom=0)
    ax.set_title(title)
    ax.grid(alpha=0.3)
    ax.legend()
    fig.tight_layout()
    path = Path(path)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png")
    plt.close(fig)


def convergence_csv(best: np.ndarray, mean: np.ndarray) -> str:
    lines = ["iteration,best_O,mean_O"]
    lines += [f"{i},{b:.6f},{m:.6f}" for i, (b, m) in enumerate(zip(best, mean))]
    return "\n".join(lines) + "\n"
