"""Ground tiles (Dong 2007 Ch. 5): ω-tile sets, scan-line tiling, GA patch selection, graph-cut seams,
meaning embedment. Examples: scikit-image's grey textures (brick, grass, gravel)."""
import copy
from pathlib import Path

import numpy as np
import pytest
import skimage.data

from natscene.config import ConfigError, load_yaml_config, validate_config
from natscene.tiles.construct import construct, from_atlas, intermediate_tiles, to_atlas
from natscene.tiles.embed import embed, grabcut_object
from natscene.tiles.genetic import GAParams, MatchCost, evaluation, quarter_layout, run_ga
from natscene.tiles.graphcut import constraint_masks, merge
from natscene.tiles.omega import _from_tuples, basic_set, dead_ends, is_completable, tile_set
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
    assert n2.m == 36 and n2.n == 6                      # P2 = {R, G, B, Y, C, M}
    tup = b.as_tuples()
    assert ("R", "G", "G", "B") in tup and ("B", "Y", "Y", "R") in tup
    # every square appears equally often in B; only <R,G,G,B> lacks yellow; <B,Y,Y,R> is the one double yellow
    counts = {c: sum(t.count(c) for t in tup) for c in "RGBY"}
    assert set(counts.values()) == {8}
    assert [t for t in tup if "Y" not in t] == [("R", "G", "G", "B")]
    assert [t for t in tup if t.count("Y") == 2] == [("B", "Y", "Y", "R")]
    # N1 holds the additional tiles of step 4
    assert ("B", "C", "Y", "R") in n1.as_tuples() and ("B", "Y", "C", "R") in n1.as_tuples()
    for ts in (b, n1, n2):
        assert len(set(ts.as_tuples())) == ts.m


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
        r = run_ga(ex, ts, 48, GAParams(), seed=seed)
        assert r.E <= r.initial_best_E                      # never worse than its initial population
        assert all(a["best"] >= b["best"] for a, b in zip(r.log, r.log[1:]))
        assert len(r.log) - 1 <= GAParams().n_g
        assert len({tuple(g) for g in r.genes}) == ts.n     # n distinct patches
        assert r.genes.min() >= 0 and (r.genes <= 96 - 48).all()
        assert r.E == pytest.approx(evaluation(r.D, 0.8))
        ratios.append(r.E / r.initial_mean_E)
    # E of a random selection = mean over the random initial population; measured ~0.77-0.81 for brick
    assert np.mean(ratios) < 0.9, ratios


# ------------------------------------------------------------------------------------------ graph cut
def test_graphcut_respects_circle_and_cross():
    rng = np.random.default_rng(1)
    A, B = rng.random((32, 32, 3)), rng.random((32, 32, 3))
    out, use_b, cost = merge(A, B, margin=1.0)
    keep_a, keep_b = constraint_masks(32, 1.0)
    assert not use_b[keep_a].any() and use_b[keep_b].all()
    assert np.array_equal(out[0], A[0].astype(np.float32))          # borders untouched
    assert np.array_equal(out[:, -1], A[:, -1].astype(np.float32))
    # identical sources: nothing to pay; a smooth seam is cheaper than a random one
    assert merge(A, A)[2] < 1e-6
    assert merge(A, A + 0.01)[2] < cost


@pytest.mark.parametrize("name", ["gravel", "grass", "brick"])
def test_synthesised_texture_has_no_visible_seams(name):
    ex = _example(name, 96)
    s = 48
    b = construct(ex, tile_set("N1"), s, GAParams(pop_size=12, n_g=6, n_o=3), seed=2)
    # outside the circle the tiles are the intermediate tiles (patch borders kept)
    keep_a, _ = constraint_masks(s, 1.0)
    assert np.array_equal(b.tiles[:, keep_a], b.intermediate[:, keep_a])
    grid = scanline_tiling(b.tileset, 10, 10, seed=3)
    tex = gather_texture(b.tiles, grid)[..., 0]

    def msd(img, axis, at):
        d = np.diff(img, axis=axis) ** 2
        idx = np.arange(d.shape[axis])
        sel = np.isin(idx % s, at)
        return d[:, sel].mean() if axis == 1 else d[sel].mean()

    inside = 0.5 * (msd(tex, 1, np.arange(s - 1)) + msd(tex, 0, np.arange(s - 1)))
    border = 0.5 * (msd(tex, 1, [s - 1]) + msd(tex, 0, [s - 1]))
    # naive: random example patches tiled side by side
    rng = np.random.default_rng(0)
    pos = rng.integers(0, 96 - s + 1, (100, 2))
    rand_tiles = np.stack([ex[y:y + s, x:x + s] for y, x in pos])
    naive_tex = gather_texture(rand_tiles, np.arange(100).reshape(10, 10))[..., 0]
    naive = 0.5 * (msd(naive_tex, 1, [s - 1]) + msd(naive_tex, 0, [s - 1]))
    assert border < 1.5 * inside, (border, inside)
    assert border < 0.5 * naive, (border, naive)


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
