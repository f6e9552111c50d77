"""
Feature-preserved texture optimisation
======================================

Defines the feature-preserved texture optimisation of Dong (2007, §6.6.1, Eq. 6.3, on Kwatra et al. 2005):

-   :func:`synthesise`: an output texture from an example, its feature maps following the target's
    (:class:`OptimisationSettings`; the result in a :class:`Result`).
-   :func:`neighbourhood_energy`: the summands of Eq. 6.3 per neighbourhood.

Texture optimisation (Kwatra, Essa, Bobick & Kwatra, *Texture optimization for example-based synthesis*,
SIGGRAPH 2005) finds an output x whose w x w neighbourhoods x_p, on a grid of spacing w/4, are each close to some
neighbourhood z_p of the example, minimising E_t = sum_p |x_p - z_p|^r (r = 0.8) by alternating an E-step (x
from the z_p: an iteratively reweighted average of the overlapping neighbourhoods) and an M-step (each z_p the
nearest example neighbourhood of x_p), coarse to fine over an image pyramid and from large to small
neighbourhoods. Dong adds the control energy

    E(x) = E_t(x; {z_p}) + lambda E_c(f'; f({z_p})),   E_c = sum_p |f'(p) - f(z_p)|^2        (Eq. 6.3)

with f the example's feature maps (scale, type, colour; one channel each, in the grey units of the thesis'
feature images), f' the target maps at the output (the example's maps resampled to the output size, §6.6.1, or
the user's, §6.6.2) and lambda = 0.5. The two changes of §6.6.1:

- initialisation from the features: z_p^0 = argmin_v E_c(f'(p), f(v)), the example neighbourhood whose features
  best match the target's (not a random one);
- the two terms are minimised separately: E_c does not depend on the output's colours, so the E-step is
  Kwatra's on E_t alone, and the nearest-neighbour step minimises |x_p - z|^2 + lambda |f'(p) - f(z)|^2 over
  the example's neighbourhoods z (a joint vector of the neighbourhood's colours and features).

Nearest neighbourhoods come from faiss (inverted lists over PCA-reduced neighbourhood vectors); a candidate replaces
the current z_p only when it lowers that neighbourhood's own energy, so with the reweighted E-step (a
majorise-minimise step for r <= 2) the energy never increases from one iteration to the next. Type constraints
(§6.4, §6.7): ``soft`` treats the type map as one more feature channel; ``tight`` searches a neighbourhood only
among the example neighbourhoods whose centre has the target's type (the background, type 0, included).

References
----------
-   Dong, W. (2007). Rendering Algorithms for Natural Scenes. PhD thesis, Université Henri Poincaré - Nancy I.
-   Kwatra, V., Essa, I., Bobick, A., & Kwatra, N. (2005). Texture optimization for example-based synthesis.
    ACM Transactions on Graphics, 24(3), 795–802.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import cv2
import numpy as np
from scipy.spatial import cKDTree

from natscene.errors import InputError
from natscene.features.type_map import check_types, soft_type_channels

__all__ = ["OptimisationSettings", "Result", "synthesise", "neighbourhood_energy"]


@dataclass(frozen=True)
class OptimisationSettings:
    """Texture optimisation with the control energy of Eq. 6.3 (config ``textures.<name>.optimisation``, and
    ``type_mode`` of ``textures.<name>.types.mode``; no defaults here: workflow/schemas/textures.schema.yaml's are
    the only ones, :func:`natscene.features.entry.optimisation_settings`)."""

    lam: float                             # lambda of Eq. 6.3
    levels: int                            # pyramid levels (each half the size of the next)
    sizes: tuple                           # neighbourhood sizes at the finest level, large to small
    iterations: int                        # EM iterations per (level, size)
    r: float                               # Kwatra's robust exponent of E_t
    type_mode: str                         # soft | tight
    pca_dims: int                          # neighbourhood vectors reduced to this many dimensions for the search
    example_step: int                      # example neighbourhoods taken every this many pixels (at least)
    seed: int

    CONFIG_NAMES = {"mode": "type_mode"}            # textures.<name>.types.mode
    SCHEMA = (("textures.schema.yaml", ("additionalProperties", "optimisation")),
              ("textures.schema.yaml", ("additionalProperties", "types")))


@dataclass
class Result:
    image: np.ndarray                      # (H, W, C) float32 output
    source: np.ndarray                     # (H, W, 2) int32: example (y, x) each output pixel was copied from
    energies: list = field(default_factory=list)   # (level, neighbourhood size, E of Eq. 6.3) per EM iteration
    timings: dict = field(default_factory=dict)


def _patches(img: np.ndarray, w: int, ys: np.ndarray, xs: np.ndarray) -> np.ndarray:
    """(n, w*w*C) neighbourhoods with top-left corners (ys, xs)."""
    oy, ox = np.mgrid[0:w, 0:w]
    return img[ys[:, None, None] + oy, xs[:, None, None] + ox].reshape(len(ys), -1)


def _grid(h: int, w: int, size: int, step: int) -> tuple[np.ndarray, np.ndarray]:
    """Top-left corners of the size x size neighbourhoods on a grid of ``step`` that cover an h x w image."""
    ys = np.unique(np.r_[np.arange(0, h - size + 1, step), h - size])
    xs = np.unique(np.r_[np.arange(0, w - size + 1, step), w - size])
    Y, X = np.meshgrid(ys, xs, indexing="ij")
    return Y.ravel(), X.ravel()


def _feature_vectors(feat: np.ndarray, w: int, ys: np.ndarray, xs: np.ndarray, cells: int) -> np.ndarray:
    """Features of each neighbourhood, averaged over cells x cells sub-blocks and weighted by the pixels each
    stands for, so that |a - b|^2 of two vectors is the per-pixel sum of squared differences of Eq. 6.3."""
    c = w // cells
    pooled = cv2.blur(feat, (c, c), borderType=cv2.BORDER_REFLECT) if c > 1 else feat
    pooled = pooled.reshape(feat.shape[0], feat.shape[1], -1)
    off = np.arange(cells) * c + c // 2
    v = pooled[ys[:, None, None] + off[None, :, None], xs[:, None, None] + off[None, None, :]]
    return (v.reshape(len(ys), -1) * c).astype(np.float32)


def neighbourhood_energy(x_patches: np.ndarray, z_patches: np.ndarray, f_target: np.ndarray, f_source: np.ndarray,
                         lam: float, r: float) -> np.ndarray:
    """Per neighbourhood: |x_p - z_p|^r + lambda |f'(p) - f(z_p)|^2 (the summands of Eq. 6.3)."""
    et = np.sum((x_patches - z_patches) ** 2, axis=1) ** (r / 2.0)
    ec = np.sum((f_target - f_source) ** 2, axis=1) if f_target.size else 0.0
    return et + lam * ec


class _Search:
    """Nearest example neighbourhoods of joint (colour, feature) vectors, optionally per type (tight mode)."""

    def __init__(self, colours: np.ndarray, feats: np.ndarray, lam: float, dims: int, groups: np.ndarray | None,
                 seed: int):
        import faiss
        self.lam = lam
        n, d = colours.shape
        dims = int(min(dims, d, n))
        rng = np.random.default_rng(seed)
        sample = colours[rng.choice(n, size=min(n, 4000), replace=False)]
        self.mean = sample.mean(0)
        centred = (sample - self.mean).astype(np.float64)
        if dims < min(centred.shape) - 1:  # the leading singular vectors alone (ARPACK): 20x faster than a full SVD
            from scipy.sparse.linalg import svds
            _, sv, vt = svds(centred, k=dims, solver="arpack", random_state=seed)
            vt = vt[np.argsort(sv)[::-1]]
        else:
            _, _, vt = np.linalg.svd(centred, full_matrices=False)
        self.basis = vt[:dims].T.astype(np.float32)
        base = self._vec(colours, feats)
        self.groups = {}
        keys = np.zeros(n, np.int64) if groups is None else groups
        for g in np.unique(keys):
            ids = np.flatnonzero(keys == g)
            d = base.shape[1]
            if len(ids) < 4000:  # exact for small sets
                index = faiss.IndexFlatL2(d)
            else:  # inverted lists: k-means cells, the query's 32 nearest cells searched exactly
                cells = max(1, min(int(2 * np.sqrt(len(ids))), len(ids) // 39))  # faiss wants 39 points a cell
                index = faiss.IndexIVFFlat(faiss.IndexFlatL2(d), d, cells)
                index.cp.seed = seed
                index.train(base[ids])
                index.nprobe = 32
            index.add(base[ids])
            self.groups[int(g)] = (index, ids)

    def _vec(self, colours, feats):
        c = (colours - self.mean) @ self.basis
        return np.ascontiguousarray(np.hstack([c, np.sqrt(self.lam) * feats]) if feats.size else c, np.float32)

    def query(self, colours: np.ndarray, feats: np.ndarray, groups: np.ndarray | None) -> np.ndarray:
        q = self._vec(colours, feats)
        out = np.zeros(len(q), np.int64)
        keys = np.zeros(len(q), np.int64) if groups is None else groups
        for g in np.unique(keys):
            sel = np.flatnonzero(keys == g)
            if int(g) not in self.groups:
                raise InputError(f"type {int(g)} of the target type map is not in the example's type map")
            index, ids = self.groups[int(g)]
            _, nn = index.search(q[sel], 1)
            out[sel] = ids[nn[:, 0]]
        return out


def _pyramid(img: np.ndarray, levels: int) -> list:
    if img.ndim == 3 and img.shape[2] == 0:  # no feature channel
        return [np.zeros(((img.shape[0] >> k) or 1, (img.shape[1] >> k) or 1, 0), np.float32)
                for k in range(levels - 1, -1, -1)]
    out = [img]
    for _ in range(levels - 1):
        out.append(cv2.resize(out[-1], (max(1, out[-1].shape[1] // 2), max(1, out[-1].shape[0] // 2)),
                              interpolation=cv2.INTER_AREA))
    return out[::-1]  # coarse to fine


def _as3(a: np.ndarray) -> np.ndarray:
    return a[..., None] if a.ndim == 2 else a


def synthesise(example: np.ndarray, size: tuple, example_features: np.ndarray | None = None,
               target_features: np.ndarray | None = None, settings: OptimisationSettings | None = None,
               example_types: np.ndarray | None = None, target_types: np.ndarray | None = None,
               known: np.ndarray | None = None, initial: np.ndarray | None = None, log=None) -> Result:
    """An output of ``size`` (height, width) from ``example`` (H, W, C) in [0, 1].

    ``example_features`` (H, W, k) and ``target_features`` (h, w, k): the feature maps of Eq. 6.3 (grey units);
    ``example_types`` / ``target_types``: integer type maps (§6.4) used as ``settings.type_mode`` says; ``known``
    (h, w) boolean with ``initial`` (h, w, C): pixels that stay as given (image completion, §6.7), the rest is
    synthesised; then the example must not overlap them (the caller passes the known region's neighbourhoods).
    ``settings``: None: the schema's defaults.
    """
    import time

    from natscene.config import default_settings
    s = settings if settings is not None else default_settings(OptimisationSettings)
    log = log or (lambda msg: None)
    ex = _as3(np.asarray(example, np.float32))
    H, W = int(size[0]), int(size[1])
    none = np.zeros(ex.shape[:2] + (0,), np.float32), np.zeros((H, W, 0), np.float32)  # no feature channel
    fe = _as3(np.asarray(example_features, np.float32)) if example_features is not None else none[0]
    ft = _as3(np.asarray(target_features, np.float32)) if target_features is not None else none[1]
    if fe.shape[:2] != ex.shape[:2] or ft.shape[:2] != (H, W) or fe.shape[2] != ft.shape[2]:
        raise InputError(f"feature maps: example {fe.shape} and target {ft.shape} do not match the example "
                         f"{ex.shape[:2]} and the output {(H, W)}")
    if s.type_mode not in ("soft", "tight"):
        raise InputError(f"type_mode {s.type_mode!r}: soft or tight")
    types_e = types_t = None
    if example_types is not None:
        types_e, types_t = check_types(example_types, target_types)
        if s.type_mode == "soft":  # one more feature channel
            fe, ft = soft_type_channels(fe, ft, types_e, types_t)
    if min(H, W) < min(s.sizes):
        raise InputError(f"output {W}x{H} is smaller than the smallest neighbourhood {min(s.sizes)}")
    rng = np.random.default_rng(s.seed)
    ex_p, fe_p, ft_p = _pyramid(ex, s.levels), _pyramid(fe, s.levels), _pyramid(ft, s.levels)
    known_p = _pyramid(known.astype(np.float32), s.levels) if known is not None else [None] * s.levels
    init_p = _pyramid(_as3(np.asarray(initial, np.float32)), s.levels) if initial is not None else [None] * s.levels
    tl = lambda a, shape: cv2.resize(a, (shape[1], shape[0]), interpolation=cv2.INTER_NEAREST)  # noqa: E731
    x = None
    energies, timings = [], {"search_s": 0.0, "estep_s": 0.0}
    for level in range(s.levels):
        E, Fe, Ft = ex_p[level], _as3(fe_p[level]), _as3(ft_p[level])
        h, w = Ft.shape[:2]
        he, we = E.shape[:2]
        kn = known_p[level] > 0.999 if known_p[level] is not None else None
        te = tl(types_e, (he, we)) if (types_e is not None and s.type_mode == "tight") else None
        tt = tl(types_t, (h, w)) if (types_t is not None and s.type_mode == "tight") else None
        sizes = [n for n in s.sizes if 2 * n <= min(he, we, h, w)] or [min(s.sizes[-1], he, we, h, w)]
        if x is not None:
            x = cv2.resize(x, (w, h), interpolation=cv2.INTER_LINEAR).reshape(h, w, -1)
        if kn is not None:
            known_img = init_p[level].reshape(h, w, -1)
            x = known_img.copy() if x is None else np.where(kn[..., None], known_img, x)
        for n in sizes:
            step = max(1, n // 4)
            eys, exs = _grid(he, we, n, max(s.example_step, n // 8))  # fewer vectors for the big neighbourhoods
            if kn is not None:  # image completion: the example is the image's fully known neighbourhoods
                ok = _patches(kn.astype(np.float32)[..., None], n, eys, exs).min(1) > 0
                eys, exs = eys[ok], exs[ok]
                if not len(eys):
                    raise InputError(f"completion: no {n}x{n} neighbourhood of the image is fully known")
            cells = min(4, n)
            Z = _patches(E, n, eys, exs)
            FZ = _feature_vectors(Fe, n, eys, exs, cells) if Fe.shape[2] else np.zeros((len(eys), 0), np.float32)
            groups_e = te[eys + n // 2, exs + n // 2] if te is not None else None
            t0 = time.perf_counter()
            search = _Search(Z, FZ, s.lam, s.pca_dims, groups_e, s.seed + level)
            timings["search_s"] += time.perf_counter() - t0
            oys, oxs = _grid(h, w, n, step)
            if kn is not None:  # only neighbourhoods that touch the unknown pixels
                touch = _patches((~kn).astype(np.float32)[..., None], n, oys, oxs).max(1) > 0
                oys, oxs = oys[touch], oxs[touch]
            FT = _feature_vectors(Ft, n, oys, oxs, cells) if Ft.shape[2] else np.zeros((len(oys), 0), np.float32)
            groups_t = tt[oys + n // 2, oxs + n // 2] if tt is not None else None
            if x is None or (kn is not None and level == 0 and n == sizes[0]):
                # feature-guided initialisation: z_p^0 = argmin_v E_c (random without features)
                if FT.shape[1]:
                    q = _Search(np.zeros((len(eys), 1), np.float32), FZ, 1.0, 1, groups_e, s.seed)
                    z = q.query(np.zeros((len(oys), 1), np.float32), FT, groups_t)
                else:
                    z = _random_in_groups(rng, groups_e, groups_t, len(eys), len(oys))
                # the start is a mosaic, each pixel from the chosen neighbourhood whose centre is nearest (an
                # average of the overlapping z_p^0 would start from a grey blur that the EM cannot sharpen)
                sy, sx = _sources(eys[z], exs[z], oys, oxs, n, h, w)
                x0 = E[np.clip(sy, 0, he - 1), np.clip(sx, 0, we - 1)]
                x = x0 if kn is None else np.where(kn[..., None], known_img, x0)
            else:
                z = search.query(_patches(x, n, oys, oxs), FT, groups_t)
            for it in range(s.iterations):
                xp = _patches(x, n, oys, oxs)
                t0 = time.perf_counter()
                cand = search.query(xp, FT, groups_t)
                timings["search_s"] += time.perf_counter() - t0
                e_old = neighbourhood_energy(xp, Z[z], FT, FZ[z], s.lam, s.r)
                e_new = neighbourhood_energy(xp, Z[cand], FT, FZ[cand], s.lam, s.r)
                z = np.where(e_new < e_old, cand, z)
                t0 = time.perf_counter()
                x = _estep(Z[z], oys, oxs, n, h, w, E.shape[2], xp, s.r)
                if kn is not None:
                    x[kn] = known_img[kn]
                timings["estep_s"] += time.perf_counter() - t0
                xp = _patches(x, n, oys, oxs)
                energies.append((level, n, float(neighbourhood_energy(xp, Z[z], FT, FZ[z], s.lam, s.r).sum())))
            log(f"level {level + 1}/{s.levels} ({w}x{h}), neighbourhood {n}: E = {energies[-1][2]:.4g}")
    src_y, src_x = _sources(eys[z], exs[z], oys, oxs, n, h, w)  # of the last (finest) stage
    out_src = np.stack([src_y, src_x], -1).astype(np.int32)
    if known is not None:
        out_src[known > 0.999] = -1
    return Result(image=np.clip(x, 0.0, 1.0).astype(np.float32), source=out_src, energies=energies, timings=timings)


def _random_in_groups(rng, groups_e, groups_t, n_e: int, n_q: int) -> np.ndarray:
    """A random example neighbourhood per query, of the query's type when types are tight."""
    if groups_t is None:
        return rng.integers(0, n_e, n_q)
    z = np.zeros(n_q, np.int64)
    for g in np.unique(groups_t):
        ids = np.flatnonzero(groups_e == g)
        if not len(ids):
            raise InputError(f"type {int(g)} of the target type map is not in the example's type map")
        sel = np.flatnonzero(groups_t == g)
        z[sel] = ids[rng.integers(0, len(ids), len(sel))]
    return z


def _estep(zp: np.ndarray, oys, oxs, n: int, h: int, w: int, c: int, xp: np.ndarray | None, r: float) -> np.ndarray:
    """Kwatra's E-step: each output pixel the weighted mean of the neighbourhoods z_p that cover it, weights
    |x_p - z_p|^(r - 2) (iteratively reweighted least squares of E_t; 1 before the first x exists)."""
    if xp is None:
        wts = np.ones(len(oys), np.float32)
    else:
        wts = (np.sum((xp - zp) ** 2, axis=1) + 1e-6) ** ((r - 2.0) / 2.0)
    acc = np.zeros((h * w, c), np.float64)
    norm = np.zeros(h * w, np.float64)
    patches = zp.reshape(-1, n, n, c) * wts[:, None, None, None]
    base = oys * w + oxs  # distinct neighbourhoods: for one offset every target pixel appears once
    for dy in range(n):
        for dx in range(n):
            idx = base + (dy * w + dx)
            acc[idx] += patches[:, dy, dx]
            norm[idx] += wts
    return (acc / np.maximum(norm, 1e-12)[:, None]).reshape(h, w, c).astype(np.float32)


def _sources(zy, zx, oys, oxs, n, h, w):
    """For each output pixel, the example pixel it comes from through the neighbourhood whose centre is nearest."""
    cy, cx = oys + n / 2.0, oxs + n / 2.0
    yy, xx = np.mgrid[0:h, 0:w]
    _, k = cKDTree(np.c_[cy, cx]).query(np.c_[yy.ravel() + 0.5, xx.ravel() + 0.5])
    sy = zy[k] + (yy.ravel() - oys[k])
    sx = zx[k] + (xx.ravel() - oxs[k])
    return sy.reshape(h, w), sx.reshape(h, w)
