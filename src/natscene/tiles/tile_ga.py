"""
ω-tile GA
=========

Defines the sample-patch selection of an ω-tile set by genetic algorithm (Dong 2007, §5.4.2, Eqs. 5.1-5.6):

-   :func:`run_tile_ga`: select the n sample patches of a set from an example, a :class:`GAResult`.
-   :class:`GAParams`: the GA settings with the defaults of §5.5.
-   :class:`MatchCost`, :func:`quarter_layout`: the quarter SSD maps of Eq. 5.1 and the quarters' layout.
-   :func:`evaluation`: E of Eq. 5.4.
-   :func:`min_patch_positions`, :func:`max_tile_size`, :func:`min_example_side`: what an example must offer.

A chromosome holds the n sample-patch coordinates (one gene per colour square, ``(y, x)`` of the patch's
top-left corner in the example). Its evaluation (Eqs. 5.1-5.4) over the m intermediate tiles of the set:

    C_j(t) = sum_{p in S_t} |T_j(p) - I(p - t)|^2          (5.1)   all translations t in P_T
    D_j    = min_t C_j(t)                                  (5.2)
    V      = Variance(D_1 .. D_m)                          (5.3)
    E      = lambda * sum_j D_j + (1 - lambda) * V         (5.4)   lambda = 0.8

P_T: every position of a tile-sized window inside the example. The intermediate tile is made of four
patch quarters, so C_j(t) is the sum of four *quarter* SSD maps, each depending only on one gene and the
quarter it plays. Each map is the SSD of one half-tile block of the example against every block of the
example, computed for all translations at once by FFT correlation (sum I^2 + sum T^2 - 2 I*T), cached per
gene: evaluating a chromosome is then m sums of four maps and a minimum.

Options (§5.5): ``metric='gradient_sum'`` (Eq. 5.6: adds mu * sum |grad T - grad I|^2, done as extra
feature channels sqrt(mu) * d/dx, d/dy) and ``metric='gradient_ratio'`` (Eq. 5.5: each squared colour
difference divided by mu (|grad T| + |grad I|); not a correlation, evaluated directly, slow). Gradients
of a quarter are those of the example at its source pixels. mu = 10.

Selection: rank-based roulette, eval(A_i) = alpha (1 - alpha)^(i-1) over the population sorted by
fitness F = 1/E; crossover with probability P_c (single cut c in [2, n] per parent pair); range mutation
with probability P_m (genes n1..n2 replaced by random patches different from the chromosome's genes);
termination after N_g generations or N_o generations without improvement of the best. Defaults
pop_size = 40, alpha = 0.05, P_c = 0.3, P_m = 0.2, N_g = 50, N_o = 5 (§5.5).
Deviation: the paper writes the mutation range as 1 <= n1 < n2 <= n - 1 (which, read 1-based, would
never mutate the last gene); here n1 < n2 are drawn among all n genes.

References
----------
-   Dong, W. (2007). Rendering algorithms for natural scenes. PhD thesis, Université Henri Poincaré – Nancy 1.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from natscene.tiles.omega import TileSet

__all__ = ["run_tile_ga", "GAParams", "GAResult", "MatchCost", "quarter_layout", "evaluation",
           "min_patch_positions", "max_tile_size", "min_example_side"]

METRICS = ("color", "gradient_sum", "gradient_ratio")


@dataclass
class GAParams:
    """GA settings (config ``tiles.<name>.ga``; no defaults here: workflow/schemas/tiles.schema.yaml's, Dong 2007
    §5.5's, are the only ones, :func:`natscene.config.settings_from_section`)."""

    pop_size: int
    alpha: float
    p_c: float
    p_m: float
    n_g: int
    n_o: int
    lam: float
    metric: str
    mu: float

    CONFIG_NAMES = {"lambda": "lam"}  # config name -> field (``lambda`` is a Python keyword)
    SCHEMA = (("tiles.schema.yaml", ("additionalProperties", "ga")),)


def quarter_layout(s: int):
    """For corner q (TL, TR, BL, BR): (offset of the source block inside the patch, offset of the
    quarter inside the tile). The tile's TL quarter is the patch's BR quarter, etc."""
    h = s // 2
    return [((h, h), (0, 0)), ((h, 0), (0, h)), ((0, h), (h, 0)), ((0, 0), (h, h))]


def _gradients(img: np.ndarray) -> np.ndarray:
    gy, gx = np.gradient(img, axis=(0, 1))
    return gy, gx


class MatchCost:
    """Quarter SSD maps of one example for one tile size, cached per block position (Eq. 5.1)."""

    def __init__(self, example: np.ndarray, tile_size: int, metric: str = "color", mu: float = 10.0):
        ex = np.asarray(example, np.float64)
        if ex.ndim == 2:
            ex = ex[..., None]
        if metric not in METRICS:
            raise ValueError(f"metric must be one of {METRICS}, got {metric!r}")
        s = int(tile_size)
        if s % 2 or s < 4:
            raise ValueError(f"tile_size must be even and >= 4, got {s}")
        H, W = ex.shape[:2]
        if s > H or s > W:
            raise ValueError(f"tile_size {s} larger than the example {W}x{H}")
        self.s, self.h, self.H, self.W = s, s // 2, H, W
        self.metric, self.mu = metric, float(mu)
        self.PH, self.PW = H - s + 1, W - s + 1  # translations P_T
        self.BH, self.BW = H - self.h + 1, W - self.h + 1  # half-tile block positions
        self.example = ex
        gy, gx = _gradients(ex)
        if metric == "gradient_sum":
            r = np.sqrt(self.mu)
            feat = np.concatenate([ex, r * gy, r * gx], axis=-1)
        else:
            feat = ex
        self.feat = feat
        self.gmag = np.sqrt((gy ** 2 + gx ** 2).sum(-1))  # |grad I| (Eq. 5.5)
        h = self.h
        if metric != "gradient_ratio":
            self._fI = np.fft.rfft2(feat, axes=(0, 1))
            sq = np.pad((feat ** 2).sum(-1), ((1, 0), (1, 0))).cumsum(0).cumsum(1)
            self._I2 = sq[h:, h:] - sq[:-h, h:] - sq[h:, :-h] + sq[:-h, :-h]  # (BH, BW) block energy
        self._cache: dict[tuple[int, int], np.ndarray] = {}

    def block_map(self, ay: int, ax: int) -> np.ndarray:
        """SSD (BH, BW) between the half-tile block at (ay, ax) and every block of the example."""
        key = (int(ay), int(ax))
        m = self._cache.get(key)
        if m is not None:
            return m
        h = self.h
        if self.metric == "gradient_ratio":
            m = self._ratio_map(ay, ax)
        else:
            T = self.feat[ay:ay + h, ax:ax + h]
            pad = np.zeros_like(self.feat)
            pad[:h, :h] = T
            corr = np.fft.irfft2((self._fI * np.conj(np.fft.rfft2(pad, axes=(0, 1)))).sum(-1),
                                 s=(self.H, self.W))[:self.BH, :self.BW]
            m = np.maximum(self._I2 + (T ** 2).sum() - 2.0 * corr, 0.0)
        self._cache[key] = m
        return m

    def _ratio_map(self, ay, ax):
        h = self.h
        from numpy.lib.stride_tricks import sliding_window_view
        T = self.example[ay:ay + h, ax:ax + h]
        gT = self.gmag[ay:ay + h, ax:ax + h]
        win = sliding_window_view(self.example, (h, h), axis=(0, 1))   # (BH, BW, C, h, h)
        gwin = sliding_window_view(self.gmag, (h, h))                   # (BH, BW, h, h)
        out = np.empty((self.BH, self.BW))
        Tt = T.transpose(2, 0, 1)
        for y in range(self.BH):  # rows of translations (the option is documented as slow)
            d2 = ((win[y] - Tt) ** 2).sum(1)                            # (BW, h, h)
            out[y] = (d2 / (self.mu * (gT + gwin[y]) + 1e-6)).sum((1, 2))
        return out

    def gene_maps(self, genes: np.ndarray) -> np.ndarray:
        """(n, 4, PH, PW): C restricted to quarter q of the patch of each gene, per translation t."""
        out = np.empty((len(genes), 4, self.PH, self.PW))
        for i, (gy, gx) in enumerate(np.asarray(genes).tolist()):
            for q, ((sy, sx), (oy, ox)) in enumerate(quarter_layout(self.s)):
                bm = self.block_map(gy + sy, gx + sx)
                out[i, q] = bm[oy:oy + self.PH, ox:ox + self.PW]
        return out

    def tile_errors(self, genes: np.ndarray, tiles: np.ndarray):
        """(D_j, argmin translation (ty, tx)) for every tile (Eqs. 5.1-5.2)."""
        maps = self.gene_maps(genes)
        q = np.arange(4)
        total = maps[tiles, q[None, :]].sum(1)                   # (m, PH, PW)
        flat = total.reshape(len(tiles), -1)
        k = flat.argmin(1)
        D = flat[np.arange(len(tiles)), k]
        return D, np.stack([k // self.PW, k % self.PW], 1)


def evaluation(D: np.ndarray, lam: float = 0.8) -> float:
    """E = lambda * sum D_j + (1 - lambda) * Var(D_j) (Eq. 5.4)."""
    D = np.asarray(D, np.float64)
    return float(lam * D.sum() + (1.0 - lam) * D.var())


@dataclass
class GAResult:
    genes: np.ndarray            # (n, 2) best chromosome: patch (y, x)
    E: float                     # its evaluation
    D: np.ndarray                # (m,) minimum matching errors
    matches: np.ndarray          # (m, 2) best matching patch (y, x) per tile
    initial_best_E: float        # best E of the initial population
    initial_mean_E: float        # mean E of the initial (random) population
    log: list = field(default_factory=list)   # per generation: best, mean
    evaluations: int = 0


def min_patch_positions(n: int) -> int:
    """Distinct patch positions the GA of :func:`run_tile_ga` needs for a set of ``n`` sample patches: a mutation
    replaces up to all ``n`` genes by new ones distinct from the ``n`` it had, so ``2 n``."""
    return 2 * int(n)


def max_tile_size(height: int, width: int, n: int) -> int | None:
    """The largest valid tile size (even, >= 4, at most the example's smaller side) with which an example of
    ``width`` x ``height`` px offers the GA enough patch positions ((H - s + 1)(W - s + 1) >= 2 n) for a set
    of ``n`` sample patches; None when no tile size does."""
    s = min(int(height), int(width)) // 2 * 2
    while s >= 4:
        if (height - s + 1) * (width - s + 1) >= min_patch_positions(n):
            return s
        s -= 2
    return None


def min_example_side(n: int, tile_size: int = 4) -> int:
    """The smallest side of a square example that has enough patch positions at ``tile_size``."""
    k = int(np.ceil(np.sqrt(min_patch_positions(n))))
    return int(tile_size) - 1 + k


def random_genes(rng, n: int, PH: int, PW: int, exclude=()) -> np.ndarray:
    """n distinct random patch coordinates not in ``exclude``."""
    if n + len(exclude) > PH * PW:
        raise ValueError(f"example too small: needs {n} distinct patch positions, has {PH * PW}")
    taken = {tuple(e) for e in exclude}
    out = []
    while len(out) < n:
        g = (int(rng.integers(PH)), int(rng.integers(PW)))
        if g not in taken:
            taken.add(g)
            out.append(g)
    return np.array(out, np.int64).reshape(n, 2)


def run_tile_ga(example: np.ndarray, ts: TileSet, tile_size: int, params: GAParams | None = None,
           seed: int = 0, cost: MatchCost | None = None) -> GAResult:
    """Select the n sample patches of ``ts`` from ``example`` by the GA of §5.4.2."""
    if params is None:
        from natscene.config import default_settings
        params = default_settings(GAParams)
    p = params
    if not (0 < p.alpha < 1) or not (0 <= p.p_c <= 1) or not (0 < p.p_m < 1) or p.pop_size < 2:
        raise ValueError(f"invalid GA parameters {p}")
    rng = np.random.default_rng(seed)
    cost = cost or MatchCost(example, tile_size, p.metric, p.mu)
    n, PH, PW = ts.n, cost.PH, cost.PW
    if PH * PW < min_patch_positions(n):
        raise ValueError(f"example too small for tile size {cost.s}: set {ts.name} needs {min_patch_positions(n)} "
                         f"distinct patch positions, the example has {PH * PW}; largest tile size that works: "
                         f"{max_tile_size(cost.H, cost.W, n)}")
    memo: dict[bytes, float] = {}
    counter = [0]

    def E_of(chrom):
        key = chrom.tobytes()
        e = memo.get(key)
        if e is None:
            D, _ = cost.tile_errors(chrom, ts.tiles)
            e = evaluation(D, p.lam)
            memo[key] = e
            counter[0] += 1
        return e

    pop = [random_genes(rng, n, PH, PW) for _ in range(p.pop_size)]
    Es = np.array([E_of(c) for c in pop])
    best_i = int(Es.argmin())
    best, best_E = pop[best_i].copy(), float(Es[best_i])
    init_best, init_mean = best_E, float(Es.mean())
    log = [{"generation": 0, "best": best_E, "mean": float(Es.mean())}]
    ranks = p.alpha * (1 - p.alpha) ** np.arange(p.pop_size)
    q = np.cumsum(ranks)
    stall = 0
    for gen in range(1, p.n_g + 1):
        order = np.argsort(Es, kind="stable")                 # high fitness (low E) first
        ranked = [pop[i] for i in order]
        gam = rng.uniform(0, q[-1], p.pop_size)
        gam = np.where(gam <= 0, q[-1], gam)                  # gamma in (0, q_pop]
        mothers = [ranked[int(min(np.searchsorted(q, g_, side="left"), p.pop_size - 1))].copy()
                   for g_ in gam]
        # crossover
        pick = rng.random(p.pop_size) < p.p_c
        parents = [m for m, k in zip(mothers, pick) if k]
        others = [m for m, k in zip(mothers, pick) if not k]
        if len(parents) % 2:
            others.append(parents.pop())
        children = []
        for a, b in zip(parents[0::2], parents[1::2]):
            c = int(rng.integers(2, n + 1)) if n >= 2 else 1   # c in [2, n] (1-based)
            x = np.concatenate([a[:c - 1], b[c - 1:]])
            y = np.concatenate([b[:c - 1], a[c - 1:]])
            for ch in (x, y):  # keep genes distinct: a duplicate becomes a fresh random patch
                seen = set()
                for i in range(n):
                    t = tuple(ch[i])
                    if t in seen:
                        ch[i] = random_genes(rng, 1, PH, PW, exclude=[tuple(v) for v in ch])[0]
                    seen.add(tuple(ch[i]))
            children += [x, y]
        pop = children + others
        # mutation
        for i in range(len(pop)):
            if n >= 2 and rng.random() < p.p_m:
                n1, n2 = sorted(rng.choice(n, 2, replace=False).tolist())
                ch = pop[i].copy()
                new = random_genes(rng, n2 - n1 + 1, PH, PW, exclude=[tuple(v) for v in ch])
                ch[n1:n2 + 1] = new
                pop[i] = ch
        Es = np.array([E_of(c) for c in pop])
        i = int(Es.argmin())
        if Es[i] < best_E:
            best, best_E, stall = pop[i].copy(), float(Es[i]), 0
        else:
            stall += 1
        log.append({"generation": gen, "best": best_E, "mean": float(Es.mean())})
        if stall >= p.n_o:
            break
    D, matches = cost.tile_errors(best, ts.tiles)
    return GAResult(best, best_E, D, matches, init_best, init_mean, log, counter[0])
