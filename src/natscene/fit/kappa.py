"""
Line search for the atmospheric extinction
==========================================

Defines the linear search for kappa_a(lambda) of Dobashi et al. (2012, §4.2, Eq. 3, Fig. 3):

-   :func:`kappa_grid`: the sampled kappa_a values.
-   :class:`KappaSearch`: the Eq. 3 blend and the per-channel search of kappa_a for a whole population.

Eq. 3 blends the cloud intensity with the sky behind it:
``L_cg = L_c exp(-kappa_a t_c) + (1 - exp(-kappa_a t_c)) L_sky``. L_c does not depend on kappa_a, so for each
GA candidate the cloud image is composed once and kappa_a is found by sampling it at regular intervals
(default every 0.1 over [0, 1]) and keeping the value with the smallest objective (Fig. 3: kappa from 0
upward, replaced only on a strictly smaller O, so ties keep the smallest kappa). Each channel's histogram
depends only on its own kappa_a(lambda) and O is the mean of per-channel terms, so the three channels are
searched independently: 3 x 11 evaluations give the same minimiser as the 11^3 joint grid.

Vectorised over the whole population, the channels and the kappa samples: the factors exp(-kappa t_c) are
computed once per pixel. Two interchangeable back ends count the P x 3 x K histograms: a numpy one (per
individual, the 3 x K images of levels are built in one pass and all their histograms counted by a single
``np.bincount`` on offset level indices) and, where numba is importable (it ships with the declared
dependencies prosail and miepython), one fused compiled loop over (individual, channel) in parallel that
never materialises the 3 x K images (its level lookup table held in the narrowest integer type, which keeps it in
the L1 cache). Both perform the same float32 operations and give identical counts.

References
----------
-   Dobashi, Y., Iwasaki, W., Ono, A., Yamamoto, T., Yue, Y., & Nishita, T. (2012). An inverse problem approach
    for automatically adjusting the parameters for rendering clouds using photographs. ACM Transactions on
    Graphics, 31(6).
"""
from __future__ import annotations

import numpy as np

from natscene.fit.objective import Levels, channel_distance, histograms, METRICS

__all__ = ["kappa_grid", "KappaSearch"]


def kappa_grid(lo: float = 0.0, hi: float = 1.0, step: float = 0.1) -> np.ndarray:
    """The sampled kappa_a values lo, lo + step, ..., hi (inclusive, robust to rounding)."""
    if step <= 0 or hi < lo:
        raise ValueError(f"kappa grid needs step > 0 and hi >= lo (got {lo}, {hi}, {step})")
    n = int(np.floor((hi - lo) / step + 1e-9)) + 1
    return lo + step * np.arange(n)


try:  # optional compiled back end
    import numba as _nb
except Exception:  # noqa: BLE001 - numba missing or broken: numpy back end only
    _nb = None

_KERNEL = None


def _numba_kernel():
    global _KERNEL
    if _KERNEL is None and _nb is not None:
        @_nb.njit(parallel=True, cache=True)
        def counts_kernel(cloud, sky, att, lut, lut_size, n_levels):  # pragma: no cover - compiled
            P, C, N = cloud.shape
            K = att.shape[0]
            out = np.zeros((P, C, K, n_levels), np.int32)
            scale = np.float32(lut_size)
            one = np.float32(1.0)
            zero = np.float32(0.0)
            for pc in _nb.prange(P * C):
                p = pc // C
                c = pc - p * C
                d = np.empty(N, np.float32)
                idx = np.empty(N, np.int32)
                sub = np.zeros((4, n_levels), np.int32)    # 4 interleaved histograms: no store-to-load chain
                for i in range(N):
                    d[i] = cloud[p, c, i] - sky[c, i]
                for k in range(K):
                    for i in range(N):                      # the level's LUT cell (a loop that vectorises)
                        v = d[i] * att[k, i] + sky[c, i]
                        v = min(max(v, zero), one)
                        idx[i] = np.int32(np.sqrt(v) * scale)
                    sub[:] = 0
                    for i in range(N):
                        sub[i & 3, lut[idx[i]]] += 1
                    h = out[p, c, k]
                    for b in range(n_levels):
                        h[b] = sub[0, b] + sub[1, b] + sub[2, b] + sub[3, b]
            return out

        _KERNEL = counts_kernel
    return _KERNEL


class KappaSearch:
    """Objective evaluation with the per-channel kappa_a line search for a fixed set of cloud pixels.

    ``sky`` (N, 3) L_sky and ``t_c`` (N,) normalised distance at the N synthetic cloud pixels;
    ``target`` (M, 3) linear photo cloud pixels (for ``pixel_ssd``: (N, 3), the same pixels as ``sky``).
    """

    def __init__(self, sky: np.ndarray, t_c: np.ndarray, target: np.ndarray, kappas: np.ndarray | None = None,
                 levels: Levels | None = None, metric: str = "difference", backend: str = "auto"):
        if metric not in METRICS:
            raise ValueError(f"unknown metric {metric!r}; choose one of {METRICS}")
        self.levels = levels or Levels()
        self.metric = metric
        if backend not in ("auto", "numba", "numpy"):
            raise ValueError(f"backend must be auto, numba or numpy, got {backend!r}")
        if backend == "numba" and _nb is None:
            raise ValueError("backend 'numba' requested but numba is not importable")
        self.backend = "numba" if backend in ("auto", "numba") and _nb is not None else "numpy"
        self.kappas = np.asarray(kappa_grid() if kappas is None else kappas, np.float64)
        self.sky = np.ascontiguousarray(np.asarray(sky, np.float32).reshape(-1, 3).T)  # (3, N)
        self.t_c = np.asarray(t_c, np.float32).reshape(-1)
        n = self.sky.shape[1]
        if self.t_c.shape[0] != n:
            raise ValueError(f"t_c has {self.t_c.shape[0]} pixels, sky {n}")
        if n == 0:
            raise ValueError("no synthetic cloud pixels")
        # attenuation factors exp(-kappa t_c) for every kappa sample: (K, N)
        self.att = np.exp(-self.kappas[:, None] * self.t_c[None, :].astype(np.float64)).astype(np.float32)
        target = np.asarray(target, np.float32).reshape(-1, 3)
        if target.shape[0] == 0:
            raise ValueError("no photo cloud pixels")
        nl = self.levels.n_levels
        # the levels' lookup table in the narrowest integer type: 8 KB at 256 levels, where int32's 32 KB would
        # fill the core's L1 cache beside the histograms
        self._lut = self.levels.lut.astype(np.uint8 if nl <= 256 else np.uint16)
        k = len(self.kappas)
        self._offsets = (np.arange(3 * k, dtype=np.int32) * nl).reshape(3, k, 1)
        if metric == "pixel_ssd":
            if target.shape[0] != n:
                raise ValueError("pixel_ssd needs a target image with the same pixels as the synthetic one")
            self.target_enc = self.levels(target.T).astype(np.float64) / (self.levels.n_levels - 1)  # (3, N)
            self.target_hist = None
        else:
            self.target_hist = histograms(self.levels(target.T), nl)  # (3, n_L)

    @property
    def n_pixels(self) -> int:
        return self.sky.shape[1]

    def blend(self, cloud: np.ndarray, kappa: np.ndarray) -> np.ndarray:
        """Eq. 3 at the cloud pixels: cloud (P, N, 3) L_c, kappa (P, 3) -> L_cg (P, N, 3)."""
        # same float32 arithmetic as the search: L_sky + (L_c - L_sky) exp(-kappa t_c)
        e = np.exp(-np.asarray(kappa, np.float64)[:, None, :]
                   * self.t_c[None, :, None].astype(np.float64)).astype(np.float32)
        sky = self.sky.T[None]
        out = np.asarray(cloud, np.float32) - sky
        out *= e
        out += sky
        return out

    def channel_distances(self, cloud: np.ndarray) -> np.ndarray:
        """Per-channel distances for every kappa sample: cloud (P, N, 3) -> (P, 3, K)."""
        cloud = np.asarray(cloud, np.float32)
        p_count = cloud.shape[0]
        if cloud.shape[1:] != (self.n_pixels, 3):
            raise ValueError(f"cloud pixels must be (P, {self.n_pixels}, 3), got {cloud.shape}")
        nl = self.levels.n_levels
        k = len(self.kappas)
        if self.metric != "pixel_ssd" and self.backend == "numba":
            cl = np.ascontiguousarray(np.moveaxis(cloud, -1, 1))  # (P, 3, N)
            counts = _numba_kernel()(cl, self.sky, self.att, self._lut, self.levels.lut_size, nl)
            h = counts / self.n_pixels
            return channel_distance(h, self.target_hist[None, :, None, :], self.metric)
        out = np.empty((p_count, 3, k))
        buf = np.empty((3, k, self.n_pixels), np.float32)
        lv = np.empty((3, k, self.n_pixels), np.int32)
        for p in range(p_count):  # one individual at a time keeps the working set in cache
            d = cloud[p].T - self.sky  # (3, N): L_c - L_sky
            np.multiply(d[:, None, :], self.att[None], out=buf)
            buf += self.sky[:, None, :]  # L_cg = L_sky + (L_c - L_sky) exp(-kappa t_c)
            self.levels(buf, out=lv)
            if self.metric == "pixel_ssd":
                diff = lv.astype(np.float64) / (nl - 1) - self.target_enc[:, None, :]
                out[p] = np.einsum("ckn,ckn->ck", diff, diff) / self.n_pixels
                continue
            lv += self._offsets
            h = np.bincount(lv.ravel(), minlength=3 * k * nl).reshape(3, k, nl) / self.n_pixels
            out[p] = channel_distance(h, self.target_hist[:, None, :], self.metric)
        return out

    def search(self, cloud: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Best kappa_a per channel and the resulting O: cloud (P, N, 3) -> (O (P,), kappa (P, 3))."""
        dist = self.channel_distances(cloud)
        best = np.argmin(dist, axis=-1)  # first minimum = smallest kappa among ties (Fig. 3)
        per_channel = np.take_along_axis(dist, best[..., None], -1)[..., 0]
        return per_channel.mean(-1), self.kappas[best]

    def evaluate(self, cloud: np.ndarray, kappa: np.ndarray) -> np.ndarray:
        """O for given kappa_a (P, 3) without searching (exact Eq. 3 blend + metric)."""
        img = self.blend(cloud, kappa)
        nl = self.levels.n_levels
        if self.metric == "pixel_ssd":
            d = self.levels(np.moveaxis(img, -1, 1)).astype(np.float64) / (nl - 1) - self.target_enc[None]
            return np.einsum("pcn,pcn->pc", d, d).mean(-1) / d.shape[-1]
        h = histograms(self.levels(np.moveaxis(img, -1, 1)), nl)  # (P, 3, n_L)
        return channel_distance(h, self.target_hist[None], self.metric).mean(-1)
