"""Scattering precompute, composition and forward renderer with Dobashi's transport (``transport: dobashi``,
2012 §4.3, Eqs. 3–9): these tests are also the regression test of the paper's model, which stays selectable
beside the all-orders default (tests/test_transport.py).

References known independently of the code: closed forms for a constant-density box, and Mitsuba 3's own
``volpath`` integrator on the same volume / camera / sun / HG phase / albedo / extinction (per order via its
max_depth). Error metric over cloud pixels: relative L1 = Σ|ours - ref| / Σ ref.
"""
import numpy as np
import pytest

import natscene  # noqa: F401
from natscene.errors import InputError
from natscene.geometry import Camera, ray_box
from natscene.scatter.compose import apply_atmosphere, compose, compose_cloud
from natscene.scatter.nodes import lerp_weights
from natscene.scatter.medium import make_medium
from natscene.scatter.mitsuba_scene import render_reference, render_transmittance
from natscene.scatter.multiple import trace_orders
from natscene.scatter.phase import hg
from natscene.scatter.render import render
from natscene.scatter.single import march_view
from natscene.scatter.tables import load_tables, precompute, save_tables
from natscene.volume.grid import Volume, placement

SUN = np.array([0.5, 0.6, 0.3]) / np.linalg.norm([0.5, 0.6, 0.3])
CAM = Camera((0.0, 0.25, -2.4), (0.0, 0.28, 0.0), (0.0, 1.0, 0.0), fov=30, width=32, height=24)


K = 40.0   # the blob's extinction_scale: extinction [1/m of the unit box] = sigma_t * K


def blob_volume(scale=K):
    nx, ny, nz = 24, 16, 24
    lo, hi = placement((nx, ny, nz))
    z, y, x = np.meshgrid(np.linspace(-1, 1, nz), np.linspace(0, 1, ny), np.linspace(-1, 1, nx), indexing="ij")
    d = np.clip(1 - (x ** 2 + ((y - 0.45) / 0.5) ** 2 + z ** 2) / 0.6, 0, 1).astype(np.float32)
    return Volume(d, lo, hi, scale)


def rel_l1(a, b, mask):
    return float(np.abs(a - b)[mask].sum() / np.abs(b)[mask].sum())


@pytest.fixture(scope="module")
def vol():
    return blob_volume()


@pytest.fixture(scope="module")
def tables(vol, tmp_path_factory):
    tb = precompute(vol, CAM, SUN, extinctions=[0.0, 0.5 * K, 1.0 * K], gs=[0.0, 0.4, 0.8], n_m=4, spp=4096, seed=1, transport="dobashi")
    d = tmp_path_factory.mktemp("pre")
    save_tables(d, tb)
    return tb, d


def params(sig, g, beta, L_amb=0.0, L_in=1.0, kappa=0.0):
    return dict(c_in=[1.0, 1.0, 1.0], L_in=L_in, g=g, extinction=sig * K, beta=beta, L_amb=L_amb, kappa_a=[kappa] * 3)


# ------------------------------------------------------------------------------ closed forms
def test_constant_box_closed_forms():
    n = 16
    lo, hi = placement((n, n, n))
    vol = Volume(np.ones((n, n, n), np.float32), lo, hi, 5.0)
    sun = np.array([0.0, 1.0, 0.0])
    cam = Camera((0.0, 0.3, -2.0), (0.0, 0.3, 0.0), (0.0, 1.0, 0.0), fov=20, width=24, height=18)
    med = make_medium(vol, sun)
    sig = [0.0, 0.3, 1.0]
    r = march_view(med, cam, sig, supersample=1)
    d = cam.ray_directions()
    o = np.broadcast_to(np.asarray(cam.position, float), d.shape)
    t0, t1 = ray_box(o, d, lo, hi)
    L = np.maximum(t1 - t0, 0)
    hit = L > 0.05
    assert hit.sum() > 50
    for i, s in enumerate(sig):
        mu = s * vol.extinction_scale
        T = np.exp(-mu * L)
        amb = L if s == 0 else (1 - T) / mu
        np.testing.assert_allclose(r["T"][i][hit], T[hit], rtol=5e-3, atol=1e-6)
        np.testing.assert_allclose(r["S_amb"][i][hit], amb[hit], rtol=5e-3)
        if s > 0:
            # sun overhead: tau_sun = exp(-mu (y_top - y(t))), y(t) = y0 + dy t, so
            # S_sun = ∫_t0^t1 mu exp(-mu (t - t0)) exp(-mu (y_top - y0 - dy t)) dt in closed form
            y0, dy = cam.position[1], d[..., 1]
            a = mu * (1 - dy)
            ssun = mu * np.exp(-mu * (hi[1] - y0) + mu * t0) * (np.exp(-a * t0) - np.exp(-a * t1)) / a
            y_ends = np.maximum(y0 + dy * t0, y0 + dy * t1)
            inner = hit & (y_ends < hi[1] - 0.1) & (np.minimum(y0 + dy * t0, y0 + dy * t1) > lo[1] + 0.05)
            assert inner.sum() > 20
            np.testing.assert_allclose(r["S_sun"][i][inner], ssun[inner], rtol=5e-3)
    assert np.all(r["footprint"][hit] == 1) and np.all(r["footprint"][L == 0] == 0)


@pytest.mark.parametrize("zenith", [0.0, 60.0])
def test_single_scattering_of_a_thick_slab_closed_form(zenith):
    """Order 1 seen along the normal of a slab two mean free paths per voxel (the march steps 1 mean free path):
    S_sun = mu0 / (1 + mu0) (1 - exp(-tau (1 + 1 / mu0))). The sun's optical depth changes by 1 / mu0 across a
    step, which the sun's transmittance at the step's midpoint made 27 % low at 60 deg."""
    from natscene.scatter.reference_scene import slab_camera, slab_volume
    tau = 64.0
    vol = slab_volume(tau=tau, n=(48, 32, 48), width=12.0)
    z = np.radians(zenith)
    med = make_medium(vol, np.array([-np.sin(z), np.cos(z), 0.0]))
    r = march_view(med, slab_camera(1.0, above=True, res=8), [1.0], supersample=1)
    mu0 = np.cos(z)
    expected = mu0 / (1 + mu0) * (1 - np.exp(-tau * (1 + 1 / mu0)))
    np.testing.assert_allclose(r["S_sun"][0], expected, rtol=5e-3)


def test_transmittance_matches_volpath(vol):
    med = make_medium(vol, SUN)
    r = march_view(med, CAM, [0.5])
    ref = render_transmittance(vol, CAM, 0.5, spp=1024)
    cloud = r["footprint"] > 0
    # volpath's T is a 0/1 estimate per sample (noise ~ sqrt(T(1-T)/spp) per pixel): per-pixel L1 is
    # noise-bound, the sum over the cloud is not
    assert rel_l1(r["T"][0], ref, cloud) < 0.03
    assert abs(r["T"][0][cloud].sum() - ref[cloud].sum()) / ref[cloud].sum() < 0.005


# ------------------------------------------------------------------------------ Mitsuba volpath
def test_single_and_order2_match_volpath(vol):
    tb = precompute(vol, CAM, SUN, extinctions=[0.5 * K], gs=[0.5], n_m=2, spp=4096, seed=3, with_error=False,
                    transport="dobashi")
    sky = np.zeros((CAM.height, CAM.width, 3), np.float32)
    cloud = (tb.footprint > 0) & (tb.transmittance[0] < 0.95)
    single = tb.s_sun[0] * 0.9 * hg(tb.cos_theta, 0.5)
    ref1 = render_reference(vol, CAM, SUN, 0.5, 0.5, 0.9, orders=1, spp=1024)[..., 0]
    assert rel_l1(single, ref1, cloud) < 0.03
    img = compose_cloud(tb, params(0.5, 0.5, 0.9), sky)[0, ..., 0]
    ref2 = render_reference(vol, CAM, SUN, 0.5, 0.5, 0.9, orders=2, spp=4096)[..., 0]
    assert rel_l1(img, ref2, cloud) < 0.03
    assert img[cloud].sum() > 1.1 * single[cloud].sum()  # order 2 is there


@pytest.mark.parametrize("sig,g,beta", [(0.5, 0.0, 0.9), (0.5, 0.8, 0.95), (1.0, 0.4, 0.99)])
def test_compose_matches_volpath_four_orders(tables, vol, sig, g, beta):
    tb, _ = tables
    sky = np.zeros((CAM.height, CAM.width, 3), np.float32)
    img = compose(tb, params(sig, g, beta), sky)[0, ..., 0]
    ref = render_reference(vol, CAM, SUN, sig, g, beta, orders=4, spp=8192, seed=5)[..., 0]
    i = list(tb.extinction).index(sig * K)
    cloud = (tb.footprint > 0) & (tb.transmittance[i] < 0.95)
    err = rel_l1(img, ref, cloud)
    bias = abs(img[cloud].sum() - ref[cloud].sum()) / ref[cloud].sum()
    print(f"sigma_t={sig} g={g} beta={beta}: relative L1 vs volpath {err:.4f}, bias of the sum {bias:.4f}")
    # sum bias measured 0.2 / 0.9 / 0.4 % (it was 2.2 % at sigma_t = 1 before the sun optical depth got its
    # exact near field, see Medium.sun_depth); the issue allows 3 %
    assert bias < 0.015
    # per pixel both sides carry Monte Carlo noise; with g = 0.8 next-event estimation through the peaked
    # HG lobe is heavy-tailed (measured 0.10 at 1k/2k spp, 0.057 at 4k/8k spp: noise, not bias)
    assert err < (0.08 if g >= 0.8 else 0.04)


def test_g08_meets_three_percent_with_stronger_reference(vol):
    """The issue's <= 3 % mean relative error for g = 0.8 (all g of the table from the same paths, mixture
    proposal over [0, 0.4, 0.8]). Per-pixel noise is what limits it (measured at 4k spp, 16x12: ours 0.063,
    volpath 0.035 relative L1 between two seeds / sqrt 2), so both sides get 32k spp at half the test
    resolution (expected combined noise ~0.02). At 16x12 a pixel spans ~2 voxels of the blob: the
    single-scattering march's 2x2 sub-rays (supersample=4) then leave a 2.6 % per-pixel box-filter error
    against volpath's order 1 (measured; 1.1 % with 4x4), so this test marches 4x4 sub-rays per pixel."""
    cam = Camera(CAM.position, CAM.look_at, CAM.up, fov=CAM.fov, width=16, height=12)
    tb = precompute(vol, cam, SUN, extinctions=[0.0, 0.5 * K], gs=[0.0, 0.4, 0.8], n_m=4, spp=32768, seed=2, transport="dobashi",
                    supersample=16, with_error=False)
    img = compose(tb, params(0.5, 0.8, 0.95), np.zeros((12, 16, 3), np.float32))[0, ..., 0]
    ref = render_reference(vol, cam, SUN, 0.5, 0.8, 0.95, orders=4, spp=32768, seed=7)[..., 0]
    cloud = (tb.footprint > 0) & (tb.transmittance[1] < 0.95)
    assert cloud.sum() >= 25
    err = rel_l1(img, ref, cloud)
    bias = abs(img[cloud].sum() - ref[cloud].sum()) / ref[cloud].sum()
    print(f"g=0.8 at 16x12, 32k/32k spp: relative L1 vs volpath {err:.4f}, bias of the sum {bias:.4f}")
    assert err < 0.03 and bias < 0.015


@pytest.mark.parametrize("opts", [dict(split=4), dict(guide=0.3, g_guide=0.8)])
def test_sampling_options_are_unbiased(vol, opts):
    """Splitting at the first vertex and sun-guided directions change only the variance: the image sums
    of every order and g agree with plain sampling within 4 combined standard errors."""
    med = make_medium(vol, SUN)
    cam = Camera(CAM.position, CAM.look_at, CAM.up, fov=CAM.fov, width=16, height=12)
    a, sa = trace_orders(med, cam, 0.5, [0.0, 0.8], n_max=3, spp=4096, seed=4, with_error=True)
    b, sb = trace_orders(med, cam, 0.5, [0.0, 0.8], n_max=3, spp=4096 // opts.get("split", 1), seed=5,
                         with_error=True, **opts)
    for k in range(3):
        for j in range(2):
            d = abs(a[k, j].sum() - b[k, j].sum())
            s = np.sqrt((sa[k, j] ** 2).sum() + (sb[k, j] ** 2).sum())
            assert d < 4 * s + 1e-9, (k + 1, j, d, s)
            assert s < 0.05 * a[k, j].sum()  # the check has power


# ------------------------------------------------------------------------------ composition
def test_compose_at_grid_point_equals_tables(tables):
    tb, _ = tables
    H, W = tb.t_c.shape
    sky = np.zeros((H, W, 3), np.float32)
    si, gi = 2, 1
    img = compose_cloud(tb, params(tb.extinction[si] / K, tb.g[gi], 1.0), sky)[0, ..., 1]
    want = hg(tb.cos_theta, tb.g[gi]) * tb.s_sun[si] + tb.multiple[:, gi, si].sum(0)
    np.testing.assert_allclose(img, want, rtol=1e-4, atol=1e-9)
    amb = compose_cloud(tb, params(tb.extinction[si] / K, 0.0, 0.5, L_amb=1.0, L_in=0.0), sky)[0, ..., 0]
    np.testing.assert_allclose(amb, tb.s_amb[si], rtol=1e-4, atol=1e-9)
    sky1 = np.ones((H, W, 3), np.float32)
    bg = compose_cloud(tb, params(tb.extinction[si] / K, 0.0, 0.5, L_in=0.0), sky1)[0, ..., 2]
    np.testing.assert_allclose(bg, tb.transmittance[si], rtol=1e-4)


def test_population_and_interpolation(tables):
    tb, _ = tables
    H, W = tb.t_c.shape
    sky = np.full((H, W, 3), 0.2, np.float32)
    P = dict(c_in=[[1, 0.9, 0.8], [0.7, 0.8, 1.0]], L_in=[2.0, 3.0], g=[0.2, 0.6], extinction=[0.25 * K, 0.75 * K],
             beta=[0.9, 0.99], L_amb=[0.1, 0.0], kappa_a=[[0.1, 0.2, 0.3], [0, 0, 0]])
    both = compose(tb, P, sky)
    assert both.shape == (2, H, W, 3) and both.dtype == np.float32
    one = compose(tb, {k: np.asarray(v)[1] for k, v in P.items()}, sky)
    np.testing.assert_allclose(both[1], one[0], rtol=1e-6)
    # linear in sigma_t between grid points: midpoint of S_amb
    mid = compose_cloud(tb, params(0.25, 0.0, 0.5, L_amb=1.0, L_in=0.0), sky * 0)[0, ..., 0]
    np.testing.assert_allclose(mid, 0.5 * (tb.s_amb[0] + tb.s_amb[1]), rtol=1e-5)
    w = lerp_weights([0, 0.5, 1.0], [-1, 0.25, 1.0, 3])
    np.testing.assert_allclose(w, [[1, 0, 0], [0.5, 0.5, 0], [0, 0, 1], [0, 0, 1]])


def test_atmosphere_eq3(tables):
    tb, _ = tables
    H, W = tb.t_c.shape
    L_c = np.random.default_rng(0).random((2, H, W, 3)).astype(np.float32)
    sky = np.full((H, W, 3), 0.3, np.float32)
    np.testing.assert_allclose(apply_atmosphere(L_c, tb.t_c, 0.0, sky), L_c, rtol=1e-5, atol=1e-7)
    far = apply_atmosphere(L_c, np.full((H, W), 100.0, np.float32), [1.0, 1.0, 1.0], sky)
    np.testing.assert_allclose(far, np.broadcast_to(sky, far.shape), atol=1e-6)
    k = np.array([[0.2, 0.5, 1.0], [0.0, 0.0, 0.0]])
    out = apply_atmosphere(L_c, tb.t_c, k, sky)
    e = np.exp(-0.5 * tb.t_c)
    np.testing.assert_allclose(out[0, ..., 1], L_c[0, ..., 1] * e + (1 - e) * 0.3, rtol=1e-5)
    np.testing.assert_allclose(out[1], L_c[1], rtol=1e-5, atol=1e-7)


def test_save_load_roundtrip(tables):
    tb, d = tables
    back = load_tables(d)
    for name in ("s_sun", "s_amb", "transmittance", "multiple", "t_c", "cos_theta", "footprint"):
        np.testing.assert_array_equal(getattr(back, name), getattr(tb, name))
    assert back.orders == [2, 3, 4] and np.allclose(back.g, tb.g)
    assert 0 < tb.t_c[tb.footprint > 0].min() < 1.2


def test_render_agrees_with_compose_and_interpolation_error(tables, vol):
    tb, _ = tables
    sky = np.full((CAM.height, CAM.width, 3), 0.1, np.float32)
    for sig, g, tol in [(0.5, 0.4, 0.03), (0.75, 0.6, 0.10)]:  # grid point, then between grid points
        p = params(sig, g, 0.95, L_amb=0.05, kappa=0.2)
        c = compose(tb, p, sky)[0]
        r = render(vol, CAM, SUN, p, sky, {"orders": 4, "spp": 1024, "seed": 9, "transport": "dobashi"})
        cloud = tb.footprint > 0
        err = rel_l1(c, r, cloud)
        print(f"compose vs render sigma_t={sig} g={g}: relative L1 {err:.4f}")
        assert err < tol


def test_bad_input(tables):
    tb, _ = tables
    with pytest.raises(InputError):
        compose(tb, params(0.5, 0.5, 0.9), np.zeros((5, 5, 3)))
    with pytest.raises(InputError):
        precompute(blob_volume(), CAM, SUN, extinctions=[0.5, 0.2])
    with pytest.raises(InputError):
        make_medium(Volume(np.zeros((4, 4, 4), np.float32), np.zeros(3), np.ones(3), 1.0))


def _two_lumps() -> Volume:
    """Two lumps far apart in a wide box (72 x 24 x 32 voxels): empty majorant cells between and around them."""
    nx, ny, nz = 72, 24, 32
    z, y, x = np.meshgrid(np.linspace(-1, 1, nz), np.linspace(0, 1, ny), np.linspace(-1, 1, nx), indexing="ij")
    lump = lambda cx, r: np.clip(1 - ((x - cx) ** 2 + ((y - 0.5) / 0.6) ** 2 + z ** 2) / r ** 2, 0, 1)
    d = (lump(-0.75, 0.25) + 0.5 * lump(0.7, 0.2)).astype(np.float32)
    return Volume(d, *placement((nx, ny, nz)), 80.0)


def test_order_one_passes_over_empty_space_exactly():
    """Order 1's march (``march_view``) passes over empty majorant cells: the same sample points and segments, so
    the same S_sun, S_amb, T, distance and footprint as a march that takes every step (two lumps far apart in a
    wide box, three sigma_t, 0 among them)."""
    from natscene.scatter.reference_scene import CAM, SUN
    from natscene.scatter.single import march_view
    med = make_medium(_two_lumps(), SUN)
    every = march_view(med, CAM, [0.0, 0.5, 3.0], supersample=4, skip_empty=False)
    skipping = march_view(med, CAM, [0.0, 0.5, 3.0], supersample=4)
    assert every["S_sun"][1].max() > 0.05 and every["footprint"].sum() > 50
    for k in every:
        np.testing.assert_array_equal(skipping[k], every[k], err_msg=k)


def _gather_inputs(seed: int):
    """(volume, medium, 3 random cache fields, their denominators) on two lumps far apart, cells of 2 voxels."""
    from natscene.scatter.reference_scene import SUN
    vol = _two_lumps()
    d = vol.density
    nz, ny, nx = d.shape
    den = (d.reshape(nz // 2, 2, ny // 2, 2, nx // 2, 2).sum((1, 3, 5)) + 1e-3).astype(np.float32)
    caches = (np.random.default_rng(seed).random((3,) + den.shape) * den).astype(np.float32)
    return vol, make_medium(vol, SUN), caches, den


def test_gather_passes_over_empty_space_exactly():
    """The cache gather's march passes over empty majorant cells in whole steps: the same sample points, so the
    same images as a march that takes every step (two lumps far apart in a wide box, random cache fields)."""
    from natscene.scatter.inscatter import gather
    from natscene.scatter.majorant import majorant_grid
    from natscene.scatter.reference_scene import CAM
    vol, med, caches, den = _gather_inputs(0)
    grid = majorant_grid(vol.density, vol.bbox_min, vol.bbox_max, 4)
    assert (np.asarray(grid.dr_skip) > 0).any()
    every = gather(med, CAM, 0.5, caches, den, 2, 0.5, 1)
    skipping = gather(med, CAM, 0.5, caches, den, 2, 0.5, 1, grid=grid)
    assert every.max() > 0.05
    np.testing.assert_allclose(skipping, every, rtol=0, atol=1e-6 * float(every.max()))


def test_gather_is_bounded_by_the_cells_the_camera_sees():
    """The view integral of the cache, sum T_prev (1 - e^(-sigma rho h)) S, is at most the largest in-scatter
    S = C / Q of the cells it interpolates: a cell the camera cannot see (Q = 0) but holding tallies (a grazing
    view's voxel at a face) adds nothing, instead of C divided by its neighbours' Q, which vanishes toward its centre
    (10^21 times too bright in a slab seen from 89 degrees)."""
    from natscene.scatter.inscatter import cache_fields, gather
    from natscene.scatter.reference_scene import CAM
    _, med, caches, den = _gather_inputs(2)
    dead = np.zeros(den.shape, bool)
    dead[::2, ::2, ::2] = True
    den = np.where(dead, 0.0, den)
    caches = np.where(dead, 5.0 * caches.max(), caches)
    num, q = cache_fields(caches, den)
    img = gather(med, CAM, 0.5, num, q, 2, 0.5, 1)
    bound = float((caches[:, ~dead] / den[~dead]).max())
    assert img.max() > 0.05 * bound
    assert np.isfinite(img).all() and img.max() <= bound * (1 + 1e-5)


def test_gather_marches_once_for_all_its_images():
    """A gather of several images returns each image as gathered alone, from one run of its march: as many kernel
    launches as for one image (``natscene.scatter.rays.pixel_means`` evaluates the march's outputs together; one
    at a time, each block sum would run the whole march again)."""
    import drjit as dr
    from natscene.scatter.inscatter import gather
    from natscene.scatter.reference_scene import CAM
    _, med, caches, den = _gather_inputs(1)

    def launches(c):
        dr.set_flag(dr.JitFlag.KernelHistory, True)
        try:
            dr.kernel_history()
            img = gather(med, CAM, 0.5, c, den, 2, 0.5, 4)
            hist = dr.kernel_history()
        finally:
            dr.set_flag(dr.JitFlag.KernelHistory, False)
        return img, sum(1 for k in hist if k["type"] == dr.KernelType.JIT)

    together, n_three = launches(caches)
    assert together.max() > 0.05
    for i in range(3):
        alone, n_one = launches(caches[i:i + 1])
        np.testing.assert_allclose(together[i], alone[0], rtol=1e-6, atol=1e-7)
        assert n_three == n_one, (n_three, n_one)


def _layer_means(edges: np.ndarray, mu: float, c: float) -> tuple[np.ndarray, np.ndarray]:
    """Per layer [a, b] of optical depth z above a face seen from mu: Q = ∫ e^(-z/mu) dz and the mean of
    S(z) = z + c weighted by e^(-z/mu) (closed forms)."""
    a, b = edges[:-1], edges[1:]
    ea, eb = np.exp(-a / mu), np.exp(-b / mu)
    q = mu * (ea - eb)
    first = mu * (a * ea - b * eb) + mu * mu * (ea - eb)     # ∫ z e^(-z/mu) dz over [a, b]
    return q, first / q + c


@pytest.mark.parametrize("layers", [16, 5])
def test_gather_of_a_field_rising_from_a_face(layers):
    """A slab of 10 optical depths seen from 30 degrees off the normal of its bottom face, its in-scatter rising
    linearly inward, S(z) = z + 0.71 (the diffusion profile of light transmitted through a thick slab, 0.71 mean
    free paths its extrapolation length). Each layer's cache holds what the photons' tallies estimate, the mean of
    S weighted by the camera transmittance e^(-z/mu), and Q = ∫ e^(-z/mu) (closed forms); the view integral
    ∫ e^(-s) S(mu s) ds is mu + 0.71. The march reconstructs it within 1.5 % in layers of 0.625 and 4 % in layers of
    2 mean free paths (interpolating C and Q and dividing, which leans every point toward the shallower layer:
    2.4 % and 6.4 % low; 0.8 % and 3.2 % high here)."""
    from natscene.scatter.inscatter import gather
    from natscene.scatter.reference_scene import slab_camera, slab_volume
    mu, c = float(np.cos(np.radians(30))), 0.71
    vol = slab_volume(tau=10.0, n=(8, layers, 8), width=4.0)
    q, s = _layer_means(np.linspace(0.0, 10.0, layers + 1), mu, c)
    shape = vol.density.shape
    den = np.broadcast_to(q[None, :, None], shape).astype(np.float32)
    caches = np.broadcast_to((s * q)[None, None, :, None], (1,) + shape).astype(np.float32)
    img = gather(make_medium(vol), slab_camera(mu, above=False, res=8), 1.0, caches, den, 1, 0.25, 1)
    exact = mu + c
    print(f"layers {layers}: {img.mean() / exact:.4f} of the exact view integral")
    assert abs(img.mean() / exact - 1) <= (0.015 if layers == 16 else 0.04), img.mean() / exact
