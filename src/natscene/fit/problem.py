"""
Fitting problem of the keyframe fit
===================================

Defines the fitting problem of Dobashi et al. (2012, §3, Eq. 1): argmin_c O(I_cg(c), I_usr).

-   :class:`FitProblem`: O(c) for a population of candidates, kappa_a searched per channel.
-   :func:`restrict_tables`: the tables kept only at the pixels of a mask, as a 1 x N image.
-   :func:`params_dict`: the scatter contract's parameters for a population.

Ties the precomputed tables (§4.3, ``natscene.scatter``), the photo's products (§4.1: cloud pixels, L_sky,
c_in) and the objective with its kappa_a line search (Eqs. 2-3) into one function of the five GA
parameters. For speed the tables are restricted once to the N pixels of the synthetic cloud footprint
(reshaped to a 1 x N image), so every candidate image is composed only where its histogram is taken.

References
----------
-   Dobashi, Y., Iwasaki, W., Ono, A., Yamamoto, T., Yue, Y., & Nishita, T. (2012). An inverse problem approach
    for automatically adjusting the parameters for rendering clouds using photographs. ACM Transactions on
    Graphics, 31(6).
"""
from __future__ import annotations

import copy
import dataclasses

import numpy as np

from natscene.fit.genetic import PARAMS, fit_params
from natscene.fit.kappa import KappaSearch
from natscene.fit.objective import Levels
from natscene.errors import InputError

__all__ = ["restrict_tables", "params_dict", "FitProblem"]


def restrict_tables(tables, mask: np.ndarray):
    """A copy of ``tables`` whose per-pixel arrays (trailing dims H, W) keep only ``mask`` pixels, as 1 x N."""
    mask = np.asarray(mask, bool)
    h, w = mask.shape
    idx = np.flatnonzero(mask)

    def cut(a):
        if isinstance(a, np.ndarray) and a.ndim >= 2 and a.shape[-2:] == (h, w):
            flat = a.reshape(a.shape[:-2] + (h * w,))
            return np.ascontiguousarray(flat[..., idx]).reshape(a.shape[:-2] + (1, len(idx)))
        return a

    if dataclasses.is_dataclass(tables):
        return dataclasses.replace(tables, **{f.name: cut(getattr(tables, f.name))
                                              for f in dataclasses.fields(tables) if f.init})
    out = copy.copy(tables)
    for k, v in vars(tables).items():
        setattr(out, k, cut(v))
    return out


def params_dict(values: np.ndarray, c_in, kappa=None, names: tuple = PARAMS, fixed: dict | None = None) -> dict:
    """The scatter contract's params for a population: values (P, n) in ``names`` order, plus the ``fixed``
    settings of the composition (all-orders transport: the sky dome's calibration and the ground albedo)."""
    v = np.atleast_2d(np.asarray(values, np.float64))
    d = {name: v[:, i].astype(np.float32) for i, name in enumerate(names)}
    d.setdefault("L_amb", np.zeros(len(v), np.float32))
    d["c_in"] = np.asarray(c_in, np.float32).reshape(3)
    d["kappa_a"] = (np.zeros((len(v), 3), np.float32) if kappa is None
                    else np.asarray(kappa, np.float32).reshape(len(v), 3))
    d.update(fixed or {})
    return d


class FitProblem:
    """O(c) for GA candidates c = (L_in, g, sigma_t, beta[, L_amb]) (:func:`natscene.fit.genetic.fit_params`
    of the tables' transport), kappa_a searched per channel; ``fixed``: settings composed with every candidate
    (all-orders transport: ``sky_scale``, ``ground_albedo``).

    ``tables``: a ``natscene.scatter.tables.Tables``; ``sky``, ``photo``: (H, W, 3) linear at the tables'
    resolution; ``photo_cloud``: (H, W) bool, the photo's cloud pixels; ``c_in``: (3,) sunlight colour.
    ``compose_cloud``/``apply_atmosphere`` default to ``natscene.scatter.compose``'s.
    """

    def __init__(self, tables, sky, photo, photo_cloud, c_in, levels: Levels | None = None,
                 metric: str = "difference", kappas=None, compose_cloud=None, apply_atmosphere=None,
                 source: str = "fit", fixed: dict | None = None):
        import natscene.scatter.compose as _c
        compose_cloud = compose_cloud or _c.compose_cloud
        apply_atmosphere = apply_atmosphere or _c.apply_atmosphere
        self.names = fit_params(getattr(tables, "transport", "dobashi"))
        self.fixed = dict(fixed or {})
        self.compose_cloud, self.apply_atmosphere = compose_cloud, apply_atmosphere
        self.tables = tables
        self.sky = np.asarray(sky, np.float32)
        self.photo = np.asarray(photo, np.float32)
        h, w = np.asarray(tables.t_c).shape
        for name, a in (("sky", self.sky), ("photo", self.photo)):
            if a.shape[:2] != (h, w):
                raise InputError(f"{source}: the {name} image is {a.shape[1]}x{a.shape[0]} but the precompute "
                                 f"tables are {w}x{h}; resample the sky products to the view's resolution")
        photo_cloud = np.asarray(photo_cloud, bool)
        if photo_cloud.shape != (h, w):
            raise InputError(f"{source}: the cloud mask is not {w}x{h} like the precompute tables")
        if not photo_cloud.any():
            raise InputError(f"{source}: the photo has no cloud pixels; check the sky extraction's mask")
        self.footprint = np.asarray(tables.footprint) > 0.5
        if not self.footprint.any():
            raise InputError(f"{source}: the synthetic cloud covers no pixel of the view; aim the camera at "
                             f"the volume")
        self.c_in = np.asarray(c_in, np.float32).reshape(3)
        self.sub = restrict_tables(tables, self.footprint)
        self.sky_sub = self.sky[self.footprint][None]  # (1, N, 3)
        target = self.photo[self.footprint] if metric == "pixel_ssd" else self.photo[photo_cloud]
        self.search = KappaSearch(self.sky[self.footprint], np.asarray(tables.t_c)[self.footprint], target,
                                  kappas=kappas, levels=levels, metric=metric)
        self.n_evaluations = 0

    @property
    def n_pixels(self) -> int:
        return self.search.n_pixels

    def cloud(self, values: np.ndarray) -> np.ndarray:
        """L_c (Eq. 4) at the footprint pixels: (P, N, 3)."""
        out = self.compose_cloud(self.sub, params_dict(values, self.c_in, names=self.names, fixed=self.fixed),
                                 self.sky_sub)
        out = np.asarray(out, np.float32)
        return out.reshape(out.shape[0], -1, 3)

    def __call__(self, values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(O (P,), kappa (P, 3)): the evaluate function of run_ga / gradient_descent."""
        values = np.atleast_2d(values)
        self.n_evaluations += len(values)
        return self.search.search(self.cloud(values))

    def render(self, values: np.ndarray, kappa: np.ndarray) -> np.ndarray:
        """Full synthetic images L_cg (Eq. 3 over Eq. 4) for parameter sets (P, n) and kappa (P, 3): (P, H, W, 3)."""
        params = params_dict(values, self.c_in, kappa, names=self.names, fixed=self.fixed)
        lc = np.asarray(self.compose_cloud(self.tables, params, self.sky), np.float32)
        return np.asarray(self.apply_atmosphere(lc, np.asarray(self.tables.t_c), params["kappa_a"], self.sky),
                          np.float32)
