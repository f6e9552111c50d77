"""Ground tiles (Dong 2007 Ch. 5): ω-tile sets, scan-line tiling, GA patch selection, graph-cut seams,
meaning embedment. Examples: scikit-image's grey textures (brick, grass, gravel)."""
import copy
from pathlib import Path

import numpy as np
import pytest
import skimage.data

from natscene.config import default_settings, load_yaml_config, validate_config
from natscene.errors import ConfigError
from natscene.tiles.blend import poisson_blend
from natscene.tiles.construct import construct, from_atlas, intermediate_tiles, to_atlas
from natscene.tiles.embed import embed, grabcut_object
from natscene.tiles.tile_ga import GAParams, MatchCost, evaluation, quarter_layout, run_tile_ga
from natscene.tiles.graphcut import (_tables, array_pair_values, axis_weights, build_tile, constraint_masks,
                                     intermediate_offsets, junction_extensions, merge, render,
                                     seam_energy, tile_energy)
from natscene.tiles.omega import (NG_16_TILES, _from_tuples, basic_set, build_lookup, dead_ends, extend,
                                  is_completable, tile_set)
from natscene.tiles.scanline import gather_texture, scanline_tiling, tiling_violations

ROOT = Path(__file__).resolve().parents[1]


def _example(name, size=96):
    """A size x size grey crop of a scikit-image texture (512x512), values in [0, 1]."""
    img = getattr(skimage.data, name)().astype(np.float32) / 255.0
    return np.ascontiguousarray(img[100:100 + size, 100:100 + size, None])


# ------------------------------------------------------------------------------------------ tile sets
def test_tile_set_sizes_and_paper_tiles():
    b, n1, n2 = tile_set("B"), tile_set("N1"), tile_set("N2")
    assert (b.m, n1.m) == (8, 17)                        # §5.3.2: 8 + 7 copies + 2 additional
    assert n2.m == 36 and n2.n == 6                      # P2 = {R, G, B, Y, C, M}; the thesis says 38
    tup = b.as_tuples()
    assert ("R", "G", "G", "B") in tup and ("B", "Y", "Y", "R") in tup
    assert set(tup) <= set(NG_16_TILES)                  # a subset of Ng et al.'s 16-tile set
    # every square appears equally often in B; only <R,G,G,B> lacks yellow; <B,Y,Y,R> is the one double yellow
    counts = {c: sum(t.count(c) for t in tup) for c in "RGBY"}
    assert set(counts.values()) == {8}
    assert [t for t in tup if "Y" not in t] == [("R", "G", "G", "B")]
    assert [t for t in tup if t.count("Y") == 2] == [("B", "Y", "Y", "R")]
    # N1 holds the additional tiles of step 4
    assert ("B", "C", "Y", "R") in n1.as_tuples() and ("B", "Y", "C", "R") in n1.as_tuples()
    for ts in (b, n1, n2):
        assert len(set(ts.as_tuples())) == ts.m


def test_n2_count_follows_the_extension_rule():
    """|N2| = |N1| + (N1 tiles holding R) + 2 (N1 tiles holding R twice), counted by hand; every
    completable 8-tile subset of Ng's 16-tile set that satisfies §5.3.2's statements has one double-red
    tile, so N2 has 36 tiles (38 would need two)."""
    n1 = tile_set("N1").as_tuples()
    assert tile_set("N2").m == len(n1) + sum("R" in t for t in n1) + 2 * sum(t.count("R") == 2 for t in n1)
    from itertools import combinations
    rest = [t for t in NG_16_TILES if t not in {("R", "G", "G", "B"), ("B", "Y", "Y", "R")}]
    found = []
    for extra in combinations(rest, 6):
        tiles = [("R", "G", "G", "B"), ("B", "Y", "Y", "R"), *extra]
        if [t for t in tiles if "Y" not in t] != [("R", "G", "G", "B")] or \
                [t for t in tiles if t.count("Y") > 1] != [("B", "Y", "Y", "R")]:
            continue
        ts = _from_tuples("b", tiles, list("RGBY"))
        if is_completable(ts):
            found.append((sum(t.count("R") == 2 for t in tiles), extend(extend(ts, "Y", "C", "N1"), "R", "M", "N2").m))
    assert sorted(found) == [(1, 36), (1, 36)]
    assert sorted(basic_set().as_tuples()) in [sorted(t) for t in [tile_set("B").as_tuples()]]


def _worst_recurrence(ts, n=30, seeds=3):
    """Largest fraction, over offsets up to 6 tiles, of positions holding the same tile."""
    out = {}
    for seed in range(seeds):
        g = scanline_tiling(ts, n, n, seed=seed)
        for dy in range(7):
            for dx in range(-6, 7):
                if (dy, dx) > (0, 0):
                    a = g[dy:, max(dx, 0):n + min(dx, 0)]
                    b = g[:n - dy, max(-dx, 0):n - max(dx, 0)]
                    out[dy, dx] = out.get((dy, dx), 0.0) + (a == b).mean() / seeds
    return max(out.values())


def test_repetition_falls_as_the_set_grows():
    """B has one tile per (TL, TR, BL) triple, so its scan-line tilings are fixed by the first row and
    column and periodic; each extension adds choices, so the worst recurrence of a tile drops."""
    b = tile_set("B")
    assert all(len(v) == 1 for v in build_lookup(b).interior.values())
    g = scanline_tiling(b, 20, 20, seed=0)
    assert (g[4:] == g[:-4]).all()
    worst = [_worst_recurrence(tile_set(n)) for n in ("B", "N2", "N4")]
    assert worst[0] == 1.0 and worst[0] > worst[1] > worst[2], worst
    assert worst[2] < 0.15, worst
    for n in ("N3", "N4"):
        assert is_completable(tile_set(n))


def test_completability_needs_the_additional_tiles():
    for name in ("B", "N1", "N2"):
        assert is_completable(tile_set(name)), dead_ends(tile_set(name))
    # N1' (N1 without the two additional tiles) meets yellow and cyan at once: dead ends (Fig. 5.4)
    n1 = tile_set("N1").as_tuples()
    n1p = [t for t in n1 if t not in {("B", "C", "Y", "R"), ("B", "Y", "C", "R")}]
    assert not is_completable(_from_tuples("N1'", n1p, list(tile_set("N1").colours)))
    # so does any strict subset of B
    b = basic_set().as_tuples()
    assert all(not is_completable(_from_tuples("sub", b[:k] + b[k + 1:], list("RGBY"))) for k in range(8))


@pytest.mark.parametrize("name", ["B", "N1", "N2"])
def test_tilings_obey_edge_constraints(name):
    ts = tile_set(name)
    for seed in range(12):
        for nx, ny in [(1, 1), (1, 9), (9, 1), (64, 64), (37, 5)]:
            grid = scanline_tiling(ts, nx, ny, seed=seed * 101 + nx)
            assert grid.shape == (ny, nx)
            assert tiling_violations(ts, grid) == 0
    big = scanline_tiling(ts, 64, 64, seed=5)
    assert len(np.unique(big)) == ts.m                   # all tiles get used
    assert not np.array_equal(big, scanline_tiling(ts, 64, 64, seed=6))
    assert np.array_equal(big, scanline_tiling(ts, 64, 64, seed=5))


def test_violation_counter_detects_a_broken_tiling():
    ts = tile_set("N2")
    grid = scanline_tiling(ts, 8, 8, seed=0)
    k = grid[3, 3]
    bad = next(j for j in range(ts.m) if tuple(ts.tiles[j]) != tuple(ts.tiles[k]))
    grid[3, 3] = bad
    assert tiling_violations(ts, grid) > 0


def test_gather_matches_pixel_loop_and_atlas_roundtrip():
    rng = np.random.default_rng(0)
    tiles = rng.random((5, 6, 6, 3)).astype(np.float32)
    grid = rng.integers(0, 5, (3, 4))
    out = gather_texture(tiles, grid, 22, 15)
    ref = np.empty((15, 22, 3), np.float32)
    for y in range(15):
        for x in range(22):
            ref[y, x] = tiles[grid[y // 6, x // 6], y % 6, x % 6]
    assert np.array_equal(out, ref)
    assert np.array_equal(from_atlas(to_atlas(tiles), 5, 6), tiles)


# ------------------------------------------------------------------------------------------ Eqs. 5.1-5.6
def _brute_C(example, tile, metric="color", mu=10.0):
    from numpy.lib.stride_tricks import sliding_window_view
    s = tile.shape[0]
    win = sliding_window_view(example, (s, s), axis=(0, 1)).transpose(0, 1, 3, 4, 2)
    d2 = ((win - tile) ** 2).sum(-1)
    if metric == "color":
        return d2.sum((2, 3))
    gy, gx = np.gradient(example, axis=(0, 1))
    wgy = sliding_window_view(gy, (s, s), axis=(0, 1)).transpose(0, 1, 3, 4, 2)
    wgx = sliding_window_view(gx, (s, s), axis=(0, 1)).transpose(0, 1, 3, 4, 2)
    return wgy, wgx, d2


def test_match_cost_equals_brute_force_eq_5_1_and_5_6():
    ex = _example("gravel", 40).astype(np.float64)
    s = 16
    ts = tile_set("B")
    genes = np.array([[0, 0], [10, 20], [24, 3], [17, 11]])
    tiles_px = intermediate_tiles(ex, genes, ts, s)
    D, arg = MatchCost(ex, s).tile_errors(genes, ts.tiles)
    for j in range(ts.m):
        C = _brute_C(ex, tiles_px[j])
        assert D[j] == pytest.approx(C.min(), rel=1e-9, abs=1e-9)
        assert C[tuple(arg[j])] == pytest.approx(C.min(), abs=1e-9)
    # Eq. 5.6 with the quarters' gradients taken from the example at their source pixels
    gy, gx = np.gradient(ex, axis=(0, 1))
    tg = intermediate_tiles(np.concatenate([gy, gx], -1), genes, ts, s)
    D6, _ = MatchCost(ex, s, "gradient_sum", mu=10.0).tile_errors(genes, ts.tiles)
    wgy, wgx, d2 = _brute_C(ex, tiles_px[2], "grad")
    C6 = d2.sum((2, 3)) + 10.0 * (((wgy - tg[2][..., :1]) ** 2).sum((2, 3, 4))
                                  + ((wgx - tg[2][..., 1:]) ** 2).sum((2, 3, 4)))
    assert D6[2] == pytest.approx(C6.min(), rel=1e-9)
    # Eq. 5.5: colour distance divided by mu (|grad T| + |grad I|)
    D5, _ = MatchCost(ex, s, "gradient_ratio", mu=10.0).tile_errors(genes, ts.tiles)
    gm = np.sqrt(gy ** 2 + gx ** 2)[..., 0]
    tgm = intermediate_tiles(gm[..., None], genes, ts, s)[2, ..., 0]
    from numpy.lib.stride_tricks import sliding_window_view
    wg = sliding_window_view(gm, (s, s))
    C5 = (d2 / (10.0 * (tgm + wg) + 1e-6)).sum((2, 3))
    assert D5[2] == pytest.approx(C5.min(), rel=1e-6)


def test_evaluation_eq_5_4():
    D = np.array([1.0, 2.0, 6.0])
    assert evaluation(D, 0.8) == pytest.approx(0.8 * 9.0 + 0.2 * np.var(D))
    assert evaluation(D, 1.0) == pytest.approx(9.0)


def test_ga_improves_on_random_selection():
    ex = _example("brick", 96)
    ts = tile_set("N1")
    ratios = []
    for seed in range(3):
        r = run_tile_ga(ex, ts, 48, default_settings(GAParams), seed=seed)
        assert r.E <= r.initial_best_E                      # never worse than its initial population
        assert all(a["best"] >= b["best"] for a, b in zip(r.log, r.log[1:]))
        assert len(r.log) - 1 <= default_settings(GAParams).n_g
        assert len({tuple(g) for g in r.genes}) == ts.n     # n distinct patches
        assert r.genes.min() >= 0 and (r.genes <= 96 - 48).all()
        assert r.E == pytest.approx(evaluation(r.D, 0.8))
        ratios.append(r.E / r.initial_mean_E)
    # E of a random selection = mean over the random initial population; measured ~0.77-0.81 for brick
    assert np.mean(ratios) < 0.9, ratios


# ------------------------------------------------------------------------------------------ graph cut
def test_graphcut_is_the_exact_minimum_of_the_seam_energy():
    """Max-flow labelling = brute-force minimum over all labellings of the free pixels (8x8 tile, 16
    free pixels), with the mid-line pairs priced by continued sources (submodular by the triangle
    inequality)."""
    rng = np.random.default_rng(0)
    s = 8
    for _ in range(3):
        A, B = rng.random((s, s, 3)), rng.random((s, s, 3))
        ext = tuple(rng.random((s, 3)) for _ in range(4))
        _, use_b, E = merge(A, B, 1.0, ext, core=2.2)
        keep_a, keep_b = constraint_masks(s, 1.0, 2.2)
        assert not use_b[keep_a].any() and use_b[keep_b].all()
        free = np.flatnonzero(~keep_a & ~keep_b)
        assert len(free) == 16
        tables = _tables(array_pair_values(A, ext), B)
        codes = np.arange(2 ** len(free))
        lab = np.broadcast_to(keep_b.ravel(), (len(codes), s * s)).copy()
        lab[:, free] = ((codes[:, None] >> np.arange(len(free))) & 1).astype(bool)
        lab = lab.reshape(-1, s, s)
        tot = np.zeros(len(lab))
        for axis, (aa, ab, ba) in tables.items():           # all labellings at once
            p = lab[:, :, :-1] if axis == 1 else lab[:, :-1]
            q = lab[:, :, 1:] if axis == 1 else lab[:, 1:]
            tot += (np.where(~p & ~q, aa, 0) + np.where(~p & q, ab, 0) + np.where(p & ~q, ba, 0)).sum((1, 2))
        best = tot.min()
        assert E == pytest.approx(best, abs=1e-9)
        assert seam_energy(tables, use_b) == pytest.approx(E)


def test_graphcut_respects_circle_and_prices_the_junction():
    rng = np.random.default_rng(1)
    A, B = rng.random((32, 32, 3)), rng.random((32, 32, 3))
    out, use_b, cost = merge(A, B, margin=1.0)
    keep_a, keep_b = constraint_masks(32, 1.0)
    assert not use_b[keep_a].any() and use_b[keep_b].all()
    assert np.array_equal(out[0], A[0].astype(np.float32))          # borders untouched
    assert np.array_equal(out[:, -1], A[:, -1].astype(np.float32))
    assert merge(A, A)[2] < 1e-9                                     # identical sources: nothing to pay
    # an intermediate tile of a real texture: pricing the junction (ext) erases more of it than treating
    # the tile as one image, and its cut is never worse under the true (junction-priced) energy
    img = _example("gravel", 96).astype(np.float64)
    genes = np.array([[0, 0], [40, 50], [60, 10], [20, 64]])
    s = 32
    tile = render(img, intermediate_offsets(genes, [0, 1, 2, 3], s))
    ext = junction_extensions(img, genes, [0, 1, 2, 3], s)
    patch = img[30:30 + s, 30:30 + s]
    _, with_j, e_j = merge(tile, patch, 1.0, ext)
    _, without_j, _ = merge(tile, patch, 1.0, None)
    true = _tables(array_pair_values(tile, ext), patch)
    assert e_j <= seam_energy(true, without_j) + 1e-9
    mid = np.zeros((s, s), bool)
    mid[:, s // 2 - 1:s // 2 + 1] = mid[s // 2 - 1:s // 2 + 1] = True
    assert with_j[mid].sum() > without_j[mid].sum()
    # the junction extensions are the quarters' patches one pixel past their edge (TL quarter = the
    # BR quarter of patch 0, continued to column s/2: patch column s)
    left, right, top, bottom = ext
    assert np.allclose(left[3], img[genes[0][0] + s // 2 + 3, genes[0][1] + s])
    assert np.allclose(right[3], img[genes[1][0] + s // 2 + 3, genes[1][1] - 1])
    assert np.allclose(top[20], img[genes[1][0] + s, genes[1][1] + 20 - s // 2])
    assert np.allclose(bottom[20], img[genes[3][0] - 1, genes[3][1] + 20 - s // 2])


def test_refinement_never_raises_the_seam_energy():
    ex = _example("gravel", 96).astype(np.float64)
    genes = np.array([[3, 7], [40, 44], [20, 0], [48, 30]])
    off0 = intermediate_offsets(genes, [0, 1, 2, 3], 48)
    cands = [(10, 10), (30, 5), (0, 40), (44, 44)]
    off1, _, e1, acc1 = build_tile(ex, off0, cands[:1])
    off, changed, e, acc = build_tile(ex, off0, cands, passes=2)
    assert e <= e1 + 1e-9 and acc[0] == acc1[0] == cands[0]
    assert e == pytest.approx(tile_energy(ex, off), rel=1e-9)       # reported = recomputed energy
    assert e < tile_energy(ex, off0)                                 # better than the raw junctions
    keep_a, _ = constraint_masks(48, 1.0)
    assert np.array_equal(off[keep_a], off0[keep_a])                 # tile border = sample patches


def _line_msd(tex, s, off):
    r = np.arange(off, tex.shape[0], s)
    r = r[r > 0]
    return 0.5 * (((tex[r] - tex[r - 1]) ** 2).mean() + ((tex[:, r] - tex[:, r - 1]) ** 2).mean())


@pytest.mark.parametrize("name", ["gravel", "grass", "brick"])
def test_synthesised_texture_has_no_visible_seams(name):
    ex = _example(name, 96)
    s, h = 48, 24
    b = construct(ex, tile_set("N1"), s, default_settings(GAParams, pop_size=12, n_g=6, n_o=3), seed=2)
    # outside the circle the tiles are the intermediate tiles (patch borders kept)
    keep_a, _ = constraint_masks(s, 1.0)
    assert np.array_equal(b.tiles[:, keep_a], b.intermediate[:, keep_a])
    grid = scanline_tiling(b.tileset, 10, 10, seed=3)
    tex = gather_texture(b.tiles, grid)[..., 0]
    # tile borders: every pair across a border is a pair of neighbouring example pixels (the patch
    # continues), checked on the texture against the example directly
    t = b.tileset.tiles[grid]                                        # (ny, nx, 4) corner colours
    g = b.ga.genes
    for j in range(1, 10):
        for i in range(10):
            gy, gx = g[t[j, i, 0]]                                   # TL colour: its patch spans the border
            assert np.allclose(tex[j * s - 1, i * s:i * s + h], ex[gy + h - 1, gx + h:gx + s, 0])
            assert np.allclose(tex[j * s, i * s:i * s + h], ex[gy + h, gx + h:gx + s, 0])
    # mid-lines: where four patches meet in the intermediate tiles; after junction removal the MSD
    # across them is like that across other interior lines, and far below the intermediate tiles'
    others = [_line_msd(tex, s, o) for o in range(1, s) if abs(o - h) > 3]
    mid = _line_msd(tex, s, h)
    raw = _line_msd(gather_texture(b.intermediate, grid)[..., 0], s, h)
    assert mid <= max(others), (mid / np.mean(others), max(others) / np.mean(others))
    assert mid < 0.4 * raw, (mid, raw)
    # and far below naive tiling of random example patches
    border = 0.5 * (_line_msd(tex, s, 0) + _line_msd(tex, s, 0))
    rng = np.random.default_rng(0)
    pos = rng.integers(0, 96 - s + 1, (100, 2))
    rand_tiles = np.stack([ex[y:y + s, x:x + s] for y, x in pos])
    naive_tex = gather_texture(rand_tiles, np.arange(100).reshape(10, 10))[..., 0]
    assert border < 0.5 * _line_msd(naive_tex, s, 0)


# ------------------------------------------------------------------------------------------ blending
def test_poisson_blend_removes_a_constant_step_and_keeps_the_border():
    """Example whose right half is its left half + 0.3: a tile from the left half with a disc from the
    right half has the same guidance everywhere as the left-half tile alone, so the Poisson solution
    with the border band fixed is exactly the left-half tile (the 0.3 step is gone); a single-source
    tile comes back unchanged."""
    rng = np.random.default_rng(4)
    left = rng.random((40, 40, 3))
    ex = np.concatenate([left, left + 0.3], 1)
    s = 32
    yy, xx = np.mgrid[0:s, 0:s]
    off = np.zeros((s, s, 2), np.int64) + [3, 4]
    disc = (yy - 14) ** 2 + (xx - 17) ** 2 < 8 ** 2
    off[disc, 1] += 40
    keep, _ = constraint_masks(s, 1.0, None, "square")
    assert keep.sum() == 4 * s - 4 and not keep[1:-1, 1:-1].any()
    plain = render(ex, off)
    assert np.ptp(plain[disc] - left[3:3 + s, 4:4 + s][disc]) < 1e-12       # raw: a 0.3 step
    out = poisson_blend(ex, off, keep)
    assert np.allclose(out, left[3:3 + s, 4:4 + s], atol=1e-9)
    assert np.array_equal(out[keep], plain[keep])
    one = np.zeros((s, s, 2), np.int64) + [5, 41]
    assert np.allclose(poisson_blend(ex, one, keep), render(ex, one), atol=1e-9)


def test_axis_weights_price_seams_across_the_grain():
    """Vertical stripes vary along x only: a horizontal seam (pairs along y, axis 0) crosses the
    stripes' smooth direction and costs more; transposing swaps the weights; isotropic noise ~ 1."""
    rng = np.random.default_rng(5)
    stripes = np.repeat(rng.random((1, 64, 1)), 64, 0) + 0.01 * rng.random((64, 64, 1))
    w = axis_weights(stripes)
    assert w[0] > 10 * w[1] and 0.5 * (1 / w[0] + 1 / w[1]) == pytest.approx(1.0)
    wt = axis_weights(stripes.transpose(1, 0, 2))
    assert wt[1] == pytest.approx(w[0]) and wt[0] == pytest.approx(w[1])
    wn = axis_weights(rng.random((128, 128, 3)))
    assert wn[0] == pytest.approx(1.0, abs=0.03) and wn[1] == pytest.approx(1.0, abs=0.03)
    # the bundled grass (upright blades): horizontal seams cost ~3x vertical ones
    from natscene.color import linear_to_srgb
    from natscene.io import read_photo
    g = axis_weights(linear_to_srgb(read_photo(ROOT / "resources/textures/grass_meadow_128.png")))
    assert g[0] > 2.5 * g[1]


def test_square_region_anisotropic_poisson_build_keeps_edges_and_hides_seams():
    """The pipeline's settings (square region, direction weights, Poisson blending) on an anisotropic
    texture (the brick crop varies ~2.4x more along x than along y): tile borders stay the sample patches' (tilings stay seamless
    across tiles), and the mid-line MSD is within the spread of the other interior lines and far below
    the intermediate tiles'."""
    ex = _example("brick", 96)
    s, h = 48, 24
    b = construct(ex, tile_set("N1"), s, default_settings(GAParams, pop_size=12, n_g=6, n_o=3), seed=2, region="square",
                  anisotropic=True, blend="poisson")
    keep = b.extra["keep"]
    assert keep.sum() == 4 * s - 4
    assert np.array_equal(b.tiles[:, keep], b.intermediate[:, keep])
    assert not np.array_equal(b.tiles[:, ~keep], b.intermediate[:, ~keep])
    dx, dy = np.abs(np.diff(ex, axis=1)).mean(), np.abs(np.diff(ex, axis=0)).mean()
    assert dx > 2 * dy and b.extra["axis_weights"][0] > 2 * b.extra["axis_weights"][1]   # this crop: x-varying
    grid = scanline_tiling(b.tileset, 10, 10, seed=3)
    tex = gather_texture(b.tiles, grid)[..., 0]
    others = [_line_msd(tex, s, o) for o in range(1, s) if abs(o - h) > 3]
    mid = _line_msd(tex, s, h)
    raw = _line_msd(gather_texture(b.intermediate, grid)[..., 0], s, h)
    assert mid <= max(others), (mid / np.mean(others), max(others) / np.mean(others))
    assert mid < 0.4 * raw, (mid, raw)
    with pytest.raises(ValueError):
        construct(ex, tile_set("B"), s, default_settings(GAParams, pop_size=4, n_g=1, n_o=1), blend="feather")


# ------------------------------------------------------------------------------------------ embedment
def test_meaning_embedment_changes_only_the_circle():
    rng = np.random.default_rng(3)
    src = 0.1 + 0.05 * rng.random((80, 80, 3)).astype(np.float32)
    yy, xx = np.mgrid[0:80, 0:80]
    src[(yy - 40) ** 2 + (xx - 40) ** 2 < 15 ** 2] = [0.8, 0.2, 0.1]
    obj, mask = grabcut_object(src, [15, 15, 50, 50])
    area = (mask > 0).sum()
    assert 0.8 * np.pi * 15 ** 2 < area < 1.25 * np.pi * 15 ** 2     # the disc, not the whole box
    tile = 0.3 + 0.02 * rng.random((48, 48, 3)).astype(np.float32)
    out = embed(tile, obj, mask, size=0.6)
    keep, _ = constraint_masks(48, 1.0)
    assert np.array_equal(out[keep], tile[keep])
    c = out[20:28, 20:28]
    assert c[..., 0].mean() > c[..., 1].mean() + 0.1                # reddish object at the centre


# ------------------------------------------------------------------------------------------ config
def test_config_section_validates_and_rejects_odd_tiles():
    schema = ROOT / "workflow" / "schemas" / "config.schema.yaml"
    cfg = validate_config(copy.deepcopy(load_yaml_config(ROOT / "config" / "config.yaml")), schema)
    g = cfg["tiles"]["grass"]
    assert g["ga"]["pop_size"] == 40 and g["ga"]["alpha"] == 0.05 and g["ga"]["lambda"] == 0.8
    bad = copy.deepcopy(load_yaml_config(ROOT / "config" / "smoke.yaml"))
    bad["tiles"]["grass"]["tile_size"] = 47
    with pytest.raises(ConfigError, match="tiles.grass.tile_size"):
        validate_config(bad, schema)
    with pytest.raises(ValueError):
        MatchCost(np.zeros((32, 32, 1)), 15)
