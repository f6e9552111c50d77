"""
Petal shape and venation
========================

Defines the petal shape and venation input of Dong (2007, §3.3.1):

-   :class:`Venation`: the vascular cells of a petal grid.
-   :func:`venation_from_nodes`: a vein tree rasterised onto the grid; :func:`radial_venation_spec`: a fan of
    veins in that format.
-   :func:`venation_from_photo`: a connected vein tree extracted from a photograph.
-   :func:`parametric_petal`: a procedural petal mask.

The shape is a black/white mask (petal = 1). The venation is "a set of vein nodes, including a vein root
and vein width": here a tree of nodes in normalised image coordinates (x right, y down, both in [0, 1]),
each with a relative width (1 = the main vein at the root) and a parent (-1 = the root). Edges are
rasterised as lines whose pixel thickness is ``max(1, width * vein_px)``; every vascular pixel keeps its
vein width ``w`` (used by the transport function, Eq. 3.1) and its path length to the root along the
vein (``dist``, pixels; used for the non-adjacent vascular connections of Eq. 3.1c).

A venation can also be extracted from a photograph (§3.5: "we ... extract the shape and venation
information"): a multi-scale ridge filter (Sato tubeness, scikit-image) of log-luminance with local contrast
normalisation, a threshold at a percentile inside the petal and skeletonisation give vein pieces; one
minimum-cost-path run from the vein root over a cost that is low on strong ridges, traced back from every
piece's tips, joins them into one tree rooted at the root (``venation_from_photo``); the vein width comes
from the distance transform of the thresholded ridge mask.

``parametric_petal`` draws a petal outline procedurally: in polar coordinates around the base,
``r(phi) = L * sin(pi * s)^p * (1 + notch * cos(2 pi * lobes * s))`` with ``s`` the normalised opening
angle, giving the rounded, slightly lobed shapes of Fig. 3.3 (petunia) and the daisy of Fig. 3.5.

References
----------
-   Dong, W. (2007). Rendering Algorithms for Natural Scenes. PhD thesis, Université Henri Poincaré - Nancy I.
-   Sato, Y., Nakajima, S., Shiraga, N., Atsumi, H., Yoshida, S., Koller, T., Gerig, G., & Kikinis, R. (1998).
    Three-dimensional multi-scale line filter for segmentation and visualization of curvilinear structures in
    medical images. Medical Image Analysis, 2(2), 143–168.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import ndimage

from natscene.errors import InputError

__all__ = ["Venation", "parametric_petal", "venation_from_nodes", "radial_venation_spec", "venation_from_photo"]


@dataclass
class Venation:
    """Vascular cells of a petal grid: mask (H, W) bool, width (H, W) float (0 off-vein),
    dist (H, W) path length to the root along the veins (inf off-vein), root (row, col)."""

    vascular: np.ndarray
    width: np.ndarray
    dist: np.ndarray
    root: tuple[int, int]
    #: centreline of every root-to-tip vein path as (K, 2) int arrays of (row, col), 1-pixel steps; used for
    #: the non-adjacent vascular connections of Eq. 3.1c. None when unknown (photo-extracted venation).
    paths: list | None = None

    @classmethod
    def empty(cls, shape, root=(0, 0)) -> "Venation":
        return cls(np.zeros(shape, bool), np.zeros(shape, np.float32), np.full(shape, np.inf, np.float32),
                   tuple(int(v) for v in root))


def parametric_petal(height: int, width: int, base=(0.5, 0.95), length: float = 0.9,
                     opening_deg: float = 80.0, roundness: float = 0.6, lobes: int = 0,
                     notch: float = 0.0) -> np.ndarray:
    """A procedural petal mask (H, W) float32 in {0, 1}: polar outline around ``base`` (x, y normalised),
    opening upward (toward y = 0); see module docstring for the outline function."""
    yy, xx = np.mgrid[0:height, 0:width].astype(np.float64)
    bx, by = base[0] * (width - 1), base[1] * (height - 1)
    dx, dy = xx - bx, by - yy  # up is +dy
    r = np.hypot(dx, dy)
    phi = np.degrees(np.arctan2(dx, dy))  # 0 = straight up
    half = opening_deg / 2.0
    s = np.clip((phi + half) / opening_deg, 0.0, 1.0)
    scale = length * min(height, width) if height < width else length * height
    outline = scale * np.sin(np.pi * s) ** roundness * (1.0 + notch * np.cos(2 * np.pi * lobes * s))
    inside = (np.abs(phi) <= half) & (r <= outline)
    inside |= r <= 1.5  # the base pixel itself
    return inside.astype(np.float32)


def _draw_segment(shape, p0, p1, w0, w1, px):
    """Pixels (rows, cols) and widths along a thick segment from p0 to p1 (pixel coords, (x, y))."""
    h, w = shape
    n = int(np.ceil(np.hypot(p1[0] - p0[0], p1[1] - p0[1]))) * 2 + 2
    s = np.linspace(0.0, 1.0, n)
    xs = p0[0] + (p1[0] - p0[0]) * s
    ys = p0[1] + (p1[1] - p0[1]) * s
    ws = w0 + (w1 - w0) * s
    rows, cols, widths, along = [], [], [], []
    seglen = float(np.hypot(p1[0] - p0[0], p1[1] - p0[1]))
    rad = np.maximum(1.0, ws * px) / 2.0
    rmax = int(np.ceil(rad.max()))
    offs = np.arange(-rmax, rmax + 1)
    ox, oy = np.meshgrid(offs, offs)
    ox, oy = ox.ravel(), oy.ravel()
    dd = np.hypot(ox, oy)
    X = np.rint(xs[:, None] + ox[None]).astype(int)
    Y = np.rint(ys[:, None] + oy[None]).astype(int)
    keep = (dd[None] <= np.maximum(rad[:, None], 0.5)) & (X >= 0) & (X < w) & (Y >= 0) & (Y < h)
    W = np.broadcast_to(ws[:, None], X.shape)
    A = np.broadcast_to((s * seglen)[:, None], X.shape)
    return Y[keep], X[keep], W[keep], A[keep]


def venation_from_nodes(shape, spec: dict, vein_px: float = 3.0, key: str = "venation") -> Venation:
    """Rasterise a vein tree ``{root: [x, y], root_width: w, nodes: [{xy: [x, y], width: w, parent: i}]}``
    (normalised coordinates; ``parent`` -1 = the root) onto a grid of ``shape`` (H, W)."""
    h, w = shape
    try:
        root = np.asarray(spec["root"], float)
        nodes = spec.get("nodes", [])
        root_w = float(spec.get("root_width", 1.0))
    except (KeyError, TypeError) as e:
        raise InputError(f"config key '{key}': needs 'root' [x, y] and 'nodes' ({e})") from None
    pts = [root] + [np.asarray(n["xy"], float) for n in nodes]
    wid = [root_w] + [float(n.get("width", 0.5)) for n in nodes]
    par = [-2] + [int(n.get("parent", -1)) + 1 for n in nodes]  # index into pts
    for i, p in enumerate(par[1:], start=1):
        if not 0 <= p < len(pts) or p == i:
            raise InputError(f"config key '{key}.nodes[{i - 1}].parent': {p - 1} is not a valid node index")
    to_px = lambda q: np.array([q[0] * (w - 1), q[1] * (h - 1)])
    # path length from the root to every node (pixels)
    node_dist = np.zeros(len(pts))
    order = sorted(range(1, len(pts)), key=lambda i: _depth(i, par))
    for i in order:
        node_dist[i] = node_dist[par[i]] + np.linalg.norm(to_px(pts[i]) - to_px(pts[par[i]]))
    width = np.zeros(shape, np.float32)
    dist = np.full(shape, np.inf, np.float32)
    for i in range(1, len(pts)):
        j = par[i]
        r, c, ww, along = _draw_segment(shape, to_px(pts[j]), to_px(pts[i]), wid[j], wid[i], vein_px)
        np.maximum.at(width, (r, c), ww.astype(np.float32))
        np.minimum.at(dist, (r, c), (node_dist[j] + along).astype(np.float32))
    rootpx = to_px(root)
    root_rc = (int(np.clip(round(rootpx[1]), 0, h - 1)), int(np.clip(round(rootpx[0]), 0, w - 1)))
    vas = width > 0
    return Venation(vas, width, dist, root_rc, _centre_paths(shape, pts, par, to_px))


def _centre_paths(shape, pts, par, to_px):
    """Root-to-tip centrelines (row, col) of the vein tree, one pixel per step, clipped to the grid."""
    h, w = shape
    kids = {i: [] for i in range(len(pts))}
    for i, p in enumerate(par[1:], start=1):
        kids[p].append(i)
    out, stack = [], [(0, [np.rint(to_px(pts[0]))[None].astype(int)])]
    while stack:
        i, acc = stack.pop()
        if not kids[i]:
            P = np.concatenate(acc)[:, ::-1]  # (x, y) -> (row, col)
            P = P[np.r_[True, np.any(P[1:] != P[:-1], axis=1)]]
            P = P[(P[:, 0] >= 0) & (P[:, 0] < h) & (P[:, 1] >= 0) & (P[:, 1] < w)]
            out.append(P)
            continue
        for j in kids[i]:
            p0, p1 = to_px(pts[i]), to_px(pts[j])
            n = int(np.ceil(np.linalg.norm(p1 - p0))) + 1
            s = np.linspace(0.0, 1.0, n)[1:, None]
            stack.append((j, acc + [np.rint(p0 + (p1 - p0) * s).astype(int)]))
    return out


def _depth(i, par):
    d = 0
    while par[i] >= 1:
        i = par[i]
        d += 1
    return d


def radial_venation_spec(n_veins: int = 7, base=(0.5, 0.95), length: float = 0.85, opening_deg: float = 70.0,
                         branch: bool = True, root_width: float = 1.0, tip_width: float = 0.3) -> dict:
    """A fan of primary veins from the base (and one fork each), in the format of
    :func:`venation_from_nodes`: the palmate/radial venation of a petunia petal."""
    nodes = []
    for k in range(n_veins):
        a = np.radians(-opening_deg / 2 + opening_deg * (k + 0.5) / n_veins)
        mid_r = length * 0.45
        mid = [base[0] + mid_r * np.sin(a), base[1] - mid_r * np.cos(a)]
        tip = [base[0] + length * np.sin(a) * 0.95, base[1] - length * np.cos(a) * 0.95]
        nodes.append({"xy": mid, "width": 0.5 * (root_width + tip_width), "parent": -1})
        mi = len(nodes) - 1
        nodes.append({"xy": tip, "width": tip_width, "parent": mi})
        if branch:
            b = a + np.radians(opening_deg / n_veins / 2.5)
            nodes.append({"xy": [mid[0] + 0.5 * length * np.sin(b), mid[1] - 0.5 * length * np.cos(b)],
                          "width": tip_width * 0.8, "parent": mi})
    return {"root": list(base), "root_width": root_width, "nodes": [
        {"xy": [float(n["xy"][0]), float(n["xy"][1])], "width": float(n["width"]), "parent": n["parent"]}
        for n in nodes]}


def venation_from_photo(luminance: np.ndarray, mask: np.ndarray, root_xy=(0.5, 0.5), sigmas=(1.0, 2.0, 3.0),
                        percentile: float = 85.0, bright_ridges: bool = True, min_size: int = 15,
                        off_ridge_cost: float = 20.0, contrast_radius: float = 0.075) -> Venation:
    """A connected vein tree extracted from a photo's luminance, rooted at ``root_xy`` (x, y normalised; moved
    to the nearest petal pixel when it falls outside ``mask``).

    1. Ridges: Sato tubeness of log-luminance at ``sigmas`` (bright ridges unless ``bright_ridges`` is False),
       0 outside the petal, divided by its local mean (Gaussian of ``contrast_radius`` x the larger side, plus
       0.2 x the global mean; 0 disables) so out-of-focus parts of a photo keep their weaker ridges;
       ``r`` = that / its 99th percentile inside the petal, clipped to [0, 1].
    2. Vein pieces: ``r`` above its ``percentile`` inside the petal, pieces of <= ``min_size`` pixels removed,
       skeletonised.
    3. Tree: one minimum-cost-path run (``skimage.graph.MCP_Geometric``, 8-connected, geometric step lengths)
       from the root over the cost ``1 + off_ridge_cost * (1 - r)`` (cheap along strong ridges, 1 on the skeleton,
       impassable outside the petal), then the traceback to the root from every skeleton
       tip (skeleton pixel with one skeleton neighbour) and from the farthest pixel of every skeleton piece (for
       loops without tips). All routes share one predecessor field, so their union is a tree.
    4. Cells: the route pixels are the vascular cells; where a route steps diagonally the corner pixel on the
       ridge side is added, so the veins also conduct through the 4-neighbour grid of the Laplacian (Eq. 3.4').
       Width = the distance transform of the step-2 ridge mask at the cell (at least 0.5 px, for the links
       between pieces), normalised to 1 at the widest vein; ``dist`` = path length from the root along the
       tree (pixels); ``paths`` = the root-to-tip centrelines, (K, 2) int (row, col), 8-connected steps.
    """
    from skimage.filters import sato
    from skimage.graph import MCP_Geometric
    from skimage.measure import label
    from skimage.morphology import remove_small_objects, skeletonize

    lum = np.asarray(luminance, np.float64)
    inside = np.asarray(mask) > 0.5
    if lum.ndim != 2 or inside.shape != lum.shape:
        raise InputError(f"venation_from_photo: luminance {lum.shape} and mask {inside.shape} must be the same 2-D size")
    if inside.sum() < 16:
        raise InputError("venation_from_photo: the petal mask has fewer than 16 pixels; check the mask")
    h, w = lum.shape
    ridge = sato(np.log(np.maximum(lum, 0.0) + 1e-3), sigmas=sigmas, black_ridges=not bright_ridges)
    ridge[~inside] = 0
    if contrast_radius > 0:
        # local contrast normalisation: out-of-focus parts of a photo have weak but real ridges
        s = contrast_radius * max(h, w)
        ridge = ridge / (ndimage.gaussian_filter(ridge, s) + 0.2 * float(ridge[inside].mean()) + 1e-12)
    scale = float(np.percentile(ridge[inside], 99.0))
    r = np.clip(ridge / scale, 0.0, 1.0) if scale > 0 else np.zeros_like(ridge)
    thr = np.percentile(r[inside], percentile)
    veins = remove_small_objects((r > thr) & inside, max_size=max(int(min_size) - 1, 0))
    skel = skeletonize(veins)
    edt = ndimage.distance_transform_edt(veins)
    # root: the petal pixel nearest to root_xy
    rr0 = int(np.clip(round(root_xy[1] * (h - 1)), 0, h - 1))
    rc0 = int(np.clip(round(root_xy[0] * (w - 1)), 0, w - 1))
    if not inside[rr0, rc0]:
        _, (ir, ic) = ndimage.distance_transform_edt(~inside, return_indices=True)
        rr0, rc0 = int(ir[rr0, rc0]), int(ic[rr0, rc0])
    root = (rr0, rc0)
    if not skel.any():
        ven = Venation.empty((h, w), root)
        ven.vascular[root], ven.width[root], ven.dist[root] = True, 1.0, 0.0
        ven.paths = [np.array([root])]
        return ven
    cost = np.where(inside, 1.0 + off_ridge_cost * (1.0 - np.where(skel, 1.0, r)), np.inf)
    mcp = MCP_Geometric(cost, fully_connected=True)
    cum, _ = mcp.find_costs([root])
    # tips: skeleton pixels with exactly one 8-neighbour on the skeleton, plus each piece's farthest pixel
    nb = ndimage.convolve(skel.astype(np.int32), np.ones((3, 3), np.int32), mode="constant") - 1
    tips = skel & (nb == 1) & np.isfinite(cum)
    lab = label(skel, connectivity=2)
    reach = skel & np.isfinite(cum)
    if reach.any():
        li, cc = lab[reach], cum[reach]
        flat = np.flatnonzero(reach.ravel())
        order = np.lexsort((-cc, li))  # per piece, highest cumulative cost first
        first = np.r_[True, li[order][1:] != li[order][:-1]]
        tips.ravel()[flat[order[first]]] = True
    ends = np.argwhere(tips)
    ends = ends[np.argsort(-cum[tips], kind="stable")]  # far tips first: near ones are often on their routes
    onpath = np.zeros((h, w), bool)
    paths = []
    for e in ends:
        if onpath[e[0], e[1]]:
            continue  # already inside a longer route: its centreline is a prefix of that path
        P = np.asarray(mcp.traceback(tuple(int(v) for v in e)), np.int64)
        onpath[P[:, 0], P[:, 1]] = True
        paths.append(P)
    if not paths:
        paths = [np.array([root])]
    vas = onpath.copy()
    vas[root] = True
    dist = np.full((h, w), np.inf, np.float32)
    corner_r, corner_c, corner_d = [], [], []
    for P in paths:
        step = np.hypot(*np.diff(P, axis=0).T.astype(float))
        d = np.r_[0.0, np.cumsum(step)]
        dist[P[:, 0], P[:, 1]] = np.minimum(dist[P[:, 0], P[:, 1]], d.astype(np.float32))
        diag = np.flatnonzero(step > 1.2)
        if diag.size:
            a, b = P[diag], P[diag + 1]
            # the two corners of the diagonal step: (a_row, b_col) and (b_row, a_col); take the more ridge-like
            c1 = np.stack([a[:, 0], b[:, 1]], 1)
            c2 = np.stack([b[:, 0], a[:, 1]], 1)
            s1 = np.where(inside[c1[:, 0], c1[:, 1]], r[c1[:, 0], c1[:, 1]], -1.0)
            s2 = np.where(inside[c2[:, 0], c2[:, 1]], r[c2[:, 0], c2[:, 1]], -1.0)
            c = np.where((s1 >= s2)[:, None], c1, c2)
            ok = inside[c[:, 0], c[:, 1]]
            corner_r.append(c[ok, 0])
            corner_c.append(c[ok, 1])
            corner_d.append((d[diag] + 1.0)[ok])
    if corner_r:
        cr, cc_, cd = np.concatenate(corner_r), np.concatenate(corner_c), np.concatenate(corner_d)
        fresh = ~vas[cr, cc_]
        vas[cr, cc_] = True
        np.minimum.at(dist, (cr[fresh], cc_[fresh]), cd[fresh].astype(np.float32))
    width = np.where(vas, np.maximum(edt, 0.5), 0.0)
    width = width / width.max()
    return Venation(vas, width.astype(np.float32), dist, root, paths)
