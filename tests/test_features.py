"""Feature-aware texture analysis and synthesis (Dong 2007 Ch. 6; natscene.features), against what is known
independently of the code:

- scale maps against a known perspective: a frontal texture (scikit-image's brick and gravel) warped by a
  homography has the local scale sqrt(|det J|) of the homography (analytic); the map from a feature mask (Eq. 6.1)
  and the one from the slant and tilt (Eq. 6.2) follow it;
- synthesis measured from its output: the local texel size (the width of each window's autocorrelation peak, no
  code of the stage involved) follows the target scale map with lambda = 0.5 and not with lambda = 0;
- the energy of Eq. 6.3 never increases from one EM iteration to the next;
- hierarchical quilting follows the same target by the same measure, splits cells only where the target varies,
  and pastes a periodic example seamlessly (every output pixel a copy of the pattern at one common phase);
- tight type constraints put the example's type region where the target's type map has it (IoU);
- Reinhard's colour transfer gives each region its saved statistics (CIEDE2000 from colour-science);
- completion keeps the scale trend of the photo through the hole, where OpenCV's inpainting does not.
"""
import colour
import cv2
import numpy as np
import pytest
from skimage import data

from natscene.config import default_settings
from natscene.errors import InputError
from natscene.features.colour import (lab_rs_to_rgb, recolour_regions, region_colours, region_stats, rgb_to_lab_rs,
                                      segment, transfer_to_largest)
from natscene.features.completion import complete, inpaint_baseline
from natscene.features.optimisation import OptimisationSettings, synthesise
from natscene.features.quilting import QuiltingSettings, cells, quilt
from natscene.features.scale import copy_region, scale_from_angles, scale_from_mask, scale_preview, scale_region
from natscene.features.type_map import type_map


def _perspective(tex, size, top=(0.3, 0.7)):
    """``tex`` warped to size x size by the homography that maps its square to a trapezoid narrowing toward the
    top (mirrored at the borders, so the frame is full), and the homography's local scale sqrt(|det J|)."""
    S = size
    h0, w0 = tex.shape[:2]
    src = np.float32([[0, 0], [w0, 0], [w0, h0], [0, h0]])
    dst = np.float32([[S * top[0], 0], [S * top[1], 0], [S, S], [0, S]])
    hm = cv2.getPerspectiveTransform(src, dst)
    warped = cv2.warpPerspective(tex, hm, (S, S), flags=cv2.INTER_AREA, borderMode=cv2.BORDER_REFLECT)
    hinv = np.linalg.inv(hm)
    yy, xx = np.mgrid[0:S, 0:S] + 0.5
    d = hinv[2, 0] * xx + hinv[2, 1] * yy + hinv[2, 2]
    return warped, 1.0 / np.sqrt(np.abs(np.linalg.det(hinv) / d ** 3))


def _corr(a, b):
    return float(np.corrcoef(np.ravel(a), np.ravel(b))[0, 1])


def texel_width(img, win=48, step=16):
    """Local texel size: per window on a grid of ``step``, the radius at which the radially averaged
    autocorrelation of the (Hann-windowed, mean-free) window falls to half its peak (linear between radii)."""
    g = img.mean(-1) if img.ndim == 3 else img
    hann = np.outer(np.hanning(win), np.hanning(win))
    yy, xx = np.mgrid[0:win, 0:win]
    rb = np.round(np.hypot(np.minimum(yy, win - yy), np.minimum(xx, win - xx))).astype(int).ravel()
    count = np.bincount(rb)
    out = []
    for y in range(0, g.shape[0] - win + 1, step):
        row = []
        for x in range(0, g.shape[1] - win + 1, step):
            p = (g[y:y + win, x:x + win] - g[y:y + win, x:x + win].mean()) * hann
            ac = np.real(np.fft.ifft2(np.abs(np.fft.fft2(p)) ** 2))
            prof = np.bincount(rb, ac.ravel()) / count / max(ac[0, 0], 1e-12)
            k = int(np.argmax(prof < 0.5)) if (prof < 0.5).any() else len(prof) - 1
            row.append(k - 1 + (prof[k - 1] - 0.5) / (prof[k - 1] - prof[k]) if k > 0 else 0.0)
        out.append(row)
    return np.array(out)


def _window_means(a, win=48, step=16):
    return np.array([[a[y:y + win, x:x + win].mean() for x in range(0, a.shape[1] - win + 1, step)]
                     for y in range(0, a.shape[0] - win + 1, step)])


# ------------------------------------------------------------------------------------------- scale (§6.3)
@pytest.mark.parametrize("name", ["brick", "gravel"])
def test_scale_maps_follow_a_known_homography(name):
    """Eq. 6.1 on the Canny edges of the warped texture (n = 64 and a 31-pixel Gaussian: the neighbourhood a user
    picks for texels of ~40 pixels) and Eq. 6.2 at the plane's slant (tilt 0: scale varies up the image) both
    correlate >= 0.9 with the homography's local scale."""
    tex = getattr(data, name)().astype(np.float32) / 255.0
    warped, truth = _perspective(tex, 512)
    core = (slice(48, -48), slice(48, -48))
    edges = cv2.Canny((warped * 255).astype(np.uint8), 50, 150) > 0
    from_mask = scale_from_mask(edges, n=64, gaussian=31)
    from_angles = scale_from_angles(512, 512, 60.0, 0.0)
    assert _corr(from_mask[core], truth[core]) >= 0.9
    assert _corr(from_angles[core], truth[core]) >= 0.9


def test_eq_6_2_runs_from_s_max_to_s_min():
    """Slant 60 deg: 1/cos = 2 at the bottom-left origin, cos = 0.5 at the far corner; tilt 90 deg turns the ramp
    to run along x."""
    s = scale_from_angles(200, 100, 60.0, 0.0)
    assert s[-1, 0] == pytest.approx(2.0, rel=0.02) and s[0, 0] == pytest.approx(0.5, rel=0.02)
    assert np.allclose(s, s[:, :1])  # tilt 0: constant along rows
    t = scale_from_angles(200, 100, 60.0, 90.0)
    assert t[0, 0] == pytest.approx(2.0, rel=0.02) and t[0, -1] == pytest.approx(0.5, rel=0.02)
    assert np.allclose(scale_from_angles(64, 64, 0.0, 30.0), 1.0)


def test_eq_6_1_scale_is_one_at_the_middle_count_and_smooth():
    """Scale 1 where the neighbourhood count is a_mid; a denser mask half reads smaller texels."""
    m = np.zeros((128, 256), bool)
    m[:, :128:4] = True    # dense lines: small texels
    m[:, 128::8] = True    # sparse lines: large texels
    s = scale_from_mask(m, n=32, gaussian=13)
    assert s[:, 20:100].mean() < 1.0 < s[:, 150:230].mean()
    # counts per 32 x 32 window: 256 (dense) and 128 (sparse), a_mid = 192: scales 0.75 and 1.5
    assert s[:, 20:100].mean() == pytest.approx(0.75, rel=0.02)
    assert s[:, 150:230].mean() == pytest.approx(1.5, rel=0.02)


def test_scale_edits():
    s = np.ones((64, 64), np.float32)
    region = np.zeros((64, 64), bool)
    region[:32] = True
    e = scale_region(s, region, 2.0)
    assert e[:32].min() == 2.0 and e[32:].max() == 1.0
    c = copy_region(e, (0, 0, 16, 16), (40, 40))
    assert (c[40:56, 40:56] == 2.0).all() and c[39, 39] == 1.0
    assert scale_preview(np.array([1.0, 2.0, 0.5])).tolist() == [0.5, 1.0, 0.0]
    with pytest.raises(InputError, match="leaves"):
        copy_region(e, (0, 0, 16, 16), (60, 60))


# --------------------------------------------------------------------------------------- synthesis (§6.6)
@pytest.fixture(scope="module")
def perspective_example():
    tex = cv2.resize(data.gravel().astype(np.float32) / 255.0, (256, 256), interpolation=cv2.INTER_AREA)
    ex, truth = _perspective(tex, 192, top=(0.25, 0.75))
    return np.repeat(ex[..., None], 3, -1), scale_from_angles(192, 192, 60.0, 0.0)


@pytest.fixture(scope="module")
def scale_aware(perspective_example):
    ex, scale = perspective_example
    H, W = 192, 384
    f_ex = scale_preview(scale)
    # a user-specified target (§6.6.2) the example's layout does not give by itself: large texels on the left,
    # small on the right (the example's scales, the outer 15 % at each end left out, turned by 90 deg)
    hi, lo = np.percentile(f_ex, [85, 15])
    f_t = np.broadcast_to(np.linspace(hi, lo, W, dtype=np.float32), (H, W)).copy()
    st = dict(levels=3, sizes=(32, 16, 8), iterations=4)
    return {lam: synthesise(ex, (H, W), f_ex, f_t, default_settings(OptimisationSettings, lam=lam, **st))
            for lam in (0.5, 0.0)}, f_t


def test_scale_aware_synthesis_follows_its_target(scale_aware):
    """The output's local texel width (autocorrelation) correlates >= 0.8 with the target scale map at
    lambda = 0.5, and plain texture optimisation (lambda = 0) does not (<= 0.3)."""
    results, f_t = scale_aware
    target = _window_means(f_t)
    with_features = _corr(texel_width(results[0.5].image), target)
    plain = _corr(texel_width(results[0.0].image), target)
    print(f"texel width vs target scale: lambda 0.5 {with_features:.3f}, lambda 0 {plain:.3f}")
    assert with_features >= 0.8
    assert plain <= 0.3


def test_quilting_follows_its_target(perspective_example, scale_aware):
    """Hierarchical quilting (alpha 0.5) on the same example and target: the output's texel width correlates
    >= 0.8 with the target scale map, as texture optimisation's does."""
    ex, scale = perspective_example
    _, f_t = scale_aware
    res = quilt(ex, f_t.shape, scale_preview(scale), f_t, default_settings(QuiltingSettings))
    got = _corr(texel_width(res.image), _window_means(f_t))
    print(f"quilting: texel width vs target scale {got:.3f}")
    assert got >= 0.8
    assert (res.source >= 0).all()  # every output pixel copied from the example


def test_quilting_cells_split_only_where_the_target_varies():
    """A target flat on the left half and a steep ramp on the right: the left stays in 32-pixel cells, the right
    is split down to the smallest cell; the leaves tile the output exactly once, bottom row first."""
    H, W = 64, 128
    t = np.zeros((H, W, 1), np.float32)
    t[:, 64:, 0] = np.linspace(0, 1, 64)[None, :]
    leaves = cells(t, default_settings(QuiltingSettings, cell=32, min_cell=8, tolerance=0.05))
    cover = np.zeros((H, W), int)
    for y, x, h, w in leaves:
        cover[y:y + h, x:x + w] += 1
    assert (cover == 1).all()
    assert {(h, w) for y, x, h, w in leaves if x < 64} == {(32, 32)}
    assert {(h, w) for y, x, h, w in leaves if x >= 64} == {(8, 8)}
    assert leaves[0][0] == 32 and leaves[-1][0] < 32  # the bottom row of cells first


def test_quilting_a_periodic_example_is_seamless():
    """A periodic example (period 16 both ways, random within a period): a block of the least overlap error
    continues the pattern exactly, so the output is the pattern at one phase everywhere (no seam)."""
    rng = np.random.default_rng(3)
    tile = rng.random((16, 16, 3)).astype(np.float32)
    ex = np.tile(tile, (8, 8, 1))
    res = quilt(ex, (96, 160), settings=default_settings(QuiltingSettings, cell=32, epsilon=0.0))
    phase = (res.source[..., 0] % 16 - np.arange(96)[:, None] % 16) % 16, \
        (res.source[..., 1] % 16 - np.arange(160)[None, :] % 16) % 16
    assert len(np.unique(phase[0])) == 1 and len(np.unique(phase[1])) == 1
    assert res.energies[-1][2] < 1e-6


def test_energy_of_eq_6_3_never_increases(scale_aware):
    results, _ = scale_aware
    for res in results.values():
        by_stage = {}
        for level, n, e in res.energies:
            by_stage.setdefault((level, n), []).append(e)
        for stage, es in by_stage.items():
            assert all(b <= a * (1 + 1e-6) for a, b in zip(es, es[1:])), (stage, es)


def test_tight_types_land_where_the_target_puts_them():
    """An example with a disc of brick (type 1) in gravel (type 0); the target asks for the disc elsewhere and
    bigger: the output pixels copied from the example's type-1 pixels match the target's type-1 region
    (IoU >= 0.8, tight mode), by texture optimisation and by hierarchical quilting."""
    g = cv2.resize(data.gravel(), (128, 128)).astype(np.float32) / 255
    b = cv2.resize(data.brick(), (128, 128)).astype(np.float32) / 255
    yy, xx = np.mgrid[0:128, 0:128]
    disc = (yy - 64) ** 2 + (xx - 64) ** 2 < 36 ** 2
    ex = np.where(disc, b * 0.6 + 0.3, g * 0.6)[..., None].repeat(3, -1).astype(np.float32)
    types_e = disc.astype(np.int32)
    Y, X = np.mgrid[0:128, 0:192]
    types_t = ((Y - 64) ** 2 + (X - 120) ** 2 < 40 ** 2).astype(np.int32)
    res = synthesise(ex, (128, 192), None, None,
                     default_settings(OptimisationSettings, levels=2, sizes=(16, 8), iterations=3, type_mode="tight"),
                     example_types=types_e, target_types=types_t)
    quilted = quilt(ex, (128, 192), settings=default_settings(QuiltingSettings, cell=16, min_cell=4, type_mode="tight"),
                    example_types=types_e, target_types=types_t)
    want = types_t == 1
    for r in (res, quilted):
        sy = np.clip(r.source[..., 0], 0, 127)
        sx = np.clip(r.source[..., 1], 0, 127)
        got = types_e[sy, sx] == 1
        iou = (got & want).sum() / (got | want).sum()
        assert iou >= 0.8, iou


# -------------------------------------------------------------------------------------------- colour (§6.5)
def test_reinhard_lab_round_trip_and_transfer_matches_target_statistics():
    rng = np.random.default_rng(0)
    rgb = rng.uniform(0.05, 0.9, (64, 64, 3))
    assert np.allclose(lab_rs_to_rgb(rgb_to_lab_rs(rgb)), rgb, atol=1e-9)
    labels = np.zeros((64, 64), np.int32)
    labels[:, 40:] = 1
    rgb[labels == 1] *= np.array([1.0, 0.5, 0.3])  # the smaller region is orange-ish
    consistent = transfer_to_largest(rgb, labels)
    st = region_stats(consistent, labels)
    assert np.allclose(st[1]["mean"], st[0]["mean"], atol=2e-3)


def test_colour_regions_get_their_colour_back_within_de2000_5():
    """Segmentation of a two-colour texture finds two regions; after making them colour-consistent, the saved
    statistics give each region its mean colour back within CIEDE2000 5."""
    g = cv2.resize(data.gravel(), (160, 120)).astype(np.float32) / 255
    rgb = np.stack([g * 0.5 + 0.2, g * 0.6 + 0.25, g * 0.3 + 0.1], -1)
    rgb[:, 100:] = np.stack([g[:, 100:] * 0.5 + 0.45, g[:, 100:] * 0.4 + 0.2, g[:, 100:] * 0.2 + 0.05], -1)
    srgb8 = (np.clip(colour.cctf_encoding(rgb), 0, 1) * 255).astype(np.uint8)
    labels = segment(srgb8, spatial_radius=10, colour_radius=30, min_region=800)
    assert labels.max() == 1
    stats = region_stats(rgb, labels)
    back = recolour_regions(transfer_to_largest(rgb, labels), labels, stats)
    for r in range(2):
        lab = lambda a: colour.XYZ_to_Lab(colour.RGB_to_XYZ(a[labels == r].mean(0), "sRGB"))  # noqa: E731
        assert colour.delta_E(lab(back), lab(rgb), method="CIE 2000") <= 5.0


def test_colour_map_preview_shows_each_flat_region_in_its_own_colour():
    """A colour map drawn by region_colours gives a region of one flat colour exactly that colour (lαβ round trip),
    and refuses a region without statistics."""
    labels = np.zeros((8, 12), np.int32)
    labels[:, 7:] = 1
    rgb = np.where(labels[..., None] == 0, [0.6, 0.5, 0.2], [0.1, 0.3, 0.7])
    shown = region_colours(labels, region_stats(rgb, labels))
    assert np.allclose(shown, rgb, atol=1e-9)
    with pytest.raises(InputError, match="region 1 has no saved statistics"):
        region_colours(labels, region_stats(rgb, labels)[:1])


# ---------------------------------------------------------------------------------------- completion (§6.7)
def test_completion_keeps_the_scale_trend_where_inpainting_does_not(perspective_example):
    ex, scale = perspective_example
    hole = np.zeros(ex.shape[:2], bool)
    hole[64:128, 64:128] = True
    res = complete(ex, hole, scale_preview(scale),
                   default_settings(OptimisationSettings, levels=2, sizes=(16, 8), iterations=3))
    baseline = inpaint_baseline(ex, hole)
    inside = (slice(64, 128), slice(64, 128))
    want = texel_width(ex[inside])
    ours = np.abs(texel_width(res.image[inside]) - want).mean()
    theirs = np.abs(texel_width(baseline[inside]) - want).mean()
    assert ours < theirs, (ours, theirs)
    assert np.array_equal(res.image[~hole], np.clip(ex, 0, 1)[~hole])


# ------------------------------------------------------------------------------------------------ bad input
def test_bad_inputs_are_refused_with_what_is_wrong():
    with pytest.raises(InputError, match="empty"):
        scale_from_mask(np.zeros((64, 64), bool))
    with pytest.raises(InputError, match="slant"):
        scale_from_angles(64, 64, 90.0, 0.0)
    with pytest.raises(InputError, match="texture is 64x64"):
        type_map(np.zeros((32, 64), np.uint8), shape=(64, 64))
    ex = np.zeros((64, 64, 3), np.float32)
    with pytest.raises(InputError, match="not in the example"):
        synthesise(ex, (64, 64), None, None,
                   default_settings(OptimisationSettings, type_mode="tight", sizes=(8,), levels=1),
                   example_types=np.zeros((64, 64), int), target_types=np.ones((64, 64), int))
    with pytest.raises(InputError, match="smaller than the smallest neighbourhood"):
        synthesise(ex, (4, 64), None, None, default_settings(OptimisationSettings, sizes=(8,), levels=1))
