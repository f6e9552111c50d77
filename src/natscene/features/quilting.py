"""Feature-preserved hierarchical quilting

The second synthesis method of Dong (2007, §6.6.1; Fig. 6.12, Fig. 6.15), :func:`quilt`, the thesis' faster
alternative to texture optimisation, after the hierarchical image quilting of Wang et al.
(2004) for example-based painting:

1. the output is cut into regular cells of the largest patch size (32 x 32);
2. each cell is split into four equal cells, recursively, until the target feature map varies by no more than a
   tolerance inside every cell (a hierarchy of cells of different sizes; tight types split mixed cells too);
3. the cells are synthesised in depth-first order, the cells of one level from bottom to top and left to right,
   each by copying an example block of the cell's size plus an overlap band on every side, chosen by the error

       e(v) = alpha e_overlap(v) + (1 - alpha) e_feature(v)

   with e_overlap the mean squared colour difference between the block and the already synthesised pixels it
   overlaps (image quilting, Efros & Freeman 2001) and e_feature the mean squared difference between the block's
   example feature map and the target feature map at the cell's new pixels (both per pixel and channel, so that
   alpha weighs means). As in image quilting a block is drawn at random among those within (1 + epsilon) of the
   best error, and it is pasted along the minimum-cost seam through the overlap: a graph cut (Kwatra et al. 2003,
   PyMaxflow) whose edge costs are the colour differences |A(s) - B(s)| + |A(t) - B(t)| of old and new pixels.

Both error maps over all example positions come from OpenCV's masked ``matchTemplate`` (squared differences).
Types: ``soft`` adds the type map as a feature channel; ``tight`` takes a block only among those whose example
types agree best with the target's over the cell's new pixels (a squared difference of labels: zero where every
type agrees).

References
----------
-   Dong, W. (2007). Rendering Algorithms for Natural Scenes. PhD thesis, Université Henri Poincaré - Nancy I,
    Ch. 6.
-   Efros, A. A., Freeman, W. T. (2001). Image quilting for texture synthesis and transfer. SIGGRAPH '01, 341-346.
-   Kwatra, V., Schödl, A., Essa, I., Turk, G., Bobick, A. (2003). Graph-cut textures: image and video synthesis
    using graph cuts. ACM TOG 22(3), 277-286.
-   Wang, B., Wang, W., Yang, H., Sun, J. (2004). Efficient example-based painting and synthesis of 2D directional
    texture. IEEE TVCG 10(3), 266-277.
"""
from __future__ import annotations

import time
from dataclasses import dataclass

import cv2
import maxflow
import numpy as np

from natscene.errors import InputError
from natscene.features.optimisation import Result
from natscene.features.type_map import check_types, soft_type_channels

__all__ = ["QuiltingSettings", "cells", "quilt"]


@dataclass(frozen=True)
class QuiltingSettings:
    """Hierarchical quilting (config ``textures.<name>.quilting``, and ``type_mode`` of
    ``textures.<name>.types.mode``; no defaults here: workflow/schemas/textures.schema.yaml's are the only ones,
    :func:`natscene.features.entry.quilting_settings`)."""

    alpha: float                  # weight of the overlap error; 1 - alpha weighs the feature error
    cell: int                     # the top-level cells: the largest patch
    min_cell: int                 # cells are not split below this
    tolerance: float              # largest spread of a target feature channel (grey units) inside one cell
    overlap: float                # the overlap band on each side, as a share of the cell (at least 2 pixels)
    epsilon: float                # blocks within (1 + epsilon) of the best error are candidates
    type_mode: str                # soft | tight
    seed: int

    CONFIG_NAMES = {"mode": "type_mode"}            # textures.<name>.types.mode
    SCHEMA = (("textures.schema.yaml", ("additionalProperties", "quilting")),
              ("textures.schema.yaml", ("additionalProperties", "types")))


def cells(target: np.ndarray, settings: QuiltingSettings, types: np.ndarray | None = None) -> list:
    """The cell hierarchy's leaves (y, x, h, w) in synthesis order (step 2 and 3 above): the top-level cells from
    the bottom row up and left to right, each split while a feature channel of ``target`` (H, W, k) spreads more
    than the tolerance in it (or, with ``types``, while it holds more than one type), depth first."""
    H, W = target.shape[:2]
    s = settings

    def uniform(y, x, h, w):
        blk = target[y:y + h, x:x + w].reshape(h * w, -1)
        flat = blk.shape[1] == 0 or float((blk.max(0) - blk.min(0)).max()) <= s.tolerance
        if types is not None:
            t = types[y:y + h, x:x + w]
            flat = flat and bool((t == t.flat[0]).all())
        return flat

    out = []

    def visit(y, x, h, w):
        if min(h, w) < 2 * s.min_cell or uniform(y, x, h, w):
            out.append((y, x, h, w))
            return
        h1, w1 = h // 2, w // 2
        for cy, ch in ((y + h1, h - h1), (y, h1)):        # the bottom half first
            for cx, cw in ((x, w1), (x + w1, w - w1)):    # then left to right
                visit(cy, cx, ch, cw)

    for y in sorted(range(0, H, s.cell), reverse=True):
        for x in range(0, W, s.cell):
            visit(y, x, min(s.cell, H - y), min(s.cell, W - x))
    return out


def _seam(old: np.ndarray, new: np.ndarray, filled: np.ndarray, keep_old: np.ndarray) -> np.ndarray:
    """Boolean (h, w): the pixels that take the new block, from a minimum cut through the filled overlap.

    Unfilled pixels must take the new block, ``keep_old`` pixels (the filled ones on the region's border that
    touch synthesised pixels outside it) the old; a cut between neighbours s, t costs |A(s)-B(s)| + |A(t)-B(t)|."""
    d = np.sqrt(np.sum((old - new) ** 2, -1)) * filled
    g = maxflow.Graph[float]()
    ids = g.add_grid_nodes(d.shape)
    # a seam beside an unfilled pixel counts the filled side twice (else it would be half price)
    right = np.zeros_like(d)
    right[:, :-1] = (d[:, :-1] + d[:, 1:]) * np.where(filled[:, :-1] & filled[:, 1:], 1.0, 2.0)
    down = np.zeros_like(d)
    down[:-1] = (d[:-1] + d[1:]) * np.where(filled[:-1] & filled[1:], 1.0, 2.0)
    g.add_grid_edges(ids, weights=right + 1e-6, structure=np.array([[0, 0, 0], [0, 0, 1], [0, 0, 0]]),
                     symmetric=True)
    g.add_grid_edges(ids, weights=down + 1e-6, structure=np.array([[0, 0, 0], [0, 0, 0], [0, 1, 0]]),
                     symmetric=True)
    big = 1e9
    g.add_grid_tedges(ids, np.where(~filled, big, 0.0), np.where(keep_old, big, 0.0))
    g.maxflow()
    return ~g.get_grid_segments(ids)  # source side: the new block


def quilt(example: np.ndarray, size: tuple, example_features: np.ndarray | None = None,
          target_features: np.ndarray | None = None, settings: QuiltingSettings | None = None,
          example_types: np.ndarray | None = None, target_types: np.ndarray | None = None, log=None) -> Result:
    """An output of ``size`` (height, width) from ``example`` (H, W, C) in [0, 1] by hierarchical quilting.

    The arguments are those of :func:`natscene.features.optimisation.synthesise`; the result's ``energies`` hold
    one entry (0, cell size, the summed error e of the chosen blocks); ``settings``: None: the schema's defaults."""
    from natscene.config import default_settings
    s = settings if settings is not None else default_settings(QuiltingSettings)
    log = log or (lambda msg: None)
    t_start = time.perf_counter()
    ex = np.asarray(example, np.float32)
    ex = ex[..., None] if ex.ndim == 2 else ex
    H, W = int(size[0]), int(size[1])
    fe = np.zeros(ex.shape[:2] + (0,), np.float32) if example_features is None else \
        np.asarray(example_features, np.float32).reshape(ex.shape[0], ex.shape[1], -1)
    ft = np.zeros((H, W, 0), np.float32) if target_features is None else \
        np.asarray(target_features, np.float32).reshape(H, W, -1)
    if fe.shape[2] != ft.shape[2]:
        raise InputError(f"feature maps: the example has {fe.shape[2]} channels, the target {ft.shape[2]}")
    if s.type_mode not in ("soft", "tight"):
        raise InputError(f"type_mode {s.type_mode!r}: soft or tight")
    if not 0.0 <= s.alpha <= 1.0:
        raise InputError(f"quilting alpha {s.alpha}: between 0 and 1")
    tight = example_types is not None and s.type_mode == "tight"
    if example_types is not None and not tight:
        fe, ft = soft_type_channels(fe, ft, example_types, target_types)
    te, tt = (a.astype(np.float32) for a in check_types(example_types, target_types)) if tight else (None, None)
    ov_max = max(2, int(round(s.overlap * s.cell)))
    if s.cell + 2 * ov_max > min(ex.shape[:2]):
        raise InputError(f"quilting: a {s.cell}-pixel cell with its overlap ({s.cell + 2 * ov_max} pixels) does "
                         f"not fit in the {ex.shape[1]}x{ex.shape[0]} example")
    if min(H, W) < s.min_cell:
        raise InputError(f"output {W}x{H} is smaller than the smallest cell {s.min_cell}")
    rng = np.random.default_rng(s.seed)
    out = np.zeros((H, W, ex.shape[2]), np.float32)
    src = np.full((H, W, 2), -1, np.int32)
    filled = np.zeros((H, W), bool)
    leaves = cells(ft, s, tt)
    total, t_match, t_cut = 0.0, 0.0, 0.0
    for y, x, h, w in leaves:
        ov = max(2, int(round(s.overlap * min(h, w))))
        y0, y1, x0, x1 = max(0, y - ov), min(H, y + h + ov), max(0, x - ov), min(W, x + w + ov)
        rh, rw = y1 - y0, x1 - x0
        old, done = out[y0:y1, x0:x1], filled[y0:y1, x0:x1]
        t0 = time.perf_counter()
        err = np.zeros((ex.shape[0] - rh + 1, ex.shape[1] - rw + 1), np.float32)
        if done.any() and s.alpha > 0:
            m = done.astype(np.float32)
            e = cv2.matchTemplate(ex, old, cv2.TM_SQDIFF, mask=np.repeat(m[..., None], ex.shape[2], -1))
            err += s.alpha * np.maximum(e, 0) / (m.sum() * ex.shape[2])
        if ft.shape[2] and s.alpha < 1:
            m = (~done).astype(np.float32)
            e = cv2.matchTemplate(fe, ft[y0:y1, x0:x1], cv2.TM_SQDIFF,
                                  mask=np.repeat(m[..., None], ft.shape[2], -1))
            err += (1 - s.alpha) * np.maximum(e.reshape(err.shape), 0) / (max(m.sum(), 1) * ft.shape[2])
        if tight:  # only the blocks whose types agree best with the target's over the new pixels
            m = (~done).astype(np.float32)
            wrong = cv2.matchTemplate(te, tt[y0:y1, x0:x1], cv2.TM_SQDIFF, mask=m)
            err[wrong > wrong.min() + 0.5] = np.inf
        best = float(err.min())
        cand = np.flatnonzero(err.ravel() <= best * (1 + s.epsilon) + 1e-12)
        py, px = np.unravel_index(int(cand[rng.integers(len(cand))]), err.shape)
        total += best
        t1 = time.perf_counter()
        block = ex[py:py + rh, px:px + rw]
        if done.any():
            border = np.zeros((rh, rw), bool)
            border[0, :], border[-1, :], border[:, 0], border[:, -1] = y0 > 0, y1 < H, x0 > 0, x1 < W
            take = _seam(old, block, done, done & border)
        else:
            take = np.ones((rh, rw), bool)
        t_cut += time.perf_counter() - t1
        t_match += t1 - t0
        old[take] = block[take]
        yy, xx = np.nonzero(take)
        src[y0 + yy, x0 + xx] = np.stack([py + yy, px + xx], -1)
        done |= True
    log(f"hierarchical quilting: {len(leaves)} cells ({W}x{H}), block search {t_match:.1f} s, seams {t_cut:.1f} s")
    return Result(image=np.clip(out, 0.0, 1.0), source=src, energies=[(0, s.cell, total)],
                  timings={"search_s": t_match, "seam_s": t_cut, "total_s": time.perf_counter() - t_start})
