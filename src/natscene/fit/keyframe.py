"""
One keyframe fit end to end
===========================

Defines the fit of Dobashi et al. (2012, Fig. 2): photo products + tables -> ranked parameter sets.

-   :func:`fit_keyframe`: fit one keyframe with the GA or the §5.1 gradient baseline.
-   :func:`effective_ranges`: the configured search ranges, checked against the tables.
-   :func:`optical_depths`: the optical depth through the cloud at an extinction.

Reads nothing and writes nothing: the ``fit`` rule's script loads the inputs and writes what
:func:`fit_keyframe` returns. The GA (or the §5.1 gradient baseline) runs over FitProblem's O; the top-k
distinct sets are re-rendered as full images (Eq. 3 over Eq. 4) for the contact sheet.

References
----------
-   Dobashi, Y., Iwasaki, W., Ono, A., Yamamoto, T., Yue, Y., & Nishita, T. (2012). An inverse problem approach
    for automatically adjusting the parameters for rendering clouds using photographs. ACM Transactions on
    Graphics, 31(6).
"""
from __future__ import annotations

import time

import numpy as np

from natscene.fit.genetic import DEFAULT_RANGES, fit_params, run_ga
from natscene.fit.gradient import gradient_descent
from natscene.fit.kappa import kappa_grid
from natscene.fit.objective import Levels
from natscene.fit.problem import FitProblem
from natscene.fit.settings import FitSettings, check_extinction_range, fit_settings
from natscene.errors import InputError
from natscene.scatter.transport import get as get_transport

__all__ = ["effective_ranges", "optical_depths",
           "fit_keyframe"]


def effective_ranges(settings: dict | FitSettings, tables, log=None) -> dict:
    """The configured ranges: g clipped to the tables' g grid (no data outside it); the extinction (1/m) must lie
    inside the precomputed extinction grid, else InputError naming both keys."""
    settings = settings if isinstance(settings, FitSettings) else fit_settings(settings)
    names = fit_params(getattr(tables, "transport", "dobashi"))
    ranges = {p: tuple(float(x) for x in settings.ranges.get(p, DEFAULT_RANGES[p])) for p in names}
    for p, (lo, hi) in ranges.items():
        if hi < lo:
            raise InputError(f"config key 'fit.ranges.{p}': max {hi} is below min {lo}")
    check_extinction_range(ranges["extinction"], tables.extinction)
    lo, hi = ranges["g"]
    glo, ghi = float(np.min(tables.g)), float(np.max(tables.g))
    if lo < glo or hi > ghi:
        new = (max(lo, glo), min(hi, ghi))
        if new[1] < new[0]:
            raise InputError(f"config key 'fit.ranges.g': [{lo}, {hi}] lies outside the precomputed grid "
                             f"[{glo}, {ghi}]; widen precompute.g or change the range")
        if log:
            log(f"fit.ranges.g [{lo:g}, {hi:g}] clipped to the precomputed grid [{new[0]:g}, {new[1]:g}]")
        ranges["g"] = new
    return ranges


def optical_depths(extinction: float, columns: dict | None) -> dict:
    """The optical depth through the cloud at ``extinction`` (1/m): the precompute's columns ∫ rho ds in metres
    (meta ``column_m``: horizontal and vertical, mean / p95 / max over the rays that hit the cloud) times it."""
    if not columns:
        return {}
    return {axis: {k: round(float(extinction) * float(v), 3) for k, v in stats.items()}
            for axis, stats in columns.items()}


def fit_keyframe(tables, photo, photo_cloud, sky, c_in, settings: dict | FitSettings, seed: int = 0,
                 rank: int = 1, method: str | None = None, log=None, compose_cloud=None,
                 apply_atmosphere=None) -> dict:
    """Fit one keyframe. ``settings``: the ``fit`` config section (or its :class:`FitSettings`).
    Returns {result, problem, ranges, images (k, H, W, 3), chosen, params (yaml dict)}."""
    log = log or (lambda msg: None)
    st = settings if isinstance(settings, FitSettings) else fit_settings(settings)
    method = method or st.method
    kap = st.kappa
    if kap.max < kap.min:
        raise InputError("config key 'fit.kappa': max is below min")
    levels = Levels(st.n_levels, st.encoding)
    transport = getattr(tables, "transport", "dobashi")
    fixed = get_transport(transport).fit_fixed(tables, sky, st, log)
    problem = FitProblem(tables, sky, photo, photo_cloud, c_in, levels=levels,
                         metric=st.metric, kappas=kappa_grid(kap.min, kap.max, kap.step),
                         compose_cloud=compose_cloud, apply_atmosphere=apply_atmosphere, fixed=fixed)
    names = problem.names
    ranges = effective_ranges(st, tables, log)
    log(f"{problem.n_pixels} synthetic cloud pixels, {int(np.asarray(photo_cloud).sum())} photo cloud pixels, "
        f"method {method}")

    first = []       # when the initial population (iteration 0) is scored

    def progress(it, best, mean):
        if it == 0 and not first:
            first.append(time.perf_counter())
        if it % 10 == 0:
            log(f"iteration {it:3d}: best O {best:.4f}, mean O {mean:.4f}")

    t0 = time.perf_counter()
    if method == "ga":
        result = run_ga(problem, ranges, population=st.population, bits=st.bits, crossover_rate=st.crossover_rate,
                        mutation_rate=st.mutation_rate, scaling=st.scaling, epsilon_o=st.epsilon_o, n_suc=st.n_suc,
                        n_max=st.n_max, top_k=st.top_k, distinct_tol=st.distinct_tol, seed=seed, progress=progress,
                        names=names)
    elif method == "gradient":
        gs = st.gradient
        result = gradient_descent(problem, ranges, h=gs.h, alpha0=gs.alpha0, n_alpha=gs.n_alpha,
                                  max_iter=gs.max_iter, epsilon_o=st.epsilon_o, seed=seed, progress=progress,
                                  names=names)
    else:
        raise InputError(f"config key 'fit.method': unknown method {method!r} (ga or gradient)")
    seconds = time.perf_counter() - t0
    log(f"stopped after {result.iterations} iterations ({result.reason}), {result.evaluations} evaluations, "
        f"{seconds:.2f} s; best O {result.best.objective:.4f}")
    ranked = result.ranked
    if rank > len(ranked):
        raise InputError(f"keyframe rank {rank} but only {len(ranked)} distinct parameter sets were ranked; "
                         f"choose a rank <= {len(ranked)} or raise fit.top_k")
    vals = np.array([[c.values[p] for p in names] for c in ranked])
    kappas = np.array([c.kappa for c in ranked])
    images = problem.render(vals, kappas)

    def entry(i, c):
        # L_amb is a parameter of the Dobashi transport only; 0 keeps the keyframe contract for all_orders
        return {"rank": i + 1, "O": float(c.objective), "L_amb": 0.0, **{p: float(c.values[p]) for p in names},
                "kappa_a": [round(float(k), 6) for k in c.kappa], "iteration": int(c.iteration)}

    chosen = entry(rank - 1, ranked[rank - 1])
    extra = {k: np.asarray(v, np.float64).round(6).tolist() for k, v in fixed.items()}
    if first and result.iterations > 0:   # iteration 0 includes the kernels' compile on a first run (numba cache)
        log(f"{1000 * (t0 + seconds - first[0]) / result.iterations:.1f} ms per iteration after the first; the "
            f"initial population {first[0] - t0:.2f} s (with the kernels' compile where numba's cache is cold)")
    else:
        log(f"{1000 * seconds / max(result.iterations + 1, 1):.1f} ms per iteration")
    params = {
        "chosen": {**chosen, "c_in": [float(x) for x in np.asarray(c_in).reshape(3)], **extra},
        "ranked": [entry(i, c) for i, c in enumerate(ranked)],
        "transport": transport, "method": method, "seed": int(seed), "chosen_rank": int(rank),
        "iterations": int(result.iterations), "evaluations": int(result.evaluations),
        "termination": result.reason,
        "objective": {"metric": problem.search.metric, "n_levels": levels.n_levels, "encoding": levels.encoding,
                      "kappa_grid": problem.search.kappas.tolist()},
        "ranges": {p: list(r) for p, r in ranges.items()},
        "pixels": {"synthetic_cloud": problem.n_pixels, "photo_cloud": int(np.asarray(photo_cloud).sum())},
    }
    depth = optical_depths(chosen["extinction"], tables.meta.get("column_m"))
    if depth:
        params["optical_depth"] = depth
        h = depth["horizontal"]
        log(f"extinction {chosen['extinction']:.4g} /m: optical depth through the cloud, horizontal mean {h['mean']:.3g} "
            f"(p95 {h['p95']:.3g}, max {h['max']:.3g}), vertical mean {depth['vertical']['mean']:.3g}")
    return {"result": result, "problem": problem, "ranges": ranges, "images": images, "params": params}
