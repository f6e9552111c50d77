"""
Gradient-descent baseline of the fit
====================================

Defines the baseline of Dobashi et al. (2012, §5.1, "the descent gradient method", after Snyman 2005):

-   :func:`gradient_descent`: minimise O by steepest descent; the ranked sets in a
    :class:`natscene.fit.genetic.FitResult`.

Steepest descent from a random start on the same five parameters and the same objective as the GA (the
kappa_a line search included in every evaluation). Parameters are scaled to the unit box by their ranges
(:class:`natscene.fit.genetic.UnitBox`: the extinction on a log scale);
the gradient is estimated by central finite differences with step ``h`` (in unit-box coordinates, clipped
at the box faces); the step along -grad/|grad| is chosen by a sampled line search over
``alpha = alpha0 * 2^-j`` (j = 0..n_alpha-1), taking the best point if it lowers O; the iterate is
projected onto the box. The descent stops at a zero gradient, when no step lowers O, after ``max_iter``
iterations, or when O < epsilon_O. The histogram objective is piecewise constant in the parameters, so
the method stalls in local minima and flat regions and depends on its start — the behaviour §5.1
reports.

References
----------
-   Dobashi, Y., Iwasaki, W., Ono, A., Yamamoto, T., Yue, Y., & Nishita, T. (2012). An inverse problem approach
    for automatically adjusting the parameters for rendering clouds using photographs. ACM Transactions on
    Graphics, 31(6).
-   Snyman, J. (2005). Practical Mathematical Optimization: An Introduction to Basic Optimization Theory and
    Classical and New Gradient-Based Algorithms. Springer.
"""
from __future__ import annotations

from typing import Callable

import numpy as np

from natscene.fit.genetic import DEFAULT_RANGES, PARAMS, Candidate, FitResult, UnitBox

__all__ = ["gradient_descent"]


def gradient_descent(evaluate: Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]], ranges: dict | None = None,
                     h: float = 0.01, alpha0: float = 0.25, n_alpha: int = 10, max_iter: int = 100,
                     epsilon_o: float = 0.0, seed: int = 0, start: np.ndarray | None = None,
                     progress: Callable[[int, float, float], None] | None = None,
                     names: tuple = PARAMS) -> FitResult:
    """Minimise O from a random (or given, in parameter units) start; returns a FitResult like the GA's."""
    ranges = {**DEFAULT_RANGES, **(ranges or {})}
    box = UnitBox(names, ranges)
    rng = np.random.default_rng(seed)
    n = len(names)
    u = rng.random(n) if start is None else box.to_unit(np.asarray(start, np.float64))

    def ev(us: np.ndarray):
        o, k = evaluate(box.from_unit(np.clip(us, 0, 1)))
        return np.asarray(o, np.float64), np.asarray(k)

    o, k = ev(u[None])
    cur_o, cur_k = float(o[0]), k[0]
    hist, evals, reason, it = [cur_o], 1, "max_iter", 0
    if progress:
        progress(0, cur_o, cur_o)
    alphas = alpha0 * 2.0 ** -np.arange(n_alpha)
    while it < max_iter:
        if epsilon_o > 0 and cur_o < epsilon_o:
            reason = "epsilon_O"
            break
        it += 1
        eye = np.eye(n) * h
        up, dn = np.clip(u + eye, 0, 1), np.clip(u - eye, 0, 1)
        o_fd, _ = ev(np.concatenate([up, dn]))
        evals += 2 * n
        width = (up - dn)[np.arange(n), np.arange(n)]
        grad = np.where(width > 0, (o_fd[:n] - o_fd[n:]) / np.where(width > 0, width, 1), 0.0)
        norm = np.linalg.norm(grad)
        if norm == 0:
            reason = "zero_gradient"
            hist.append(cur_o)
            break
        trial = np.clip(u[None] - alphas[:, None] * (grad / norm)[None], 0, 1)
        o_ls, k_ls = ev(trial)
        evals += n_alpha
        j = int(np.argmin(o_ls))
        if o_ls[j] >= cur_o:
            reason = "no_descent"
            hist.append(cur_o)
            break
        u, cur_o, cur_k = trial[j], float(o_ls[j]), k_ls[j]
        hist.append(cur_o)
        if progress:
            progress(it, cur_o, cur_o)
    best = Candidate(dict(zip(names, box.from_unit(u).tolist())), cur_o, cur_k, it)
    h_arr = np.array(hist)
    return FitResult(best, [best], h_arr, h_arr.copy(), it, evals, reason,
                     box.from_unit(u)[None], np.array([cur_o]))
