"""Tests of the fitting stage (Dobashi 2012 §3, §4.2, §5.1): objective, kappa search, GA, gradient baseline.

The precompute tables here are synthetic but physically shaped (a homogeneous sphere: closed-form
transmittance and ambient integral); the composition is a direct transcription of Eq. 4 so these tests do
not depend on the scatter stage. Tests against the real ``natscene.scatter`` run when it is importable.
"""
from __future__ import annotations

import cv2
import numpy as np
import pytest

from natscene.fit.genetic import PARAMS, Codec, UnitBox, run_ga, two_point_crossover, mutate, roulette
from natscene.fit.gradient import gradient_descent
from natscene.fit.kappa import KappaSearch, kappa_grid
from natscene.fit.objective import Levels, channel_distance, histograms, objective
from natscene.fit.problem import FitProblem, restrict_tables
from natscene.fit.synthetic import gradient_sky, sphere_tables
from natscene.color import srgb_to_linear


def _interp(grid, x):
    x = np.clip(x, grid[0], grid[-1])
    i = np.clip(np.searchsorted(grid, x, side="right") - 1, 0, len(grid) - 2)
    return i, (x - grid[i]) / (grid[i + 1] - grid[i])


def ref_compose_cloud(t, params, sky):
    """Eq. 4 (L_s + L_m + L_b) with linear interpolation in the extinction and g, transcribed directly."""
    out = []
    c_in = np.asarray(params["c_in"], np.float64)
    for p in range(len(params["L_in"])):
        L_in, g, st, beta, L_amb = (float(params[k][p]) for k in PARAMS)
        i, a = _interp(t.extinction, st)
        j, b = _interp(t.g, g)
        lerp = lambda arr: (1 - a) * arr[i] + a * arr[i + 1]  # noqa: E731
        s_sun, s_amb, tr = lerp(t.s_sun), lerp(t.s_amb), lerp(t.transmittance)
        geff = (1 - b) * t.g[j] + b * t.g[j + 1]
        phase = (1 - geff ** 2) / (4 * np.pi * (1 + geff ** 2 - 2 * geff * t.cos_theta) ** 1.5)
        em = sum(beta ** o * ((1 - b) * lerp(t.multiple[n, j]) + b * lerp(t.multiple[n, j + 1]))
                 for n, o in enumerate(t.orders))
        lum = L_in * beta * phase * s_sun + L_amb * s_amb + L_in * em
        out.append(lum[..., None] * c_in + tr[..., None] * sky)
    return np.stack(out).astype(np.float32)


def ref_apply_atmosphere(lc, t_c, kappa, sky):
    e = np.exp(-np.asarray(kappa)[:, None, None, :] * t_c[None, ..., None])
    return lc * e + (1 - e) * sky[None]


C_IN = np.array([1.0, 0.93, 0.82])


def make_problem(target_values, target_kappa, metric="difference", size=(96, 72)):
    t = sphere_tables(*size)
    sky = gradient_sky(*size)
    prob0 = FitProblem(t, sky, sky, np.ones(sky.shape[:2], bool), C_IN, compose_cloud=ref_compose_cloud,
                       apply_atmosphere=ref_apply_atmosphere)
    target = prob0.render(np.array([target_values]), np.array([target_kappa]))[0]
    mask = t.footprint > 0.5
    try:  # the vectorised composition of the scatter stage when present (checked equal to ref_compose_cloud below)
        from natscene.scatter.compose import compose_cloud as fast
    except ImportError:
        fast = ref_compose_cloud
    return FitProblem(t, sky, target, mask, C_IN, metric=metric, compose_cloud=fast,
                      apply_atmosphere=ref_apply_atmosphere), target


TRUE = [3.0, 0.45, 0.5, 0.9, 0.3]  # L_in, g, extinction, beta, L_amb
# the GA's ranges in these tests (the defaults are the physical ones): the extinction on its log scale
LINEAR = {"L_in": (0.0, 10.0), "g": (0.0, 1.0), "extinction": (0.01, 1.0), "beta": (0.0, 1.0), "L_amb": (0.0, 1.0)}
FIT_RANGES = LINEAR


# ------------------------------------------------------------------------------------------ objective
def test_levels_exact_on_8bit_codes_and_lut_close_to_formula():
    lv = Levels(256, "srgb")
    codes = np.arange(256)
    assert np.array_equal(lv(srgb_to_linear(codes / 255.0)), codes)
    x = np.random.default_rng(1).random(200_000).astype(np.float32) ** 2.2
    fast, exact = lv(x), lv.exact(x)
    assert np.abs(fast - exact).max() <= 1
    assert (fast == exact).mean() > 0.99  # only values within a lookup cell of a level boundary differ
    lin = Levels(64, "linear")
    assert np.array_equal(lin(np.array([0.0, 0.5 / 63 - 1e-4, 1.0, 7.0])), [0, 0, 63, 63])


def test_eq2_bounds_and_values():
    lv = Levels()
    a = np.full((100, 3), 0.2, np.float32)
    assert objective(a, a, lv) == 0.0
    assert objective(a, np.full((50, 3), 0.8, np.float32), lv) == pytest.approx(2.0)  # disjoint: sum |h| = 2
    b = a.copy()
    b[:25] = 0.8  # a quarter of the pixels moved to another level: 0.25 + 0.25 per channel
    assert objective(b, a, lv) == pytest.approx(0.5)


@pytest.mark.parametrize("metric,flag", [("correlation", cv2.HISTCMP_CORREL), ("chi_square", cv2.HISTCMP_CHISQR),
                                         ("intersection", cv2.HISTCMP_INTERSECT),
                                         ("bhattacharyya", cv2.HISTCMP_BHATTACHARYYA)])
def test_metrics_match_opencv_comparehist(metric, flag):
    rng = np.random.default_rng(2)
    for _ in range(5):
        t = rng.random(32) * (rng.random(32) > 0.3)
        h = rng.random(32) * (rng.random(32) > 0.3)
        t, h = t / t.sum(), h / h.sum()
        ref = cv2.compareHist(t.astype(np.float32), h.astype(np.float32), flag)
        ref = 1 - ref if metric in ("correlation", "intersection") else ref
        assert channel_distance(h, t, metric) == pytest.approx(ref, abs=1e-5)


def test_emd_matches_opencv():
    rng = np.random.default_rng(3)
    n = 24
    pos = (np.arange(n) / (n - 1)).astype(np.float32)
    for _ in range(5):
        t, h = rng.random(n), rng.random(n)
        t, h = t / t.sum(), h / h.sum()
        ref = cv2.EMD(np.stack([t, pos], 1).astype(np.float32), np.stack([h, pos], 1).astype(np.float32),
                      cv2.DIST_L1)[0]
        assert channel_distance(h, t, "emd") == pytest.approx(ref, abs=1e-4)


def test_histograms_normalised():
    lv = np.random.default_rng(4).integers(0, 16, size=(2, 3, 50))
    h = histograms(lv, 16)
    assert h.shape == (2, 3, 16) and np.allclose(h.sum(-1), 1)
    assert h[1, 2, 5] == pytest.approx(np.mean(lv[1, 2] == 5))


# ------------------------------------------------------------------------------------------ kappa
def test_kappa_grid_is_papers():
    assert np.allclose(kappa_grid(), np.arange(11) / 10)


@pytest.mark.parametrize("metric", ["difference", "emd", "pixel_ssd"])
def test_kappa_search_equals_bruteforce_joint_search(metric):
    prob, _ = make_problem(TRUE, [0.3, 0.5, 0.7], metric=metric, size=(40, 30))
    vals = np.array([TRUE, [6.0, 0.7, 0.9, 0.95, 0.1]])
    cloud = prob.cloud(vals)
    o, kap = prob.search.search(cloud)
    ks = kappa_grid()
    grid = np.stack(np.meshgrid(ks, ks, ks, indexing="ij"), -1).reshape(-1, 3)  # 1331 joint triples
    for p in range(len(vals)):
        oj = prob.search.evaluate(np.repeat(cloud[p:p + 1], len(grid), 0), grid)
        assert o[p] == pytest.approx(oj.min(), rel=1e-6, abs=1e-12)
        assert prob.search.evaluate(cloud[p:p + 1], kap[p:p + 1])[0] == pytest.approx(oj.min(), rel=1e-6, abs=1e-12)
    assert np.allclose(kap[0], [0.3, 0.5, 0.7]) and o[0] == pytest.approx(0.0, abs=1e-12)


def test_restricted_composition_equals_full_image_at_footprint():
    t = sphere_tables()
    sky = gradient_sky()
    m = t.footprint > 0.5
    params = {"c_in": C_IN, **{k: np.array([v]) for k, v in zip(PARAMS, TRUE)}}
    full = ref_compose_cloud(t, params, sky)[0][m]
    sub = ref_compose_cloud(restrict_tables(t, m), params, sky[m][None])[0, 0]
    assert np.allclose(full, sub)


def test_bad_inputs_are_named():
    from natscene.errors import InputError
    t = sphere_tables()
    sky = gradient_sky()
    with pytest.raises(InputError, match="no cloud pixels"):
        FitProblem(t, sky, sky, np.zeros(sky.shape[:2], bool), C_IN, compose_cloud=ref_compose_cloud,
                   apply_atmosphere=ref_apply_atmosphere)
    with pytest.raises(InputError, match="resample"):
        FitProblem(t, sky[:10], sky, np.ones(sky.shape[:2], bool), C_IN, compose_cloud=ref_compose_cloud,
                   apply_atmosphere=ref_apply_atmosphere)


# ------------------------------------------------------------------------------------------ GA
def test_codec_quantises_32_bits_and_round_trips():
    codec = Codec(UnitBox(("L_in", "g"), {"L_in": (0, 10), "g": (0, 1)}), bits=32)
    assert codec.length == 64
    v = np.array([[0.0, 1.0], [10.0, 0.0], [3.14159, 0.271828]])
    back = codec.decode(codec.encode(v))
    assert np.allclose(back, v, atol=10 / 2 ** 32 * 1.01)
    assert np.array_equal(codec.decode(np.ones((1, 64), np.uint8)), [[10.0, 1.0]])


def test_extinction_is_searched_on_a_log_scale():
    """The extinction (1/m) spans two decades: equal steps of the code are equal ratios, each decade of
    [0.002, 0.3] gets the same share of the codes, and the ends decode exactly."""
    box = UnitBox(("g", "extinction"), {"g": (0.0, 1.0), "extinction": (0.002, 0.3)})
    u = np.array([[0.0, 0.0], [0.5, 0.5], [1.0, 1.0]])
    v = box.from_unit(u)
    assert np.allclose(v[:, 1], [0.002, np.sqrt(0.002 * 0.3), 0.3], rtol=1e-12)
    assert np.allclose(v[:, 0], [0.0, 0.5, 1.0])
    assert np.allclose(box.to_unit(v), u, atol=1e-12)
    codec = Codec(box, bits=8)
    k = np.arange(256)[:, None]
    genes = ((k >> np.arange(7, -1, -1)) & 1).astype(np.uint8)
    ext = codec.decode(np.concatenate([np.zeros_like(genes), genes], 1))[:, 1]
    assert np.allclose(ext[1:] / ext[:-1], (0.3 / 0.002) ** (1 / 255), rtol=1e-9)
    with pytest.raises(ValueError, match="above 0"):
        UnitBox(("extinction",), {"extinction": (0.0, 0.3)})


def test_two_point_crossover_swaps_one_segment():
    rng = np.random.default_rng(5)
    a, b = np.zeros((200, 40), np.uint8), np.ones((200, 40), np.uint8)
    ca, cb = two_point_crossover(a, b, rng)
    assert np.array_equal(ca ^ cb, np.ones_like(ca))  # every position comes from one parent each
    switches = np.abs(np.diff(ca.astype(int), axis=1)).sum(1)
    assert switches.max() <= 2 and (switches == 2).mean() > 0.5  # one contiguous swapped segment


def test_mutation_rate_and_roulette_proportions():
    rng = np.random.default_rng(6)
    g = mutate(np.zeros((1000, 160), np.uint8), 0.01, rng)
    assert g.mean() == pytest.approx(0.01, rel=0.1)
    idx = roulette(np.array([1.0, 3.0]), 20000, rng)
    assert np.mean(idx == 1) == pytest.approx(0.75, abs=0.02)


def test_ga_minimises_analytic_function_with_elitism_and_is_repeatable():
    target = np.array([7.0, 0.2, 0.6, 0.4, 0.8])
    span = np.array([10, 1, 1, 1, 1.0])

    def f(v):
        return np.abs((v - target) / span).sum(1), np.zeros((len(v), 3))

    r1 = run_ga(f, LINEAR, seed=11, epsilon_o=0, n_suc=0, n_max=100)
    r2 = run_ga(f, LINEAR, seed=11, epsilon_o=0, n_suc=0, n_max=100)
    assert np.all(np.diff(r1.best_history) <= 0)  # elitism: best never gets worse
    assert r1.best.objective < 0.25 * r1.best_history[0]
    assert r1.evaluations == 20 + 100 * 19
    assert np.array_equal(r1.best_history, r2.best_history) and r1.best.values == r2.best.values
    objs = [c.objective for c in r1.ranked]
    assert objs == sorted(objs) and len(objs) == 10
    vals = np.array([[c.values[p] for p in PARAMS] for c in r1.ranked])
    d = np.abs(vals[:, None] - vals[None]) / span
    assert np.all(d.max(-1)[~np.eye(10, dtype=bool)] > 0.01)  # distinct sets


def test_ga_termination_criteria():
    const = lambda v: (np.full(len(v), 0.7), np.zeros((len(v), 3)))  # noqa: E731
    r = run_ga(const, n_suc=20, n_max=100, epsilon_o=0.5)
    assert r.reason == "n_suc" and r.iterations == 20
    r = run_ga(lambda v: (np.full(len(v), 0.3), np.zeros((len(v), 3))), epsilon_o=0.5)
    assert r.reason == "epsilon_O" and r.iterations == 0


def test_gradient_descent_finds_smooth_minimum():
    target = np.array([4.0, 0.3, 0.5, 0.6, 0.2])

    def f(v):
        return (((v - target) / [10, 1, 1, 1, 1]) ** 2).sum(1), np.zeros((len(v), 3))

    r = gradient_descent(f, LINEAR, seed=3, max_iter=200)
    assert r.best.objective < 1e-3


# ------------------------------------------------------------------------------------------ fit
def test_ga_recovers_synthetic_target_image():
    prob, target = make_problem(TRUE, [0.2, 0.2, 0.2])
    r = run_ga(prob, FIT_RANGES, seed=0, epsilon_o=0, n_suc=0, n_max=100)
    assert r.best.objective <= 0.1
    best = prob.render(np.array([[r.best.values[p] for p in PARAMS]]), r.best.kappa[None])[0]
    m = prob.footprint
    assert np.abs(best[m] - target[m]).mean() < 0.05 * target[m].mean()
    # the same seed gives the same result
    prob2, _ = make_problem(TRUE, [0.2, 0.2, 0.2])
    ra = run_ga(prob, FIT_RANGES, seed=1, epsilon_o=0, n_suc=0, n_max=10)
    rb = run_ga(prob2, FIT_RANGES, seed=1, epsilon_o=0, n_suc=0, n_max=10)
    assert rb.best.values == ra.best.values and np.array_equal(rb.best.kappa, ra.best.kappa)
    assert np.array_equal(ra.best_history, rb.best_history)


def test_atmosphere_blend_matches_scatter_contract():
    compose = pytest.importorskip("natscene.scatter.compose")
    prob, _ = make_problem(TRUE, [0.2, 0.2, 0.2])
    vals = np.array([TRUE, [2.0, 0.2, 0.3, 0.7, 0.5]])
    cloud = prob.cloud(vals)
    kap = np.array([[0.1, 0.4, 0.9], [0.0, 1.0, 0.5]])
    mine = prob.search.blend(cloud, kap)
    theirs = compose.apply_atmosphere(cloud[:, None], prob.search.t_c[None, :], kap, prob.search.sky.T[None])
    assert np.allclose(mine, np.asarray(theirs)[:, 0], rtol=1e-5, atol=1e-6)


def test_real_compose_on_restricted_tables_equals_full_image():
    compose = pytest.importorskip("natscene.scatter.compose")
    tables_mod = pytest.importorskip("natscene.scatter.tables")
    t = sphere_tables()
    tab = tables_mod.Tables(t.extinction, t.g, t.orders, t.s_sun, t.s_amb, t.transmittance, t.multiple, t.t_c,
                            t.cos_theta, t.footprint)
    sky = gradient_sky()
    prob = FitProblem(tab, sky, sky, tab.footprint > 0.5, C_IN)  # the real compose_cloud / apply_atmosphere
    vals = np.array([TRUE, [2.0, 0.2, 0.3, 0.7, 0.5]])
    full = prob.render(vals, np.zeros((2, 3)))
    assert np.allclose(prob.cloud(vals), full[:, prob.footprint], rtol=1e-5, atol=1e-6)
    mine = ref_compose_cloud(t, {"c_in": C_IN, **{k: vals[:, i] for i, k in enumerate(PARAMS)}}, sky)
    assert np.allclose(full, mine, rtol=1e-4, atol=1e-5)  # the contract's Eq. 4 = this file's transcription


@pytest.mark.parametrize("n_levels", [256, 1024])
def test_numba_and_numpy_backends_count_identically(n_levels):
    """The compiled search (its level table narrowed to 8 or 16 bits) counts what the numpy one does."""
    from natscene.fit import kappa as kmod
    if kmod._nb is None:
        pytest.skip("numba not importable")
    rng = np.random.default_rng(9)
    n = 3000
    sky = rng.random((n, 3)).astype(np.float32) * 0.6
    t_c = rng.random(n).astype(np.float32) * 1.5
    target = rng.random((500, 3)).astype(np.float32)
    cloud = (rng.random((7, n, 3)) * 1.3).astype(np.float32)  # some values saturate above 1
    levels = Levels(n_levels)
    a = KappaSearch(sky, t_c, target, levels=levels, backend="numpy").channel_distances(cloud)
    b = KappaSearch(sky, t_c, target, levels=levels, backend="numba").channel_distances(cloud)
    assert np.array_equal(a, b)
