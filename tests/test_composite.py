"""Tests of natscene.composite: the hybrid image's colour transformation and hybrid vs full-spectral."""
import colour
import numpy as np

from natscene.color import linear_srgb_to_lab
from natscene.composite.full_spectral import render_full_spectral
from natscene.composite.hybrid import HybridImage, final_rgb
from natscene.composite.scene import FilmObject, Leaf, SetRenderer, SetSpec, spectral_coverage, sun_spectrum_from_rgb
from natscene.geometry import Camera
from natscene.spectral.grid import DEFAULT_GRID, spectrum_to_rgb
from natscene.spectral.illuminants import d65


def small_set(W=64, H=48, spp=1):
    cam = Camera((0, 0.6, -1.6), (0, 0.1, 0), fov=40, width=W, height=H)
    yy = np.linspace(0, 1, H)[:, None, None]
    bg = np.broadcast_to(np.array([0.3, 0.45, 0.8]) * (1 - yy) + np.array([0.7, 0.75, 0.8]) * yy, (H, W, 3)).copy()
    ck = ((np.indices((8, 8)).sum(0) % 2)[..., None] * np.array([0.3, 0.25, 0.1]) + np.array([0.1, 0.3, 0.05]))
    leaf = np.zeros((16, 32, 3)) + np.array([0.6, 0.1, 0.4])
    leaf[:, :16] = [0.9, 0.8, 0.1]
    return SetSpec(cam, bg, ck, leaves=[Leaf(leaf, (-0.35, 0.08, 0.1), (0.5, 0.25), 30, 15)],
                   objects=[FilmObject((0.15, 0.12, 0.0), 0.12)], spp=spp,
                   sun_spd=sun_spectrum_from_rgb([1.0, 0.9, 0.75], 3.0))


def test_final_is_rgb_plus_integrated_spectrum():
    rng = np.random.default_rng(0)
    rgb = rng.random((2, 3, 3)).astype(np.float32)
    S = np.zeros((2, 3, DEFAULT_GRID.size), np.float32)
    S[0, 0] = d65()  # white radiance spectrum: adds (1, 1, 1)
    out = final_rgb(rgb, S)
    np.testing.assert_allclose(out[0, 0], rgb[0, 0] + 1, atol=1e-3)
    np.testing.assert_allclose(out[1], rgb[1], atol=1e-6)
    h = HybridImage(rgb, S, np.ones((2, 3), np.float32))
    h2 = HybridImage.from_array(h.to_array(), h.channel_names())
    np.testing.assert_allclose(h2.final(), h.final(), atol=1e-6)
    assert h.channel_names()[3] == "S380" and h.channel_names()[-2] == "S780" and h.channel_names()[-1] == "A"


def test_hybrid_matches_full_spectral():
    spec = small_set()
    r = SetRenderer(spec)
    hy = r.render_hybrid()
    assert 0 < spectral_coverage(hy) < 0.15  # only the film object is spectral
    # the spectral part is exactly where the film object is, and nowhere else
    assert np.all(hy.alpha[np.any(hy.spectral != 0, -1)] > 0)
    _, full = render_full_spectral(r)
    de = colour.delta_E(linear_srgb_to_lab(hy.final()), linear_srgb_to_lab(full), method="CIE 2000")
    assert np.mean(de <= 1.0) >= 0.99, np.percentile(de, [50, 99, 100])
    # the background plate passes through unchanged in the hybrid render
    bg = hy.alpha == 0
    np.testing.assert_allclose(hy.final()[bg], spec.background[bg], atol=1e-5)


def test_film_colour_shifts_with_angle_and_thickness():
    """Fresnel and interference change the film's colour with the view angle (Dong Fig. 2.4)."""
    from natscene.spectral.thin_film import film_table
    t = film_table([(1.56, 300.0)], "Au")
    c0 = spectrum_to_rgb(t.reflectance(np.cos(np.radians(0.0))) * d65())
    c60 = spectrum_to_rgb(t.reflectance(np.cos(np.radians(60.0))) * d65())
    de = colour.delta_E(linear_srgb_to_lab(c0), linear_srgb_to_lab(c60), method="CIE 2000")
    assert de > 5
