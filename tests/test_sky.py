"""Sky extraction (Dobashi 2012 §4.1): classification, Laplace sky, c_in, soft alpha, resampling, bad input."""
from pathlib import Path

import cv2
import numpy as np
import pytest

from natscene import io
from natscene.color import LUMA_709
from natscene.config import default_settings
from natscene.errors import InputError
from natscene.sky.extract import SkySettings, extract_sky
from natscene.sky.laplace import laplace_residual, solve_laplace
from natscene.sky.resample import area_resample, crop_box, resample_labels
from natscene.sky.segmentation import AUTO, CLOUD, NEITHER, SKY, decode_hand_mask, soft_alpha

ROOT = Path(__file__).resolve().parents[1]
KITE = ROOT / "resources" / "photos" / "kite_cumulus_left.jpg"

W, H = 160, 120
CLOUD_RGB = np.array([1.0, 0.96, 0.88])  # slightly warm sunlight


def sky_gradient(w=W, h=H):
    """A smooth blue sky, linear in x and y per channel (discrete harmonic)."""
    y, x = np.mgrid[0:h, 0:w].astype(np.float64)
    r = 0.04 + 0.05 * x / w + 0.03 * y / h
    g = 0.12 + 0.06 * x / w + 0.05 * y / h
    b = 0.45 - 0.10 * x / w + 0.08 * y / h
    return np.stack([r, g, b], -1)


def cloud_shape(w=W, h=H):
    y, x = np.mgrid[0:h, 0:w]
    m = np.zeros((h, w), bool)
    for cx, cy, rad in ((60, 60, 25), (85, 55, 20), (100, 70, 18), (45, 75, 15)):
        m |= (x - cx) ** 2 + (y - cy) ** 2 <= rad ** 2
    return m


def synthetic_photo():
    sky = sky_gradient()
    m = cloud_shape()
    y, x = np.mgrid[0:H, 0:W]
    shade = 0.45 + 0.45 * (y < 62)  # lit top (0.9), shaded base (0.45): two brightness classes
    photo = np.where(m[..., None], (shade[..., None] * CLOUD_RGB), sky)
    return photo.astype(np.float32), sky, m


def iou(a, b):
    return (a & b).sum() / (a | b).sum()


def test_synthetic_mask_sky_and_sun_colour():
    photo, sky, m = synthetic_photo()
    res = extract_sky(photo)
    assert iou(res.labels == CLOUD, m) >= 0.95
    # the harmonic (linear) gradient is recovered under the cloud: 1% relative, far better in fact
    err = np.abs(res.sky - sky) / sky
    assert err[m].max() < 0.01
    assert np.allclose(res.sky[~res.solved], photo[~res.solved])
    # c_in = the lit cloud colour, luminance-normalised
    expect = CLOUD_RGB / (CLOUD_RGB @ LUMA_709)
    np.testing.assert_allclose(res.sun.c_in, expect, rtol=0.01)
    assert res.sun.c_in @ LUMA_709 == pytest.approx(1.0)
    assert res.sun.counts["bright_cloud"] == pytest.approx((m & (np.mgrid[0:H, 0:W][0] < 62)).sum(), rel=0.05)
    assert not res.warnings


def test_laplace_solution_satisfies_discrete_equation_and_keeps_known_pixels():
    rng = np.random.default_rng(3)
    vals = rng.random((50, 70, 3))
    unknown = rng.random((50, 70)) < 0.5  # many regions, some touching the border (Neumann there)
    unknown[10:30, 0:25] = True
    out = solve_laplace(vals, unknown)
    res = laplace_residual(out.astype(np.float64), unknown)
    assert np.abs(res).max() < 1e-5  # float32 output; the float64 solve is exact to ~1e-13
    assert np.array_equal(out[~unknown], vals[~unknown].astype(np.float32))


def test_laplace_reproduces_harmonic_functions_exactly():
    y, x = np.mgrid[0:40, 0:60].astype(np.float64)
    f = 0.3 + 0.01 * x - 0.02 * y + 0.0005 * x * y  # discrete harmonic (bilinear)
    unknown = np.zeros((40, 60), bool)
    unknown[5:35, 10:50] = True
    out = solve_laplace(f, unknown)
    assert np.abs(out - f).max() < 1e-5


def test_cloud_touching_border_gets_natural_boundary():
    y, x = np.mgrid[0:40, 0:60].astype(np.float64)
    f = 0.2 + 0.01 * y  # constant along x: consistent with zero x-gradient at the left border
    unknown = np.zeros((40, 60), bool)
    unknown[10:30, 0:20] = True
    out = solve_laplace(f, unknown)
    assert np.abs(out - f).max() < 1e-5
    g = 0.2 + 0.01 * x  # normal gradient at the border: the solution flattens toward it
    out = solve_laplace(g, unknown)
    assert abs(out[20, 0] - out[20, 1]) < abs(out[20, 18] - out[20, 19])


def test_no_sky_raises():
    with pytest.raises(InputError, match="no sky"):
        solve_laplace(np.ones((5, 5)), np.ones((5, 5), bool))


def test_kite_photo_cloud_on_left_found_sky_not():
    photo = io.read_photo(KITE)
    res = extract_sky(photo)
    cloud = res.labels == CLOUD
    assert cloud[120:380, 0:40].mean() > 0.9  # the cumulus on the left
    assert cloud[200:470, 250:630].mean() < 0.02  # the open blue sky
    assert 0.08 < cloud.mean() < 0.3
    c = res.sun.c_in
    assert c.max() / c.min() < 1.15  # near white
    # sky behind the cloud is blue like the sky around it
    assert np.all(res.sky[cloud][:, 2] > res.sky[cloud][:, 0])


def test_hand_mask_overrides_classifier():
    photo, sky, m = synthetic_photo()
    paint = np.full((H, W, 3), 0.5, np.float32)  # decide automatically
    paint[0:10, 0:20] = 1.0  # force cloud in the sky
    paint[55:65, 55:65] = (1.0, 0.0, 0.0)  # neither (e.g. a kite)
    paint[100:, :] = 0.0  # sky
    hand = decode_hand_mask(paint, (H, W))
    assert set(np.unique(hand)) == {AUTO, CLOUD, NEITHER, SKY}
    res = extract_sky(photo, hand_mask=hand)
    assert (res.labels[0:10, 0:20] == CLOUD).all()
    assert (res.labels[55:65, 55:65] == NEITHER).all()
    assert (res.labels[100:] == SKY).all()
    assert (res.alpha[res.labels == NEITHER] == 0).all()
    with pytest.raises(InputError, match="photo's size"):
        decode_hand_mask(paint[:50], (H, W))


def test_soft_alpha_recovers_blend():
    photo, sky, m = synthetic_photo()
    a_true = np.where(m, 0.6, 0.0)
    blend = a_true[..., None] * 0.8 * CLOUD_RGB + (1 - a_true[..., None]) * sky
    labels = np.where(m, CLOUD, SKY)
    alpha = soft_alpha(blend, sky, labels, CLOUD_RGB)
    np.testing.assert_allclose(alpha[m], 0.6, atol=1e-4)
    assert (alpha[~m] == 0).all()


def test_greyscale_and_cloudless_photos_raise():
    grey = np.repeat(np.linspace(0, 1, 40 * 30).reshape(30, 40, 1), 3, -1).astype(np.float32)
    with pytest.raises(InputError, match="greyscale"):
        extract_sky(grey)
    with pytest.raises(InputError, match="greyscale"):
        extract_sky(grey[..., :1])
    blue = np.broadcast_to(sky_gradient(40, 30), (30, 40, 3)).astype(np.float32)
    with pytest.raises(InputError, match="cloud"):
        extract_sky(blue, default_settings(SkySettings, threshold=0.01))
    white = np.full((30, 40, 3), 0.8, np.float32)
    white[..., 2] += np.linspace(0, 0.01, 40)  # not quite grey, but no sky anywhere
    with pytest.raises(InputError, match="no sky"):
        extract_sky(white, default_settings(SkySettings, threshold=5.0))


def test_overcast_grey_warns_not_fails():
    photo = np.full((60, 80, 3), 0.5, np.float32)
    photo *= (0.7 + 0.3 * (np.arange(60) < 30))[:, None, None]
    photo[:, :6] = (0.05, 0.12, 0.45)  # a strip of blue sky
    res = extract_sky(photo)
    assert res.sun.overcast
    assert any("overcast" in w for w in res.warnings)
    np.testing.assert_allclose(res.sun.c_in, 1.0, atol=1e-3)


def test_exr_and_16bit_png_photos(tmp_path):
    photo, _, m = synthetic_photo()
    io.write_exr(tmp_path / "p.exr", photo)
    res = extract_sky(io.read_photo(tmp_path / "p.exr"))
    assert iou(res.labels == CLOUD, m) >= 0.95
    from natscene.color import linear_to_srgb
    enc = np.round(linear_to_srgb(photo) * 65535).astype(np.uint16)
    cv2.imwrite(str(tmp_path / "p.png"), enc[..., ::-1])
    res = extract_sky(io.read_photo(tmp_path / "p.png"))
    assert iou(res.labels == CLOUD, m) >= 0.95


def test_resample_area_average_and_majority_labels():
    rng = np.random.default_rng(0)
    img = rng.random((40, 60, 3)).astype(np.float32)
    out = area_resample(img, 30, 20)
    np.testing.assert_allclose(out, img.reshape(20, 2, 30, 2, 3).mean((1, 3)), atol=1e-6)
    assert crop_box(640, 480, 320, 240) == (0, 0, 640, 480)
    assert crop_box(640, 480, 400, 240) == (0, 48, 640, 384)
    lab = np.zeros((4, 4), np.uint8)
    lab[0, 0:2] = CLOUD
    lab[0:2, 0] = CLOUD  # top-left 2x2 block: 3 cloud, 1 sky
    lab[2:4, 2:4] = NEITHER
    lab[2, 2] = SKY
    small = resample_labels(lab, 2, 2)
    np.testing.assert_array_equal(small, [[CLOUD, SKY], [SKY, NEITHER]])


def test_otsu_matches_skimage_within_a_bin():
    from skimage.filters import threshold_otsu

    from natscene.sky.segmentation import otsu_threshold
    rng = np.random.default_rng(1)
    v = np.concatenate([rng.normal(0.2, 0.05, 5000), rng.normal(0.8, 0.1, 3000)])
    bin_width = np.ptp(v) / 256
    assert abs(otsu_threshold(v) - threshold_otsu(v)) <= bin_width
    assert ((v < otsu_threshold(v)) == (np.arange(v.size) < 5000)).mean() > 0.999


def test_multigrid_matches_direct_solver():
    photo = io.read_photo(KITE)[::2, ::2]
    unknown = np.zeros(photo.shape[:2], bool)
    unknown[20:200, 0:80] = True  # touches the border
    unknown[30:60, 150:300] = True
    mg = solve_laplace(photo, unknown, method="multigrid", rtol=1e-12)
    lu = solve_laplace(photo, unknown, method="direct")
    assert np.abs(mg - lu).max() < 1e-6


def test_greyscale_photo_with_fully_painted_mask_works():
    photo, sky, m = synthetic_photo()
    grey = photo.mean(-1, keepdims=True)
    hand = np.where(m, CLOUD, SKY).astype(np.int8)
    res = extract_sky(grey, hand_mask=hand)
    assert np.array_equal(res.labels == CLOUD, m)
    np.testing.assert_allclose(res.sun.c_in, 1.0, rtol=1e-5)
