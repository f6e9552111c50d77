"""Recolouring a flower photo (Dong 2007 §3.5, Fig. 3.8): vein tree extracted from a photo, vein transport of
the root supply (Eq. 3.1), and the YIQ recolouring."""
import numpy as np
import pytest
from scipy import ndimage

from natscene.color import linear_to_srgb, luminance, srgb_to_yiq
from natscene.errors import InputError
from natscene.patterns.expression import express_rgb, precompute
from natscene.patterns.pigments import pigment
from natscene.patterns.presets import rd_params
from natscene.patterns.reaction_diffusion import simulate
from natscene.patterns.recolour import recolour, recolour_photo, vein_contrast
from natscene.patterns.venation import venation_from_photo

N, R, N_LINES = 96, 44.0, 8
CENTRE = ((N - 1) / 2.0, (N - 1) / 2.0)


@pytest.fixture(scope="module")
def disc():
    """An orange disc (radius R) with N_LINES dark radial lines (~1.5 px wide) from its centre, a little shading."""
    yy, xx = np.mgrid[0:N, 0:N].astype(float)
    dy, dx = yy - CENTRE[1], xx - CENTRE[0]
    r, phi = np.hypot(dx, dy), np.arctan2(dy, dx)
    inside = r <= R
    # distance to the nearest radial line (rays from the centre, 4 px out to the rim)
    ang = 2 * np.pi * np.arange(N_LINES) / N_LINES + 0.2
    d = np.min(np.abs(r[..., None] * np.sin(phi[..., None] - ang)), axis=-1)
    on = np.cos(phi[..., None] - ang).max(-1) > 0  # the ray's side, not its opposite
    d_lines = np.where((r >= 2) & (r <= R - 3), d, np.inf)
    along = np.zeros((N, N), bool)
    for a in ang:
        along |= (np.abs(r * np.sin(phi - a)) < 0.75) & (np.cos(phi - a) > 0) & (r >= 2) & (r <= R - 3)
    shade = 0.8 + 0.2 * np.cos(0.07 * xx) * np.cos(0.05 * yy)
    lum = np.where(inside, shade * (1.0 - 0.6 * np.exp(-0.5 * (np.where(on, d_lines, np.inf) / 0.8) ** 2)), 0.02)
    rgb = lum[..., None] * np.array([0.9, 0.35, 0.05])
    return dict(rgb=rgb.astype(np.float32), mask=inside.astype(np.float32), lines=along)


@pytest.fixture(scope="module")
def tree(disc):
    return venation_from_photo(luminance(disc["rgb"]), disc["mask"], (0.5, 0.5), bright_ridges=False)


def test_tree_connected_to_root(tree):
    vas = tree.vascular
    assert vas[tree.root]
    lab, n = ndimage.label(vas, structure=np.ones((3, 3)))
    assert (lab[vas] == lab[tree.root]).all(), f"{n} vein components; all must hang from the root"
    # the cells also conduct through the 4-neighbour grid of the Laplacian
    lab4, _ = ndimage.label(vas)
    assert (lab4[vas] == lab4[tree.root]).all()
    assert np.isfinite(tree.dist[vas]).all() and tree.dist[tree.root] == 0
    assert (tree.width[vas] > 0).all() and tree.width.max() == pytest.approx(1.0)


def test_tree_on_drawn_lines(disc, tree):
    near = ndimage.distance_transform_edt(~disc["lines"]) <= 2.0
    frac = near[tree.vascular].mean()
    assert frac > 0.8, f"only {frac:.0%} of vein cells within 2 px of a drawn line"
    # every drawn line is found: each one's outer half carries vein cells
    yy, xx = np.mgrid[0:N, 0:N]
    phi = np.arctan2(yy - CENTRE[1], xx - CENTRE[0])
    r = np.hypot(yy - CENTRE[1], xx - CENTRE[0])
    for a in 2 * np.pi * np.arange(N_LINES) / N_LINES + 0.2:
        sector = (np.cos(phi - a) > np.cos(np.radians(8))) & (r > R / 2)
        assert (tree.vascular & sector).sum() >= 5, f"no vein along the line at {np.degrees(a):.0f} deg"


def test_paths_start_at_root_with_unit_steps(tree):
    assert tree.paths and len(tree.paths) >= N_LINES
    for P in tree.paths:
        assert P.dtype.kind == "i" and P.ndim == 2 and P.shape[1] == 2
        assert tuple(P[0]) == tree.root
        step = np.abs(np.diff(P, axis=0))
        assert (step.max(axis=1) == 1).all()  # 8-connected, no repeats
        assert tree.vascular[P[:, 0], P[:, 1]].all()
        # dist grows along the path by the step lengths (path length along the tree)
        d = np.r_[0.0, np.cumsum(np.hypot(*step.T))]
        np.testing.assert_allclose(tree.dist[P[:, 0], P[:, 1]], d, rtol=1e-5)


def test_root_outside_mask_is_moved_onto_the_petal(disc):
    v = venation_from_photo(luminance(disc["rgb"]), disc["mask"], (0.02, 0.02), bright_ridges=False)
    assert disc["mask"][v.root] > 0.5


def test_veins_conduct_the_root_supply(disc, tree):
    """Eq. 3.1: vascular links (p_mv = 2, p_vv = 10, scaled by t) carry the hormone held at the root further along
    the veins than through the mesophyll (p_mm = 1), so with an over-supplied root the map is higher on the veins."""
    p = rd_params({"preset": "radial_stripes", "root_supply": [5.0, 2.24], "t": 20.0}, 0, N)
    r = simulate(disc["mask"], tree, p)
    vein, inter = vein_contrast(r.a, tree.vascular, disc["mask"])
    assert vein > 1.2 * inter, (vein, inter)
    # and without vein transport (t = 0) the same supply gives no such vein/inter-vein difference
    r0 = simulate(disc["mask"], tree, rd_params({"preset": "radial_stripes", "root_supply": [5.0, 2.24],
                                                 "t": 0.0}, 0, N))
    v0, i0 = vein_contrast(r0.a, tree.vascular, disc["mask"])
    assert vein / inter > 1.1 * v0 / i0


def test_recolour_keeps_outside_and_luma_detail(disc):
    photo, mask = disc["rgb"], disc["mask"]
    table = precompute([pigment("betanin"), pigment("blank")])
    conc = np.broadcast_to(np.array([1.0, 0.0]), photo.shape[:2] + (2,))
    out = recolour(photo, express_rgb(table, conc), express_rgb(table, np.zeros(2)), mask)
    outside = mask < 0.5
    np.testing.assert_array_equal(out[outside], photo[outside])
    inside = ~outside
    y_in = srgb_to_yiq(linear_to_srgb(photo))[..., 0][inside]
    y_out = srgb_to_yiq(linear_to_srgb(out))[..., 0][inside]
    assert np.corrcoef(y_in, y_out)[0, 1] > 0.9
    # the hue is the pigment's: a red-violet (green-absorbing) pigment makes G the lowest channel
    enc = linear_to_srgb(out)[inside]
    assert (enc[:, 1] <= enc[:, 0] + 1e-3).mean() > 0.95 and (enc[:, 1] <= enc[:, 2] + 1e-3).mean() > 0.95
    # zero concentration gives the pigment-free (grey) colour at the photo's luma
    zero = recolour(photo, express_rgb(table, np.zeros(photo.shape[:2] + (2,))), express_rgb(table, np.zeros(2)),
                    mask)
    yiq0 = srgb_to_yiq(linear_to_srgb(zero))[inside]
    assert np.abs(yiq0[:, 1:]).max() < 0.03
    np.testing.assert_allclose(yiq0[:, 0], y_in, atol=0.01)


def test_bad_photo_path_names_the_file(tmp_path):
    bad = tmp_path / "no_such_flower.jpg"
    with pytest.raises(InputError, match="no_such_flower.jpg"):
        recolour_photo(bad, {"photo": str(bad)})
