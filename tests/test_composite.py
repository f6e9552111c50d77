"""Tests of natscene.composite: the hybrid image's colour transformation, hybrid vs full-spectral, the set's
geometry (flowers, maple leaves, beetles), filtered texturing of the ground to the horizon, the sky dome's
irradiance, the frame state of a shot, and where the cloud of the main job lands in the final frame."""
import colour
import numpy as np
import pytest

from natscene.color import linear_srgb_to_lab
from natscene.composite.beetle import GOLD_BUG, JEWEL_BEETLE, beetle_meshes
from natscene.composite.flower import PetalShape, PetalTexture, flower
from natscene.composite.full_spectral import render_full_spectral
from natscene.composite.hybrid import HybridImage, final_rgb
from natscene.composite.maple import MapleOutline, leaf_mesh, warp_season_map
from natscene.composite.mesh import TriMesh, merge
from natscene.composite.renderer import SetRenderer, spectral_coverage
from natscene.composite.set_spec import Film, Ground, SetSpec, Shape, Surface, sun_spectrum_from_rgb
from natscene.composite.sky_dome import SkyDome, gradient_sky, sphere_quadrature
from natscene.composite.texture import MipTexture
from natscene.composite.tracer import SetTracer
from natscene.geometry import Camera, sun_direction
from natscene.spectral.grid import DEFAULT_GRID, spectrum_to_rgb
from natscene.spectral.illuminants import d65

JEWEL_STACK = [(1.56, 85.0), ("2.0+0.05j", 65.0)] * 6  # chitin / melanoprotein multilayer


def petal_alpha(h=48, w=40):
    """A petal outline: an egg shape with its narrow base at the bottom centre."""
    yy, xx = (np.mgrid[0:h, 0:w] + 0.5) / np.array([h, w])[:, None, None]
    v = 1 - yy  # 0 at the bottom
    half = 0.45 * np.sqrt(np.clip(v, 0, 1)) * np.clip(1.15 - v, 0, 1)
    return ((np.abs(xx - 0.5) <= half) & (v > 0.03) & (v < 0.97)).astype(np.float32)


def solid_petal(rgb, h=48, w=40):
    a = petal_alpha(h, w)
    return np.concatenate([np.broadcast_to(np.asarray(rgb, np.float32), (h, w, 3)), a[..., None]], -1)


def small_set(W=64, H=48, spp=1, sun_rgb=None, sky=None, with_film=True, grey_ground=False):
    """Dong §2.5's setting at garden scale: a textured ground, a flower of a pattern texture, one spectral
    object (the gold bug), a parallel D65 sun (``sun_rgb``: a coloured sun) and a sky dome (neutral unless
    ``sky`` = (zenith, horizon); ``grey_ground``: a neutral ground, whose bounce light is D65-shaped too)."""
    cam = Camera((0, 0.16, -0.3), (0, 0.06, 0.1), (0, 1, 0), fov=40, width=W, height=H)
    yy = np.linspace(0, 1, H)[:, None, None]
    plate = np.broadcast_to(np.array([0.3, 0.45, 0.8]) * (1 - yy) + np.array([0.7, 0.75, 0.8]) * yy, (H, W, 3)).copy()
    ck = ((np.indices((8, 8)).sum(0) % 2)[..., None] * np.array([0.3, 0.25, 0.1]) + np.array([0.1, 0.3, 0.05]))
    if grey_ground:
        ck = ck.mean(-1, keepdims=True).repeat(3, -1)
    tex = solid_petal([0.8, 0.2, 0.5])
    tex[:, :20, :3] = [0.9, 0.8, 0.1]
    f = flower(PetalTexture(tex[..., 3], 40 / 48), 5, (-0.08, 0.05), 0.06, tilt=30, facing=180,
               shape=PetalShape(length=0.035))
    surfaces = [Surface("petal", MipTexture(tex), cutout=True, translucency=0.3),
                Surface("disc", color=(0.55, 0.4, 0.04)), Surface("stem", color=(0.07, 0.16, 0.03))]
    shapes = [Shape(merge(f.petals), surface=0), Shape(f.centre, surface=1), Shape(f.stem, surface=2)]
    films = []
    if with_film:
        m = beetle_meshes(GOLD_BUG, (0.05, 0.02), yaw=120)
        shapes += [Shape(m["shell"], film=0), Shape(m["legs"], surface=2)]
        films = [Film("gold")]
    zen, hor = sky if sky is not None else ([0.5, 0.5, 0.5], [0.6, 0.6, 0.6])
    sun = d65() * 3.0 if sun_rgb is None else sun_spectrum_from_rgb(sun_rgb, 3.0)
    return SetSpec(cam, plate, Ground(MipTexture(ck, wrap=True), (0.2, 0.2)), surfaces, films, shapes,
                   sun_direction(130, 35), sun, sky=gradient_sky(zen, hor), spp=spp)


def delta_e(a, b):
    return colour.delta_E(linear_srgb_to_lab(a), linear_srgb_to_lab(b), method="CIE 2000")


# ------------------------------------------------------------------------------------------ hybrid image
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


def test_sparse_final_equals_dense_final():
    rng = np.random.default_rng(1)
    rgb = rng.random((4, 5, 3)).astype(np.float32)
    S = np.zeros((4, 5, DEFAULT_GRID.size), np.float32)
    S[1, 2] = rng.random(DEFAULT_GRID.size)
    mask = np.zeros((4, 5), bool)
    mask[1, 2] = True
    dense = HybridImage(rgb, S, np.ones((4, 5), np.float32)).final()
    sparse = HybridImage(rgb, S, np.ones((4, 5), np.float32), mask=mask).final()
    np.testing.assert_allclose(sparse, dense, atol=1e-6)


# -------------------------------------------------------------------------------- hybrid vs full-spectral
def test_hybrid_matches_full_spectral():
    """The criterion on Dong's setting (one spectral object, D65 parallel light): CIEDE2000 <= 1 on >= 99% of
    pixels; the spectral part lives only on the film object; the plate passes through unchanged."""
    spec = small_set(spp=4)
    r = SetRenderer(spec)
    hy = r.render_hybrid()
    assert 0 < spectral_coverage(hy) < 0.15
    assert np.all(hy.alpha[np.any(hy.spectral != 0, -1)] > 0)
    _, full = render_full_spectral(r)
    de = delta_e(hy.final(), full)
    assert np.mean(de <= 1.0) >= 0.99, np.percentile(de, [50, 99, 100])
    bg = hy.alpha == 0
    assert bg.any()
    np.testing.assert_allclose(hy.final()[bg], spec.plate[bg], atol=1e-5)


def test_rgb_materials_exact_under_d65_and_shifted_under_coloured_light():
    """Mallett-Yuksel upsampling round-trips under D65: under a D65 sun, a neutral sky and a neutral ground
    (whose bounce light is D65-shaped as well) the RGB materials give the same colour in RGB and in spectra.
    Under a saturated blue sky a product of two upsampled spectra no longer integrates to the RGB product: the
    modes then differ on RGB materials (inherent to RGB shading, Dong's hybrid included)."""
    r = SetRenderer(small_set(W=48, H=36, grey_ground=True))
    hy = r.render_hybrid()
    _, full = render_full_spectral(r)
    rgb_only = (hy.alpha == 1) & ~np.any(hy.spectral != 0, -1)
    np.testing.assert_allclose(hy.final()[rgb_only], full[rgb_only], rtol=2e-3, atol=1e-4)
    r2 = SetRenderer(small_set(W=48, H=36, sky=([0.05, 0.2, 0.9], [0.3, 0.45, 0.9])))
    hy2 = r2.render_hybrid()
    _, full2 = render_full_spectral(r2)
    de = delta_e(hy2.final(), full2)
    assert np.max(de[rgb_only]) > 0.3
    plate = hy2.alpha == 0
    np.testing.assert_allclose(full2[plate], hy2.final()[plate], rtol=1e-3, atol=1e-4)


def test_films_in_rgb_mode_have_no_spectral_part_and_stay_close():
    """The benchmark's baseline: the films shaded in RGB leave the spectral part empty, and give nearly the
    same image (gold is smooth in wavelength)."""
    r = SetRenderer(small_set(spp=1))
    hy = r.render_hybrid()
    rg = r.render_hybrid(film_mode="rgb")
    assert not np.any(rg.spectral) and np.any(hy.spectral)
    film_px = hy.mask
    assert np.median(delta_e(hy.final()[film_px], rg.final()[film_px])) < 3.0


def test_gold_bug_is_bulk_gold_and_beetle_stack_is_iridescent():
    """Dong's gold bug: 300 and 500 nm of gold on copper are far thicker than gold's skin depth (~15 nm), so the
    film reflects like bulk gold. The chitin/melanoprotein stack shifts its colour strongly with angle."""
    from natscene.spectral.thin_film import film_table
    au300, au500, bulk = film_table([("Au", 300.0)], "Cu"), film_table([("Au", 500.0)], "Cu"), film_table([], "Au")
    np.testing.assert_allclose(au300.R, bulk.R, atol=1e-6)
    np.testing.assert_allclose(au500.R, bulk.R, atol=1e-6)
    beetle = film_table(JEWEL_STACK, "2.0+0.4j")
    c = [spectrum_to_rgb(beetle.reflectance(np.cos(np.radians(a))) * d65()) for a in (0.0, 50.0)]
    assert c[0][1] > c[0][0] and c[0][1] > c[0][2]
    assert c[1][2] > c[0][2] and c[1][0] < c[0][0]
    assert delta_e(c[0], c[1]) > 20


# ------------------------------------------------------------------------------------------ set geometry
@pytest.mark.parametrize("n", [5, 6, 8])
def test_flower_petals_radial_with_requested_count(n):
    """n petal meshes, their centroids at equal azimuth steps 2π/n round the head's axis, each spanning its
    texture's petal (uv over the opaque region of the pattern map) and starting at the centre."""
    tex = solid_petal([0.9, 0.1, 0.3])
    pt = PetalTexture(tex[..., 3], 40 / 48)
    f = flower(pt, n, (0.0, 0.0), 0.2, tilt=25.0, facing=40.0, shape=PetalShape(length=0.03), jitter=0.0, stagger=0.0)
    assert len(f.petals) == n
    axis = f.axis
    ref = np.cross(axis, [1.0, 0.0, 0.0])
    ref /= np.linalg.norm(ref)
    ref2 = np.cross(axis, ref)
    az = []
    for p in f.petals:
        c = p.positions.mean(0) - f.head
        c -= (c @ axis) * axis
        az.append(np.arctan2(c @ ref2, c @ ref))
        # the petal touches the centre (its base) and reaches out about its length
        r = np.linalg.norm(np.cross(p.positions - f.head, axis), axis=1)
        assert r.min() < 0.008 and 0.015 < r.max() < 0.04
        u_b, v_b, v_t, u0, u1 = pt.base
        assert p.uv[:, 1].min() == pytest.approx(v_b, abs=0.05) and p.uv[:, 1].max() == pytest.approx(v_t, abs=0.05)
    a = np.sort(np.mod(az, 2 * np.pi))
    np.testing.assert_allclose(np.diff(np.append(a, a[0] + 2 * np.pi)), 2 * np.pi / n, atol=1e-6)


def test_flower_render_shows_petals_of_their_pattern():
    """Seen from above along their axes, two flowers of n petals show n petal lobes each (angular coverage
    profile round their centres), coloured by their own pattern maps (a red and a blue texture keep their
    chromaticity under a white sky)."""
    n = 5
    shapes, surfaces, colours = [], [], ([0.8, 0.1, 0.1], [0.1, 0.2, 0.8])
    for i, (rgb, x) in enumerate(zip(colours, (-0.05, 0.05))):
        tex = solid_petal(rgb)
        f = flower(PetalTexture(tex[..., 3], 40 / 48), n, (x, 0.0), 0.1, tilt=0.0,
                   shape=PetalShape(length=0.03, opening=10.0, bend=5.0, cup=0.05), jitter=0.0, stagger=0.0)
        surfaces.append(Surface(f"p{i}", MipTexture(tex), cutout=True))
        shapes.append(Shape(merge(f.petals), surface=i))
    W, H = 240, 120
    cam = Camera((0.0, 0.45, 0.0), (0.0, 0.0, 0.0), up=(0.0, 0.0, 1.0), fov=20, width=W, height=H)
    spec = SetSpec(cam, np.zeros((H, W, 3), np.float32), None, surfaces, [], shapes, sun_direction(0, 90),
                   d65() * 0.0, sky=gradient_sky([1, 1, 1], [1, 1, 1]), spp=4)
    hy = SetRenderer(spec).render_hybrid()
    img = hy.final()
    yy, xx = np.nonzero(hy.alpha > 0.99)
    found = []
    for side in (xx < W / 2, xx >= W / 2):
        cols = img[yy[side], xx[side]]
        found.append(np.median(cols / cols.sum(-1, keepdims=True), 0))
        cx, cy = xx[side].mean(), yy[side].mean()
        ang = np.arctan2(yy[side] - cy, xx[side] - cx)
        rad = np.hypot(yy[side] - cy, xx[side] - cx)
        hist = np.histogram(ang[rad > 0.75 * rad.max()], bins=90, range=(-np.pi, np.pi))[0].astype(float)
        on = hist > 0.25 * hist.max()
        assert int(np.sum(on & ~np.roll(on, 1))) == n, hist
    targets = [np.asarray(c) / np.sum(c) for c in colours]
    found.sort(key=lambda c: -c[0])
    for f_, t in zip(found, targets):
        np.testing.assert_allclose(f_, t, atol=0.02)


def test_maple_outline_five_lobes_serrated_and_season_colours():
    """The parametric palmate outline has five lobes (connected blade regions outside the palm) and a toothed
    margin; the leaf texture takes the season stage's colours (the same mean hue inside the outline)."""
    from scipy import ndimage
    o = MapleOutline()
    size = 256
    m = o.mask(size) > 0.5
    yy, xx = (np.mgrid[0:size, 0:size] + 0.5) / size
    rho = np.hypot(xx - o.root[0], o.root[1] - yy)
    blade_far = m & (rho > 0.17) & ~((yy > o.root[1]) & (np.abs(xx - o.root[0]) < 0.03))
    assert ndimage.label(blade_far)[1] == 5
    phi = np.linspace(-np.pi, np.pi, 4000, endpoint=False)
    r = o.radius(phi)
    maxima = np.sum((r > np.roll(r, 1)) & (r > np.roll(r, -1)))
    assert maxima >= 40  # the serration and the coarse teeth
    # colour: a two-tone season map (orange blade) keeps its colour on the new outline
    season = np.zeros((96, 96, 4), np.float32)
    season[..., :3] = [0.6, 0.25, 0.05]
    season[20:80, 20:80, 3] = 1
    leaf = warp_season_map(season, o, 128)
    inside = leaf[..., 3] > 0.5
    np.testing.assert_allclose(leaf[inside, :3].mean(0), [0.6, 0.25, 0.05], atol=1e-3)
    mesh = leaf_mesh(leaf[..., 3], 0.12)
    ext = mesh.positions.max(0) - mesh.positions.min(0)
    assert 0.08 < ext[0] < 0.125 and 0.08 < ext[2] < 0.125 and ext[1] < 0.04  # lies on the ground, curled


@pytest.mark.parametrize("shape", [GOLD_BUG, JEWEL_BEETLE])
def test_beetles_have_a_believable_size(shape):
    """A few centimetres long, longer than wide, standing on the ground on its legs, the shell above them."""
    m = beetle_meshes(shape, (0.3, 0.2), yaw=90.0)
    sh, legs = m["shell"].positions, m["legs"].positions
    ext = sh.max(0) - sh.min(0)
    length, width = ext[0], ext[2]  # yaw 90: the body along x
    assert 0.02 < length < 0.05 and width < 0.7 * length
    assert 0.005 < sh[:, 1].max() < 0.02 and sh[:, 1].min() > 0
    assert legs[:, 1].min() < 0.001
    assert np.linalg.norm(sh.mean(0)[[0, 2]] - [0.3, 0.2]) < 0.01


# -------------------------------------------------------------------------------------------- texturing
def _checker(n_texels=64, squares=16):
    k = (np.indices((n_texels, n_texels)) // (n_texels // squares)).sum(0) % 2
    return np.where(k[..., None] == 1, np.array([0.8, 0.8, 0.8]), np.array([0.1, 0.1, 0.1])).astype(np.float32)


def _ground_render(filtered=True):
    """A checkerboard ground to the horizon under a constant sky (radiance 1 everywhere: L = albedo)."""
    W, H = 160, 120
    cam = Camera((0.0, 1.0, 0.0), (0.0, 0.6, 10.0), (0.0, 1.0, 0.0), fov=40, width=W, height=H)
    spec = SetSpec(cam, np.zeros((H, W, 3), np.float32), Ground(MipTexture(_checker(64, 8), wrap=True), (2.0, 2.0)),
                   sun_dir=sun_direction(0, 60), sun_spd=d65() * 0.0, sky=gradient_sky([1, 1, 1], [1, 1, 1]), spp=1,
                   max_aniso=16)
    r = SetRenderer(spec)
    r.dome.coef[:] = 0.0
    r.dome.coef[0] = np.sqrt(4 * np.pi)  # constant radiance 1 over the sphere: E = π for every normal
    if not filtered:
        r.albedo_rgb = lambda h, sel, coarse=False: spec.ground.texture.bilinear(h.uv[sel])[:, :3]
    return r.render_hybrid()


def test_ground_to_the_horizon_does_not_alias_in_the_far_field():
    """A checkerboard ground rendered to the horizon: in the farthest 10 % of the ground band the per-row
    contrast (std / mean of luminance across the row) stays below 0.05 with filtering (the squares average to
    their mean, 0.45, without moiré), while point sampling there gives moiré (contrast > 0.3); the near field
    keeps the checker's contrast (> 0.5)."""
    hy = _ground_render(True)
    y = hy.final() @ np.array([0.2126, 0.7152, 0.0722])
    rows = np.flatnonzero(hy.alpha.mean(1) > 0.999)  # the ground band
    assert rows.size > 30 and hy.alpha[: rows[0]].max() < 1
    k = max(2, int(round(0.1 * rows.size)))
    far, near = rows[:k], rows[-k:]

    def contrast(rs):
        return float(np.mean(y[rs].std(1) / y[rs].mean(1)))
    assert contrast(far) < 0.05, contrast(far)
    assert contrast(near) > 0.5
    np.testing.assert_allclose(y[far].mean(), 0.45, rtol=0.03)
    y0 = _ground_render(False).final() @ np.array([0.2126, 0.7152, 0.0722])
    assert float(np.mean(y0[far].std(1) / y0[far].mean(1))) > 0.3  # the test would catch missing filtering


def test_filtered_lookup_matches_openimageio_texture_system():
    """The vectorised lookup against OpenImageIO's TextureSystem (mip-mapped, anisotropic): identical for
    magnification and isotropic minification (the same box pyramid and trilinear level), within 1 % of the
    texture's range on average for anisotropic footprints up to 16:1."""
    import cv2
    from natscene.io import texture_lookup_reference
    rng = np.random.default_rng(0)
    tex = cv2.GaussianBlur(rng.random((128, 128, 3)).astype(np.float32), (0, 0), 1.5)
    tex = np.concatenate([tex[..., :2], _checker(128, 8)[..., :1]], -1)
    mt = MipTexture(tex, wrap=True)
    uv = rng.random((150, 2))
    ang = rng.uniform(0, np.pi, 150)
    for scale, ratio, tol in ((0.5, 1, 1e-5), (4.0, 1, 1e-5), (2.0, 8, 0.01), (8.0, 16, 0.01)):
        a, b = scale * ratio / 128, scale / 128
        dx = np.stack([np.cos(ang) * a, np.sin(ang) * a], -1)
        dy = np.stack([-np.sin(ang) * b, np.cos(ang) * b], -1)
        ref = texture_lookup_reference(tex, uv, dx, dy, wrap=True)
        assert np.abs(mt.filtered(uv, dx, dy, 16) - ref).mean() < tol, (scale, ratio)


def test_mip_pyramid_keeps_the_mean():
    rng = np.random.default_rng(2)
    for shape in ((64, 64, 3), (37, 50, 4)):
        t = rng.random(shape).astype(np.float32)
        m = MipTexture(t)
        np.testing.assert_allclose(m.mean(), t.reshape(-1, shape[-1]).mean(0), rtol=1e-4)
        assert m.levels[-1].shape[:2] == (1, 1)


def test_lookup_is_the_textbook_bilinear_formula():
    """Point lookups against the bilinear formula evaluated by hand: at texel centres the texel itself; between
    four texels of a clamped image the weights (1 − fx)(1 − fy), fx(1 − fy), (1 − fx)fy, fx·fy; with wrap the
    right neighbour of the last column is column 0. An atlas of two images picks each sample's image."""
    rng = np.random.default_rng(3)
    a = rng.random((5, 7, 2)).astype(np.float32)
    b = rng.random((4, 3, 2)).astype(np.float32)
    m = MipTexture(a)
    i, j = np.meshgrid(np.arange(5), np.arange(7), indexing="ij")
    centres = np.stack([(j.ravel() + 0.5) / 7, 1 - (i.ravel() + 0.5) / 5], -1)
    np.testing.assert_allclose(m.bilinear(centres), a.reshape(-1, 2), rtol=1e-5)  # float32: the centres' x, y
    fx, fy = 0.3, 0.8  # a point between texels (row 1, col 2) and (row 2, col 3)
    uv = np.array([[(2.5 + fx) / 7, 1 - (1.5 + fy) / 5]])
    want = ((1 - fx) * (1 - fy) * a[1, 2] + fx * (1 - fy) * a[1, 3] + (1 - fx) * fy * a[2, 2] + fx * fy * a[2, 3])
    np.testing.assert_allclose(m.bilinear(uv)[0], want, rtol=1e-5)
    w = MipTexture(a, wrap=True)
    uv = np.array([[(6.5 + fx) / 7, 1 - 2.5 / 5]])
    np.testing.assert_allclose(w.bilinear(uv)[0], (1 - fx) * a[2, 6] + fx * a[2, 0], rtol=1e-5)
    at = MipTexture.atlas([a, b])
    pts = np.array([[0.5 / 7, 1 - 0.5 / 5], [2.5 / 3, 1 - 3.5 / 4]])
    np.testing.assert_allclose(at.bilinear(pts, np.array([0, 1])), np.stack([a[0, 0], b[3, 2]]), rtol=1e-5)


def test_lookup_far_outside_a_clamped_texture_is_its_edge():
    """Clamp-to-edge for coordinates far outside [0, 1] (a probe line of a grazing footprint): the edge
    texels, as the formula says, whatever the distance; a non-finite coordinate gives a finite value."""
    a = np.arange(12, dtype=np.float32).reshape(3, 4, 1)
    m = MipTexture(a)
    uv = np.array([[-1e12, 0.5], [1e12, 0.5], [0.125, 1e12], [0.125, -1e12], [np.nan, 0.5]])
    v = m.bilinear(uv)[:, 0]
    np.testing.assert_array_equal(v[:4], [a[1, 0, 0], a[1, 3, 0], a[0, 0, 0], a[2, 0, 0]])
    assert np.isfinite(v[4])


def test_filtered_lookup_of_a_constant_texture_is_the_constant():
    """Every probe of a constant texture returns the constant, whatever the footprint (the probes' mean)."""
    rng = np.random.default_rng(4)
    m = MipTexture(np.full((64, 32, 3), 0.375, np.float32), wrap=True)
    uv = rng.random((500, 2)) * 5
    dx, dy = rng.normal(size=(500, 2)) * 0.2, rng.normal(size=(500, 2)) * 0.01
    np.testing.assert_array_equal(m.filtered(uv, dx, dy, 16), 0.375)


def _quad(z: float, half: float, flip: bool) -> TriMesh:
    """The square |x|, |y| <= ``half`` in the plane z, uv = ((x/half + 1)/2, (y/half + 1)/2)."""
    pos = np.array([[-half, -half, z], [half, -half, z], [half, half, z], [-half, half, z]])
    faces = np.array([[0, 2, 1], [0, 3, 2]] if flip else [[0, 1, 2], [0, 2, 3]])
    uv = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    return TriMesh(pos, faces, uv, np.tile([0.0, 0.0, -1.0 if flip else 1.0], (4, 1)))


def test_ray_caster_hits_are_the_analytic_plane_hits():
    """Closest hits against the plane solution: a square at z = 1 (half-width 1) in front of a larger one at
    z = 2 (half-width 3, the other winding). A ray o + t·d hits the first at t = (1 − o_z)/d_z where the hit
    point is inside it, else the second, else nothing; uv is the point's position in the square, ∂p/∂u its
    edge vector, both normals face the ray origin (rays from behind, z = 5, see +z normals); misses carry
    label -1, t = inf and zero fields. A shadow query toward +z is blocked exactly where a square is."""
    tracer = SetTracer([_quad(1.0, 1.0, False), _quad(2.0, 3.0, True)])
    rng = np.random.default_rng(5)
    xy = rng.uniform(-2.0, 2.0, (4000, 2))
    o = np.zeros((4000, 3))
    o[2000:, 2] = 5.0  # from behind, toward -z
    d = np.concatenate([xy, np.where(o[:, 2:] > 0, -1.0, 1.0)], -1)
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    h = tracer.intersect(o, d)
    label = np.full(4000, -1)
    t = np.full(4000, np.inf)
    for i, (z, half) in reversed(list(enumerate([(1.0, 1.0), (2.0, 3.0)]))):  # the nearer square wins
        tt = (z - o[:, 2]) / d[:, 2]
        p = o + d * tt[:, None]
        inside = np.all(np.abs(p[:, :2]) < half * (1 - 1e-4), -1)
        nearer = inside & (tt < t)
        label[nearer], t[nearer] = i, tt[nearer]
    edge = np.isfinite(t)
    for i, (z, half) in enumerate([(1.0, 1.0), (2.0, 3.0)]):  # skip points within 1e-4 of an edge
        p = o + d * ((z - o[:, 2]) / d[:, 2])[:, None]
        edge &= ~np.any(np.abs(np.abs(p[:, :2]) - half) < 1e-4 * half, -1)
    ok = edge | ~np.isfinite(t)
    np.testing.assert_array_equal(h["label"][ok], label[ok])
    hit = ok & (label >= 0)
    np.testing.assert_allclose(h["t"][hit], t[hit], rtol=1e-5)
    p = o + d * np.where(hit, t, 0)[:, None]
    half = np.where(label == 0, 1.0, 3.0)[:, None]
    np.testing.assert_allclose(h["uv"][hit], ((p[:, :2] / half + 1) / 2)[hit], atol=1e-5)
    np.testing.assert_allclose(h["dp_du"][hit], (np.array([2.0, 0, 0]) * half)[hit], rtol=1e-5)
    np.testing.assert_allclose(h["dp_dv"][hit], (np.array([0, 2.0, 0]) * half)[hit], rtol=1e-5)
    facing = np.where(o[:, 2:] > 0, 1.0, -1.0) * np.array([0.0, 0.0, 1.0])
    for key in ("n", "sn"):
        np.testing.assert_allclose(h[key][hit], facing[hit], atol=1e-6)
    miss = ok & (label < 0)
    assert miss.sum() > 100 and hit.sum() > 1000
    assert np.all(np.isinf(h["t"][miss])) and not np.any(h["uv"][miss]) and not np.any(h["n"][miss])
    q = np.c_[rng.uniform(-4.0, 4.0, (2000, 2)), np.zeros(2000)]
    far = np.all(np.abs(np.abs(q[:, :2]) - 3.0) > 1e-3, -1)
    blocked = tracer.occluded(q[far], [0.0, 0.0, 1.0])
    np.testing.assert_array_equal(blocked, np.all(np.abs(q[far, :2]) < 3.0, -1))


def test_texture_derivatives_on_a_plane_are_the_neighbour_rays_offsets():
    """On the plane z = 1 with ∂p/∂u = (2, 0, 0), ∂p/∂v = (0, 3, 0), the footprint of a ray from the origin
    toward d is the offset between the plane points of d and of its neighbour d', (p' − p) = d'/d'_z − d/d_z,
    divided by the tangents' lengths; a neighbour parallel to the plane gives zero."""
    from natscene.variant import select_variant
    select_variant(spectral=False)
    from natscene.composite.footprint import texture_derivative
    from natscene.composite.vectors import array3f64 as v3
    rng = np.random.default_rng(6)
    d = np.c_[rng.uniform(-0.5, 0.5, (200, 2)), np.ones(200)]
    nd = d + np.c_[rng.normal(0, 0.01, (200, 2)), rng.normal(0, 0.01, 200)]
    nd[0] = [1.0, 0.0, 0.0]
    p = d / d[:, 2:]
    z = np.zeros((200, 3))
    f = texture_derivative(v3(z), v3(p), v3(z + [0, 0, -1.0]), v3(nd), v3(z + [2.0, 0, 0]), v3(z + [0, 3.0, 0]))
    got = np.asarray(f).T
    want = (nd[1:] / nd[1:, 2:] - p[1:])[:, :2] / [2.0, 3.0]
    np.testing.assert_allclose(got[1:], want, rtol=1e-9, atol=1e-12)
    np.testing.assert_array_equal(got[0], [0.0, 0.0])


# ------------------------------------------------------------------------------------------- sky dome
def test_sky_dome_irradiance():
    """SH9 irradiance (Ramamoorthi & Hanrahan 2001): exact for a constant sky (E = π L for every normal); for a
    bright upper and a dark lower hemisphere within the published order-2 error of the brute-force integral."""
    dome = SkyDome(gradient_sky([1, 1, 1], [1, 1, 1]), sun_direction(0, 45), [0, 0, 0], [1.0, 1.0, 1.0])
    # ground of albedo 1 lit by the sky's E(up) = π: radiance 1 below too -> constant sphere
    n = np.array([[0, 1, 0], [0, -1, 0], [1, 0, 0], [0.6, 0.8, 0.0]], np.float64)
    np.testing.assert_allclose(dome.irradiance(n), np.pi, rtol=0.01)
    sky = gradient_sky([0.2, 0.4, 1.0], [0.6, 0.6, 0.7])
    dome = SkyDome(sky, sun_direction(0, 45), [0, 0, 0], [0.0, 0.0, 0.0])
    d, w = sphere_quadrature(128, 256)
    L = np.where(d[:, 1:2] > 0, sky(d), 0.0)
    for nn in ([0, 1, 0], [1, 0, 0], [0, 0.7071, 0.7071]):
        nn = np.asarray(nn, np.float64)
        brute = (L * (np.clip(d @ nn, 0, None) * w)[:, None]).sum(0)
        np.testing.assert_allclose(dome.irradiance(nn[None])[0], brute, rtol=0.1, atol=0.03)


# --------------------------------------------------------------------------------------- shot / inputs
def _shot_entry():
    return {"shot": "s", "frames": [3], "origin": [0.0, 0.0, -1000.0], "spp": 1, "upsampling": "mallett2019",
            "angle_step_deg": 1.0, "wavelengths": {"start": 380.0, "stop": 780.0, "step": 5.0},
            "sun": {"intensity": None, "spd": "matched"},
            "ground": {"texture": {"color": [0.2, 0.4, 0.1]}, "extent": [2.0, 2.0]}, "meadow": {}}


def _write_shot(tmp_path, frame=3, resolution=(8, 6), state=None):
    from natscene.io import write_exr, write_yaml
    W, H = resolution
    write_yaml(tmp_path / f"shots/s/params/{frame:04d}.yaml", state or {
        "sun": {"azimuth": 105.0, "elevation": 3.0},
        "params": {"c_in": [1.45, 0.92, 0.48], "L_in": 4.5, "kappa_a": [0.05, 0.12, 0.25]},
        "camera": {"position": [0.2, 0.3, -1000.0], "look_at": [0.2, 0.3, 0.0], "up": [0, 1, 0], "fov": 40.0}})
    write_exr(tmp_path / f"shots/s/frames/{frame:04d}.exr", np.full((H, W, 3), 0.4, np.float32), ["R", "G", "B"])
    write_yaml(tmp_path / "volumes/v/meta.yaml", {"bbox_min": [-500.0, 0.0, -500.0], "bbox_max": [500.0, 600.0, 500.0]})
    return {"volume": "v", "resolution": list(resolution), "sky": {"model": "preetham"}, "exposure": 1.0}


def test_composite_frame_follows_the_shot_frame(tmp_path):
    """Frame k of a composite: frame k's camera (in the set's frame), sun (direction, c_in, L_in), κ_a, the
    camera-to-cloud distance, the shot's resolution and sky; a malformed state or a plate of the wrong size
    names the file."""
    from natscene.composite.inputs import build_set
    from natscene.errors import InputError
    from natscene.io import write_exr, write_yaml
    shot = _write_shot(tmp_path)
    spec = build_set(_shot_entry(), 3, str(tmp_path), str(tmp_path), shot)
    np.testing.assert_allclose(spec.camera.position, [0.2, 0.3, 0.0])
    assert (spec.camera.width, spec.camera.height, spec.camera.fov) == (8, 6, 40.0)
    np.testing.assert_allclose(spec.sun_dir, sun_direction(105.0, 3.0))
    rgb = spectrum_to_rgb(spec.sun_spectrum())
    np.testing.assert_allclose(rgb, 4.5 * np.array([1.45, 0.92, 0.48]), rtol=3e-2)
    np.testing.assert_allclose(spec.atmosphere.kappa, [0.05, 0.12, 0.25])
    assert spec.atmosphere.reference_distance == pytest.approx(np.linalg.norm([0.2, 0.3 - 300.0, -1000.0]))
    from natscene.sky.daylight import preetham_rgb
    d = np.array([[0.0, 0.3, 1.0]]) / np.linalg.norm([0.0, 0.3, 1.0])
    np.testing.assert_allclose(spec.sky(d), preetham_rgb(d, sun_direction(105.0, 3.0), 3.0, 0.3, 35.0, 1.0),
                               rtol=1e-6)   # the shots' default sky
    write_yaml(tmp_path / "shots/s/params/0004.yaml", {"sun": {"azimuth": 105.0}})
    with pytest.raises(InputError, match="0004.yaml"):
        build_set(_shot_entry(), 4, str(tmp_path), str(tmp_path), shot)
    write_exr(tmp_path / "shots/s/frames/0003.exr", np.zeros((5, 5, 3), np.float32), ["R", "G", "B"])
    with pytest.raises(InputError, match="0003.exr"):
        build_set(_shot_entry(), 3, str(tmp_path), str(tmp_path), shot)


def test_pattern_without_alpha_names_the_file(tmp_path):
    from natscene.composite.inputs import build_set
    from natscene.errors import InputError
    from natscene.io import write_exr
    shot = _write_shot(tmp_path)
    write_exr(tmp_path / "patterns/p/color.exr", np.full((8, 8, 3), 0.5, np.float32), ["R", "G", "B"])
    entry = {**_shot_entry(), "meadow": {"area": {"near": 0.5, "far": 3.0, "half_angle": 30.0},
                                         "flowers": [{"pattern": "p", "count": 2}]}}
    with pytest.raises(InputError, match="patterns/p/color.exr"):
        build_set(entry, 3, str(tmp_path), str(tmp_path), shot)


def test_aerial_perspective_over_the_ground_is_dobashi_eq3():
    """Each ground pixel is L_g e^{-κ t / d_ref} + (1 - e^{-κ t / d_ref}) L_sky(direction) (Dobashi Eq. 3 with
    the ray's distance t to the ground): the far ground takes the horizon sky's colour, the near its own."""
    from natscene.composite.set_spec import Atmosphere
    W, H = 9, 120
    cam = Camera((0.0, 1.0, 0.0), (0.0, 1.0, 10.0), (0.0, 1.0, 0.0), fov=40, width=W, height=H)
    sky = gradient_sky([0.2, 0.3, 0.9], [0.8, 0.7, 0.6])
    kappa = np.array([1.0, 2.0, 4.0])
    spec = SetSpec(cam, np.zeros((H, W, 3), np.float32),
                   Ground(MipTexture(np.full((4, 4, 3), 0.1, np.float32), wrap=True), (1.0, 1.0)),
                   sun_dir=sun_direction(0, 60), sun_spd=d65() * 2.0, sky=sky, spp=1,
                   atmosphere=Atmosphere(kappa, 100.0))
    img = SetRenderer(spec).render_hybrid().final()[:, W // 2]
    spec.atmosphere = None
    bare = SetRenderer(spec).render_hybrid().final()[:, W // 2]
    d = cam.ray_directions()[:, W // 2]
    ground = d[:, 1] < 0
    t = 1.0 / -d[ground, 1]
    T = np.exp(-kappa[None] * t[:, None] / 100.0)
    want = bare[ground] * T + (1 - T) * sky(d[ground])
    np.testing.assert_allclose(img[ground], want, rtol=2e-3, atol=1e-5)
    assert np.abs(img[ground][0] - [0.8, 0.7, 0.6]).max() < 0.1  # next to the horizon: the sky's colour
    np.testing.assert_allclose(img[~ground], 0.0)  # the plate above


# -------------------------------------------------------------------------------- the main job's frame
def test_cloud_above_the_horizon_for_the_main_job_camera():
    """The main job's composite camera (the shot's keyframe cameras, metres) and the shot volume's placement:
    the cloud's pixels in the final frame (a plate showing the volume's box) are all on or above the horizon
    line and survive compositing (the ground covers the plate only below the horizon), and the cloud stands
    well above it (its centre at least 5 % of the frame height above)."""
    from natscene.composite.renderer import SetRenderer as R
    from natscene.config import load_yaml_config, validate_config
    from natscene.geometry import ray_box
    from natscene.keyframes.shot import resolve_keyframe
    from natscene.volume.build import DEFAULT_ALTITUDE_M, DEFAULT_SIZE_M
    from natscene.volume.grid import placement
    from pathlib import Path
    root = Path(__file__).resolve().parents[1]
    cfg = load_yaml_config(root / "config" / "config.yaml")
    validate_config(cfg, root / "workflow" / "schemas" / "config.schema.yaml")
    entry = next(e for e in cfg["composite"].values() if e.get("shot"))
    shot = cfg["shots"][entry["shot"]]
    vol = cfg["volumes"][shot["volume"]]
    lo, hi = placement(vol["resolution"], vol.get("size") or DEFAULT_SIZE_M[vol["kind"]])  # as build_volume places it
    alt = DEFAULT_ALTITUDE_M if vol.get("altitude") is None else float(vol["altitude"])
    lo, hi = lo + np.array([0.0, alt, 0.0]), hi + np.array([0.0, alt, 0.0])
    W, H = shot["resolution"][0] // 4, shot["resolution"][1] // 4
    origin = np.asarray(entry["origin"], np.float64)
    for i, kf in enumerate(shot["keyframes"]):
        c = resolve_keyframe(entry["shot"], i, kf, cfg)["camera"]
        cam_w = Camera(tuple(c["position"]), tuple(c["look_at"]), tuple(c["up"]), c["fov"], W, H)
        d = cam_w.ray_directions().reshape(-1, 3)
        t0, t1 = ray_box(np.broadcast_to(np.asarray(c["position"], float), d.shape), d, lo, hi)
        cloud = (t1 > t0).reshape(H, W)
        assert cloud.sum() > 0.01 * W * H, "the cloud is in the frame"
        plate = np.where(cloud[..., None], 2.0, 0.3).astype(np.float32) * np.ones((1, 1, 3), np.float32)
        cam = Camera(tuple(np.subtract(c["position"], origin)), tuple(np.subtract(c["look_at"], origin)),
                     tuple(c["up"]), c["fov"], W, H)
        spec = SetSpec(cam, plate, Ground(MipTexture(np.full((4, 4, 3), 0.1, np.float32), wrap=True), (1.0, 1.0)),
                       sun_spd=d65() * 2.0, spp=1)
        final = R(spec).render_hybrid().final()
        # horizon: the rows whose central ray points below the horizontal
        below = (cam.ray_directions()[:, W // 2, 1] < 0)
        horizon_row = int(np.argmax(below))
        rows = np.nonzero(cloud)[0]
        assert rows.max() <= horizon_row
        kept = np.abs(final - plate).max(-1) < 1e-5
        assert kept[cloud].mean() > 0.99
        assert horizon_row - rows.mean() > 0.05 * H
