"""
Junction removal by graph cut
=============================

Defines the junction removal of Dong 2007, §5.2, Fig. 5.2(b): matching patches merged into the intermediate
tile by graph-cut seams constrained to a circle (Ng et al. 2005; seam costs of Kwatra et al. 2003):

-   :func:`build_tile`: the §5.2 construction of one tile (best patch, then refinement by further merges).
-   :func:`merge`: one circle-constrained merge of a patch into a tile given as arrays.
-   :func:`intermediate_offsets`, :func:`render`: the source map of an intermediate tile, and the tile of a
    source map.
-   :func:`constraint_masks`, :func:`axis_weights`: the pinned and free regions, and the per-direction seam
    prices.
-   :func:`seam_energy`, :func:`tile_energy`, :func:`array_pair_values`: seam energies.
-   :func:`junction_extensions`: the four sample patches continued past their quarter edges.

A tile is a *source map*: every pixel is a pixel of the example, ``example[y + oy, x + ox]`` with a
per-pixel offset (oy, ox). The intermediate tile has four offsets (its four patch quarters), so its
mid-lines are seams between different sources; a matching patch is one offset over the whole tile.

One merge is a two-label problem per pixel: A (keep the current tile) or B (take the matching patch).
Pixels outside the circle (radius s/2 - margin about the tile centre) are pinned to A, so every tile
border stays that of its sample patches and matches its neighbours. Every 4-neighbour pair (p, q) is
charged by the seam it leaves in the output, measured like Kwatra et al. 2003,
M = |X(p) - Y(p)| + |X(q) - Y(q)| for p taken from source X and q from source Y, each source *continued*
across the pair (a source is a whole example region, so it has a value at both pixels):

    E(A,A) = |Xp(p) - Xq(p)| + |Xp(q) - Xq(q)|   (0 inside one source; the old seam, e.g. the junction)
    E(A,B) = |Xp(p) - B(p)|  + |Xp(q) - B(q)|
    E(B,A) = |B(p) - Xq(p)|  + |B(q) - Xq(q)|,    E(B,B) = 0,

Xp, Xq: the current sources of p and q. By the triangle inequality E(A,A) + E(B,B) <= E(A,B) + E(B,A):
the energy is submodular (Kolmogorov and Zabih 2004) and one max-flow gives its exact minimum (the
two-label case of Kwatra's seam nodes). A continued source that falls outside the example costs
``UNKNOWN`` per term (the seam cannot be priced, so it is avoided).

:func:`build_tile` does the §5.2 construction: the best matching patch (smallest Eq. 5.1 error) is
merged with a small disc about the tile centre, where the four quarters meet, pinned to it (the cross
junction is always erased; the rest of the junction lines only where that lowers the seam energy);
then, as in Kwatra's iterative refinement, the next-best matching patches are merged one by one
(nothing pinned inside the circle) and each kept only if it lowers the total seam energy of the tile.
Keeping the straight mid-line junction of the intermediate tile (pairs across the mid-lines that still
hold their original quarters) is charged ``junction_weight`` times its seam price (default 3 in
:func:`natscene.tiles.construct.construct`; clipped to E(A,B) + E(B,A) so the energy stays submodular):
at equal Kwatra price a long straight line across the texture grain, repeated in every tile, is more
visible than the curved seams around a patch, and §5.2 asks for the junctions to be erased.
Forcing a band along the mid-lines to the patch instead, with seams priced on the intermediate tile as if it
were one image, lets the cut run straight beside the band (visible straight seams along the tiles' mid-lines
every tile size).

Optional gradient normalisation (Kwatra et al. 2003, ``normalise`` > 0): all terms of a pair divided by
eps + |Xp(q) - Xp(p)| + |Xq(q) - Xq(p)| + 2 |B(q) - B(p)| (the directional differences of the sources
along the pair), eps = ``normalise`` x its mean over the tile; one factor per pair keeps the energy
submodular. It moves seams into busy regions.

References
----------
-   Dong, W. (2007). Rendering algorithms for natural scenes. PhD thesis, Université Henri Poincaré – Nancy 1.
-   Kolmogorov, V., & Zabih, R. (2004). What energy functions can be minimized via graph cuts? IEEE Transactions
    on Pattern Analysis and Machine Intelligence, 26(2), 147–159.
-   Kwatra, V., Schödl, A., Essa, I., Turk, G., & Bobick, A. (2003). Graph-cut textures: image and video synthesis
    using graph cuts. ACM Transactions on Graphics, 22(3), 277–286.
-   Ng, T.-Y., Wen, C., Tan, T.-S., Zhang, X., & Kim, Y. J. (2005). Generating an ω-tile set for texture
    synthesis. Proceedings of Computer Graphics International 2005 (CGI'05), 177–184.
"""
from __future__ import annotations

import maxflow
import numpy as np

__all__ = ["build_tile", "merge", "intermediate_offsets", "render", "constraint_masks", "axis_weights",
           "seam_energy", "tile_energy", "array_pair_values", "junction_extensions"]

INF = 1e12
UNKNOWN = 2.0 * np.sqrt(3.0)     # cost of one term whose continued source lies outside the example


def constraint_masks(s: int, margin: float = 1.0, core: float = 2.0, region: str = "circle"):
    """(keep_tile, keep_patch) boolean masks (s, s): outside the free region, and the disc of radius
    ``core`` pixels about the tile centre (where the four quarters meet; at least the central 2x2
    pixels; ``core=None``: nothing). ``region="circle"``: the circle of radius s/2 - margin (§5.2);
    ``"square"``: everything but a band of ceil(margin) (at least 1) pixels along the tile border (the
    border pixels stay those of the sample patches, which is all the edge constraints need)."""
    yy, xx = np.mgrid[0:s, 0:s]
    c = (s - 1) / 2.0
    d2 = (yy - c) ** 2 + (xx - c) ** 2
    if region == "square":
        b = max(int(np.ceil(float(margin))), 1)
        inside = (yy >= b) & (yy < s - b) & (xx >= b) & (xx < s - b)
    elif region == "circle":
        r = s / 2.0 - float(margin)
        inside = d2 <= r * r
    else:
        raise ValueError(f"region must be 'circle' or 'square', got {region!r}")
    if core is None:
        return ~inside, np.zeros((s, s), bool)
    centre = d2 <= max(float(core), 0.75) ** 2
    return ~inside, centre & inside


# ------------------------------------------------------------------------------------------ source maps
def intermediate_offsets(genes: np.ndarray, corners, s: int) -> np.ndarray:
    """(s, s, 2) source offsets of the intermediate tile with corner colours ``corners`` (TL, TR, BL, BR
    indices into ``genes``, the patches' top-left (y, x) in the example)."""
    from natscene.tiles.tile_ga import quarter_layout
    h = s // 2
    off = np.empty((s, s, 2), np.int64)
    for q, ((sy, sx), (oy, ox)) in enumerate(quarter_layout(s)):
        gy, gx = np.asarray(genes)[corners[q]]
        off[oy:oy + h, ox:ox + h] = (gy + sy - oy, gx + sx - ox)
    return off


def _read(example: np.ndarray, ys, xs) -> np.ndarray:
    """example[ys, xs] (C last), NaN where outside."""
    H, W, C = example.shape
    ok = (ys >= 0) & (ys < H) & (xs >= 0) & (xs < W)
    out = np.full(ys.shape + (C,), np.nan)
    out[ok] = example[ys[ok], xs[ok]]
    return out


def render(example: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    """The tile (s, s, C) of a source map."""
    s = offsets.shape[0]
    yy, xx = np.mgrid[0:s, 0:s]
    return _read(example, yy + offsets[..., 0], xx + offsets[..., 1])


def _pair_values(example, offsets):
    """Per axis (1: pairs (y,x)-(y,x+1), 0: (y,x)-(y+1,x)): (A(p), A(q), Xp(q), Xq(p))."""
    s = offsets.shape[0]
    yy, xx = np.mgrid[0:s, 0:s]
    out = {}
    for axis in (1, 0):
        sp = (slice(None), slice(0, s - 1)) if axis == 1 else (slice(0, s - 1), slice(None))
        sq = (slice(None), slice(1, s)) if axis == 1 else (slice(1, s), slice(None))
        py, px, qy, qx = yy[sp], xx[sp], yy[sq], xx[sq]
        op, oq = offsets[sp], offsets[sq]
        out[axis] = (_read(example, py + op[..., 0], px + op[..., 1]),
                     _read(example, qy + oq[..., 0], qx + oq[..., 1]),
                     _read(example, qy + op[..., 0], qx + op[..., 1]),
                     _read(example, py + oq[..., 0], px + oq[..., 1]))
    return out


def _split(B: np.ndarray, axis: int):
    s = B.shape[0]
    return (B[:, :s - 1], B[:, 1:]) if axis == 1 else (B[:s - 1], B[1:])


def _dist(a, b):
    d = np.sqrt(((a - b) ** 2).sum(-1))
    return np.where(np.isfinite(d), d, UNKNOWN)


def axis_weights(example: np.ndarray) -> dict:
    """{axis: w}: the seam price across ``axis`` is multiplied by w = mean / mean_axis, where mean_axis
    is the example's mean neighbour difference |X(q) - X(p)| along that axis and mean the average of
    the two (Kwatra et al. 2003's gradient normalisation with the directional gradient averaged over the
    example instead of taken locally). A step across a direction in which the texture hardly varies
    (across the blades of upright grass: horizontal seams) is more visible than one of the same size
    across a direction of strong variation; isotropic textures get w = 1 on both axes."""
    ex = np.asarray(example, np.float64)
    if ex.ndim == 2:
        ex = ex[..., None]
    m = {1: float(np.sqrt(((ex[:, 1:] - ex[:, :-1]) ** 2).sum(-1)).mean()),
         0: float(np.sqrt(((ex[1:] - ex[:-1]) ** 2).sum(-1)).mean())}
    mean = 0.5 * (m[0] + m[1])
    if mean <= 0:
        return {0: 1.0, 1: 1.0}
    return {a: mean / max(v, 1e-3 * mean) for a, v in m.items()}


def _tables(values, B, normalise: float = 0.0, junction=None, junction_weight: float = 1.0,
            axis_weight=None):
    """Pair energies {axis: (E_AA, E_AB, E_BA)} (E_BB = 0) from :func:`_pair_values`-like ``values`` and
    the candidate patch B (s, s, C); ``axis_weight``: {axis: factor} of :func:`axis_weights`."""
    out, dens = {}, {}
    for axis, (Ap, Aq, Xp_q, Xq_p) in values.items():
        Bp, Bq = _split(B, axis)
        e_ab = _dist(Ap, Bp) + _dist(Xp_q, Bq)
        e_ba = _dist(Bp, Xq_p) + _dist(Bq, Aq)
        e_aa = _dist(Ap, Xq_p) + _dist(Xp_q, Aq)
        if axis_weight is not None:
            w = float(axis_weight[axis])
            e_ab, e_ba, e_aa = w * e_ab, w * e_ba, w * e_aa
        if junction is not None and junction_weight != 1.0:
            e_aa = np.where(junction[axis], junction_weight * e_aa, e_aa)
        e_aa = np.minimum(e_aa, e_ab + e_ba)     # unchanged unless UNKNOWN or weighted
        out[axis] = [e_aa, e_ab, e_ba]
        if normalise:
            dens[axis] = _dist(Xp_q, Ap) + _dist(Aq, Xq_p) + 2.0 * _dist(Bq, Bp)
    if normalise:
        eps = float(normalise) * np.mean(np.concatenate([d.ravel() for d in dens.values()]))
        for axis in out:
            out[axis] = [e / (dens[axis] + eps) for e in out[axis]]
    return {a: tuple(v) for a, v in out.items()}


def seam_energy(tables, use_b: np.ndarray) -> float:
    """Energy of a labelling (True = B) under pair tables."""
    total = 0.0
    for axis, (e_aa, e_ab, e_ba) in tables.items():
        p, q = _split(use_b, axis)
        total += float(np.where(~p & ~q, e_aa, 0).sum() + np.where(~p & q, e_ab, 0).sum()
                       + np.where(p & ~q, e_ba, 0).sum())
    return total


def _cut(tables, keep_a: np.ndarray, pin_b: np.ndarray) -> np.ndarray:
    """Exact minimiser (True = B) of the submodular pair energy with pinned pixels, by one max-flow.
    Source side = A (label 0), sink side = B (label 1); a node in the sink segment pays its source
    capacity, one in the source segment its sink capacity; edge p->q is cut when p in A and q in B.
    E(xp, xq) = E_AA + (E_BA - E_AA) xp + (E_BB - E_BA) xq + (E_AB + E_BA - E_AA - E_BB) (1 - xp) xq."""
    s = keep_a.shape[0]
    yy, xx = np.mgrid[0:s, 0:s]
    g = maxflow.Graph[float]()
    ids = g.add_grid_nodes((s, s))
    u_b = np.zeros((s, s))                       # unary cost of label B (may be negative)
    for axis, (e_aa, e_ab, e_ba) in tables.items():
        py, px = _split(yy, axis)[0].ravel(), _split(xx, axis)[0].ravel()
        qy, qx = (py, px + 1) if axis == 1 else (py + 1, px)
        aa, ab, ba = e_aa.ravel(), e_ab.ravel(), e_ba.ravel()
        g.add_edges(ids[py, px], ids[qy, qx], np.maximum(ab + ba - aa, 0.0), np.zeros(len(py)))
        np.add.at(u_b, (py, px), ba - aa)
        np.add.at(u_b, (qy, qx), -ba)
    src_cap = np.maximum(u_b, 0.0) + np.where(keep_a, INF, 0.0)
    snk_cap = np.maximum(-u_b, 0.0) + np.where(pin_b & ~keep_a, INF, 0.0)
    g.add_grid_tedges(ids, src_cap, snk_cap)
    g.maxflow()
    return g.get_grid_segments(ids)


# ------------------------------------------------------------------------------------------ merges
def junction_pairs(offsets: np.ndarray, original: np.ndarray):
    """{axis: bool} pairs across the mid-lines whose two pixels still hold their original (different)
    quarter sources: the straight junction of the intermediate tile, still present."""
    s = offsets.shape[0]
    h = s // 2
    out = {}
    for axis in (1, 0):
        same = (offsets == original).all(-1)
        sp, sq = _split(same, axis)
        op, oq = _split(original, axis)
        j = sp & sq & (op != oq).any(-1)
        line = np.zeros(j.shape, bool)
        if axis == 1:
            line[:, h - 1] = True
        else:
            line[h - 1] = True
        out[axis] = j & line
    return out


def merge_offsets(example: np.ndarray, offsets: np.ndarray, patch_yx, keep_a: np.ndarray,
                  pin_b: np.ndarray, normalise: float = 0.0, junction=None, junction_weight: float = 1.0,
                  axis_weight=None):
    """One graph-cut merge of the matching patch at ``patch_yx`` (its top-left in the example) into the
    tile given by its source map. Returns (new offsets, mask True where the patch is used, energy)."""
    ex = np.asarray(example, np.float64)
    s = offsets.shape[0]
    ty, tx = (int(v) for v in patch_yx)
    B = render(ex, np.broadcast_to(np.array([ty, tx]), (s, s, 2)))
    outside = ~np.isfinite(B).all(-1)            # a source continued past the example: not usable
    if (outside & pin_b).any():
        raise ValueError(f"matching patch at {patch_yx} does not cover the pinned centre")
    tables = _tables(_pair_values(ex, offsets), B, normalise, junction, junction_weight, axis_weight)
    use_b = _cut(tables, keep_a | outside, pin_b)
    new = np.where(use_b[..., None], np.array([ty, tx]), offsets)
    return new, use_b, seam_energy(tables, use_b)


def tile_energy(example: np.ndarray, offsets: np.ndarray, normalise: float = 0.0, axis_weight=None) -> float:
    """Total seam energy of a source map (sum of E(A,A) over all pairs), normalised the same way as
    a merge would with B = the tile itself."""
    ex = np.asarray(example, np.float64)
    vals = _pair_values(ex, offsets)
    tables = _tables(vals, render(ex, offsets), normalise, axis_weight=axis_weight)
    return seam_energy(tables, np.zeros(offsets.shape[:2], bool))


def build_tile(example: np.ndarray, offsets: np.ndarray, candidates, margin: float = 1.0,
               core: float = 2.0, normalise: float = 0.0, passes: int = 1, junction_weight: float = 1.0,
               region: str = "circle", axis_weight=None):
    """§5.2 junction removal on a source map: merge ``candidates[0]`` (the best matching patch) with the
    centre disc pinned, then each further candidate patch if it lowers the tile's seam energy.
    ``region``, ``axis_weight``: see :func:`constraint_masks`, :func:`axis_weights`.
    Returns (offsets, mask of pixels changed from the intermediate tile, energy, accepted candidates)."""
    ex = np.asarray(example, np.float64)
    s = offsets.shape[0]
    keep_a, pin_b = constraint_masks(s, margin, core, region)
    none = np.zeros((s, s), bool)
    jw = dict(junction_weight=junction_weight, axis_weight=axis_weight)
    cur, _, energy = merge_offsets(ex, offsets, candidates[0], keep_a, pin_b, normalise,
                                   junction_pairs(offsets, offsets), **jw)
    accepted = [tuple(int(v) for v in candidates[0])]
    for _ in range(passes):
        before = energy
        for cand in candidates[1:]:
            new, used, e = merge_offsets(ex, cur, cand, keep_a, none, normalise,
                                         junction_pairs(cur, offsets), **jw)
            if used.any() and e < energy - 1e-9:
                cur, energy = new, e
                accepted.append(tuple(int(v) for v in cand))
        if energy >= before - 1e-9:
            break
    changed = (cur != offsets).any(-1)
    return cur, changed, energy, accepted


def junction_extensions(example: np.ndarray, genes: np.ndarray, corners, s: int):
    """The four sample patches of an intermediate tile continued one pixel past their quarter edges:
    (left, right, top, bottom), each (s, C), NaN outside the example. ``left[y]``: the quarter left of
    the vertical mid-line at column s/2; ``right[y]``: the quarter right of it at column s/2 - 1;
    ``top[x]``/``bottom[x]``: the quarters above/below the horizontal mid-line at rows s/2 and s/2 - 1."""
    ex = np.asarray(example, np.float64)
    if ex.ndim == 2:
        ex = ex[..., None]
    off = intermediate_offsets(genes, corners, s)
    h = s // 2
    r = np.arange(s)
    left = _read(ex, r + off[:, h - 1, 0], h + off[:, h - 1, 1])
    right = _read(ex, r + off[:, h, 0], (h - 1) + off[:, h, 1])
    top = _read(ex, h + off[h - 1, :, 0], r + off[h - 1, :, 1])
    bottom = _read(ex, (h - 1) + off[h, :, 0], r + off[h, :, 1])
    return left, right, top, bottom


def array_pair_values(A: np.ndarray, ext=None):
    """:func:`_pair_values` for a tile given as an array (s, s, C): one source, except across the
    mid-lines when ``ext`` (see :func:`merge`) gives the quarters' continuations."""
    s, C = A.shape[0], A.shape[-1]
    h = s // 2
    values = {}
    for axis in (1, 0):
        Ap, Aq = _split(A, axis)
        Xp_q, Xq_p = Aq.copy(), Ap.copy()
        if ext is not None:
            left, right, top, bottom = (np.asarray(e, np.float64).reshape(s, C) for e in ext)
            if axis == 1:
                Xp_q[:, h - 1], Xq_p[:, h - 1] = left, right
            else:
                Xp_q[h - 1], Xq_p[h - 1] = top, bottom
        values[axis] = (Ap, Aq, Xp_q, Xq_p)
    return values


def merge(tile: np.ndarray, patch: np.ndarray, margin: float = 1.0, ext=None, core: float = 2.0,
          normalise: float = 0.0):
    """Merge ``patch`` into the intermediate ``tile`` (both (s, s, C) arrays) with the circle-constrained
    minimum-energy seam, the centre disc pinned to the patch.

    ``ext``: (left, right, top, bottom) of :func:`junction_extensions` (the quarters continued across the
    mid-lines); ``None``: the tile is treated as one image (no junction). Returns (merged tile, mask
    (s, s) True where the patch is used, seam energy of the result)."""
    A = np.asarray(tile, np.float64)
    B = np.asarray(patch, np.float64)
    if A.ndim == 2:
        A, B = A[..., None], B[..., None]
    if A.shape != B.shape or A.shape[0] != A.shape[1] or A.shape[0] % 2:
        raise ValueError(f"tile and patch must be the same even square shape, got {A.shape}, {B.shape}")
    s = A.shape[0]
    values = array_pair_values(A, ext)
    keep_a, pin_b = constraint_masks(s, margin, core)
    tables = _tables(values, B, normalise)
    use_b = _cut(tables, keep_a, pin_b)
    out = np.where(use_b[..., None], B, A)
    return out.astype(np.float32), use_b, seam_energy(tables, use_b)
