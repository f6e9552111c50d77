"""The all-orders transport (natscene.scatter.allorders; precompute, composition and forward renderer).

References known independently of the code under test:
- Mitsuba 3's ``volpath`` with unlimited depth (Russian roulette off) on the same procedural cloud, camera, sun,
  HG phase, albedo and extinction: every scattering order, no tables. The 8192-spp renders are stored in
  tests/data/transport_volpath.npz (tools/transport_references.py, 25 min on 2 cores): at g = 0.85 a 512-spp
  render's 8x8 blocks scatter by 5 % (up to 15 %), as much as the tolerance under test. A short fresh run checks
  that the stored renders still belong to this cloud, camera and Mitsuba;
- a long Mitsuba run of a homogeneous slab under a normal sun (the plane-parallel reflectance and
  transmittance) and energy conservation (reflected + transmitted flux = incident flux at albedo 1);
- the white furnace: a non-absorbing cloud under a uniform sky of radiance L has radiance L everywhere.
"""
from contextlib import contextmanager
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import natscene  # noqa: F401
from natscene.config import default_settings
from natscene.errors import ConfigError, InputError
import natscene.scatter.allorders as allorders
from natscene.scatter.allorders import AllOrdersSettings, Lighting, Scene, frame_settings, view_images
from natscene.scatter.bands import (ORDER_BINS, SUN_BANDS, band_table, band_weights, channel_weights, check_bands,
                                    order_distribution)
from natscene.scatter.compose import compose
from natscene.scatter.mitsuba_scene import render_reference
from natscene.scatter.reference_scene import (BETAS, CAM, GS, K, NOSKY, SETTINGS, SIGMAS, SUN, blob_volume,
                                              block_ratios, slab_camera, slab_volume, volpath_references)
from natscene.scatter.render import render
from natscene.scatter.skylight import Dome, uniform_dome
from natscene.scatter.tables import load_tables, precompute, save_tables

REFERENCES = Path(__file__).parent / "data" / "transport_volpath.npz"


#: SETTINGS as the forward renderer ran them before it took its settings as they are: the angle biasing toward the
#: camera off, at most one photon per two collisions
RENDER_SETTINGS = replace(SETTINGS, camera_lobe=0.0, sun_photons_max=SETTINGS.sun_collisions // 2)


def _frames(**render):
    """The all-orders settings of frames rendered with the ``shots.<name>.render`` keys ``render``, at the
    precompute's tally rate and ground share (the settings these tests were calibrated with)."""
    return frame_settings({"tally_rate": 1.0, "ground_share": 0.25, **render})


@pytest.fixture(scope="module")
def vol():
    return blob_volume()


@pytest.fixture(scope="module")
def tables(vol, tmp_path_factory):
    tb = precompute(vol, CAM, SUN, extinctions=[0.0, *(s * K for s in SIGMAS)], gs=list(GS), seed=1, all_orders=SETTINGS)
    d = tmp_path_factory.mktemp("pre")
    save_tables(d, tb)
    return load_tables(d)


@pytest.fixture(scope="module")
def references():
    """volpath, every order, 8192 spp, for the 18 (sigma_t, g, beta) of the issue (sun only, no sky)."""
    return volpath_references(REFERENCES)


@pytest.mark.parametrize("s, g, b", [(0.5, 0.0, 0.99), (0.2, 0.85, 0.999)])
def test_stored_references_match_a_fresh_volpath_run(vol, references, s, g, b):
    """The stored renders belong to this cloud, camera and Mitsuba: a fresh 512-spp volpath run has the same mean
    over the cloud within 3 % (its own noise: 0.5 % at g = 0, 1.5 % at g = 0.85)."""
    fresh = render_reference(vol, CAM, SUN, s, g, b, orders=100_000, spp=512, seed=7)[..., 0]
    ref = references[s, g, b]
    m = ref > 0
    assert abs(fresh[m].mean() / ref[m].mean() - 1) <= 0.03


def _params(s, g, b):
    return dict(c_in=[1.0, 1.0, 1.0], L_in=1.0, g=g, extinction=s * K, beta=b, kappa_a=[0.0] * 3, **NOSKY)


def _ratios(ours, ref, foot, label):
    m = foot & (ref > 0)
    mean = ours[m].mean() / ref[m].mean()
    blk = block_ratios(ours, ref, m)
    print(f"{label}: mean ratio {mean:.4f}, 8x8 blocks {blk.min():.3f}..{blk.max():.3f} ({blk.size})")
    assert blk.size >= 3
    return mean, blk


@pytest.fixture(scope="module")
def composed(tables, references):
    return {k: _ratios(compose(tables, _params(*k), np.zeros((CAM.height, CAM.width, 3), np.float32))[0][..., 0],
                       ref, tables.footprint > 0, "tables sigma_t={} g={} beta={}".format(*k))
            for k, ref in references.items()}


@contextmanager
def photons_shared_across_beta():
    """Within the block the forward renderer traces its photons once per (sigma_t, g, settings, seed) and reuses
    them for every beta: its photon run (:func:`natscene.scatter.allorders.view_images`) does not depend on beta,
    which only weights the run's order bands, so a second run with the same seed would trace the same photons
    (the renders are the same to the bit; a third of the time for three betas). Yields the runs traced."""
    trace, runs = allorders.view_images, {}

    def traced_once(scene, camera, sigma, g, seed=0, **kw):
        # everything the run reads but beta; a scene with a sky dome (a new object each render) is never shared
        key = (float(sigma), float(g), seed, repr(scene.settings), repr(sorted(kw.items())), repr(camera),
               id(scene.volume), scene.med.sun_dir.tobytes(), id(scene.sky) if scene.sky is not None else None,
               scene.shadow_seed)
        if key not in runs:
            runs[key] = trace(scene, camera, sigma, g, seed=seed, **kw)
        return runs[key]

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(allorders, "view_images", traced_once)
        yield runs


def test_photons_shared_across_beta_render_what_fresh_photons_do(vol):
    """The sharing the volpath comparisons below use holds: renders at two betas from one photon run equal, to the
    bit, the renders that trace their photons each (same seed), from one trace, and differ from each other."""
    st = replace(RENDER_SETTINGS, sun_collisions=300_000)

    def image(b):
        return render(vol, CAM, SUN, _params(0.5, 0.85, b), np.zeros(3, np.float32), {"seed": 2}, skylight=False,
                      all_orders=st)

    fresh = [image(b) for b in (0.9, 0.999)]
    with photons_shared_across_beta() as runs:
        shared = [image(b) for b in (0.9, 0.999)]
    assert len(runs) == 1
    assert np.array_equal(fresh[0], shared[0]) and np.array_equal(fresh[1], shared[1])
    assert not np.array_equal(shared[0], shared[1])


@pytest.fixture(scope="module")
def rendered(vol, tables, references):
    """Forward renders (one photon run per (sigma_t, g); beta only reweights the bands), their ratios to
    volpath and to the composed tables."""
    foot = tables.footprint > 0
    out = {}
    with photons_shared_across_beta():
        for (s, g, b), ref in references.items():
            img = render(vol, CAM, SUN, _params(s, g, b), np.zeros(3, np.float32), {"seed": 5}, skylight=False,
                         all_orders=RENDER_SETTINGS)[..., 0]
            tab = compose(tables, _params(s, g, b), np.zeros((CAM.height, CAM.width, 3), np.float32))[0][..., 0]
            out[s, g, b] = _ratios(img, ref, foot, f"render sigma_t={s} g={g} beta={b}") + (
                img[foot].mean() / tab[foot].mean(),)
    return out


def _off(results, tol, betas=BETAS):
    return {k: round(float(r[0]), 4) for k, r in results.items() if k[2] in betas and abs(r[0] - 1) > tol}


def test_mean_within_3_percent_of_volpath(composed, rendered):
    """Every order, against volpath, for all 18 (sigma_t, g, beta): the mean over cloud pixels within 3 %, for the
    composed tables and for the forward renderer, and the forward renderer within 3 % of the composed tables
    (the same model)."""
    assert not _off(composed, 0.03) and not _off(rendered, 0.03), (_off(composed, 0.03), _off(rendered, 0.03))
    off = {k: round(float(r[2]), 4) for k, r in rendered.items() if abs(r[2] - 1) > 0.03}
    assert not off, f"forward render and composed tables differ by more than 3 %: {off}"


def _block_failures(results):
    return {k: (round(float(r[1].min()), 3), round(float(r[1].max()), 3))
            for k, r in results.items() if np.any(np.abs(r[1] - 1) > 0.10)}


def test_every_block_within_10_percent(composed, rendered):
    """Every 8x8 block (at least half cloud) within 10 % of volpath, for all 18 cases."""
    assert not _block_failures(composed) and not _block_failures(rendered), \
        (_block_failures(composed), _block_failures(rendered))


@pytest.mark.parametrize("g", [0.0, 0.85])
def test_slab_reflectance_transmittance_match_long_volpath(g):
    """Radiance reflected (view 30 deg from the zenith) and transmitted (30 deg from the nadir) by a
    homogeneous slab under a normal sun, against a long Mitsuba run of the same slab (2 %). One run of 8 M
    collisions scatters by 1.7 % at g 0.85 (reflected; 20 runs: mean 1.012 of the reference, standard error
    0.005: the voxel caches' discretisation, which falls to 1.002 at 32 or 64 voxels across the slab), so the
    test takes the mean of 4 runs of 16 M collisions (about 0.6 %)."""
    vol = slab_volume(n=(48, 16, 48), width=12.0)
    sun = np.array([0.0, 1.0, 0.0])
    beta = 0.99
    for above in (True, False):
        cam = slab_camera(np.cos(np.radians(30)), above)
        ref = sum(render_reference(vol, cam, sun, 1.0, g, beta, orders=100_000, spp=4096, seed=k)
                  for k in range(2))[..., 0].mean() / 2
        p = dict(c_in=[1.0] * 3, L_in=1.0, g=g, extinction=vol.extinction_scale, beta=beta, kappa_a=[0.0] * 3)
        ours = np.mean([render(vol, cam, sun, p, np.zeros(3, np.float32), {"seed": seed}, skylight=False,
                               all_orders=_frames(sun_collisions=16_000_000))[..., 0].mean() for seed in range(4)])
        print(f"slab g={g} {'reflected' if above else 'transmitted'}: ours {ours:.5f} volpath {ref:.5f}")
        assert abs(ours / ref - 1) <= 0.02


def test_energy_conservationslab_volume():
    """beta = 1, no absorption: reflected + transmitted flux = incident flux (1 %). The fluxes integrate the
    rendered radiance over the hemispheres (Gauss-Legendre in cos(zenith); the field is symmetric about the
    normal under a normal sun); the unscattered beam e^{-tau} is added to the transmitted flux."""
    vol = slab_volume(tau=1.0)
    sun = np.array([0.0, 1.0, 0.0])
    x, wq = np.polynomial.legendre.leggauss(6)
    mus, wts = (x + 1) / 2, wq / 2
    p = dict(c_in=[1.0] * 3, L_in=1.0, g=0.5, extinction=vol.extinction_scale, beta=1.0, kappa_a=[0.0] * 3)
    flux = {}
    for above in (True, False):
        L = [render(vol, slab_camera(mu, above, res=8), sun, p, np.zeros(3, np.float32), {"seed": 3},
                    skylight=False, all_orders=_frames(sun_collisions=3_000_000))[..., 0].mean() for mu in mus]
        flux[above] = 2 * np.pi * float(np.sum(wts * mus * np.asarray(L)))
    total = flux[True] + flux[False] + np.exp(-1.0)
    print(f"R {flux[True]:.4f} + T_diffuse {flux[False]:.4f} + T_direct {np.exp(-1.0):.4f} = {total:.4f}")
    assert abs(total - 1) <= 0.01


def test_white_furnace():
    """Sun off, a uniform dome of radiance L (sky and ground), a non-absorbing cloud: radiance L everywhere."""
    vol = blob_volume(scale=30.0)
    L = 0.7
    st = default_settings(AllOrdersSettings, sun_collisions=20_000, sky_collisions=6_000_000, camera_lobe=0.6)
    scene = Scene(vol, Lighting(SUN, uniform_dome(L)), st)
    for sigma in (0.3, 1.0):
        vi = view_images(scene, CAM, sigma, 0.85, seed=4)
        c = channel_weights(st.sky_bands, vi.sky_orders, 1.0)[0]
        sky = np.einsum("cb,cbhw->chw", c, vi.sky)                   # (4, H, W) at beta = 1
        from natscene.scatter.single import march_view
        T = march_view(scene.med, CAM, [sigma])["T"][0]
        img = sky[0] + sky[3] * L + T * L          # the dome's R channel + the unit-radiance ground basis at L
        cloud = T < 0.9
        print(f"white furnace sigma_t={sigma}: mean {img[cloud].mean() / L:.4f}, "
              f"min {img[cloud].min() / L:.3f}, max {img[cloud].max() / L:.3f}")
        assert abs(img[cloud].mean() / L - 1) <= 0.02
        # blocks: the photon noise of 6M sky collisions is ~2 % per 8x8 block, so 5 % per block
        assert np.all(np.abs(block_ratios(img, np.full_like(img, L), cloud) - 1) <= 0.05)


def _heavy_tail(n: int = 65537, seed: int = 0) -> np.ndarray:
    """An order histogram with a thick cloud's shape: k^-1.5 with an exponential cut-off near 1500, noisy."""
    k = np.arange(n, dtype=np.float64)
    h = np.where(k >= 1, np.maximum(k, 1) ** -1.5 * np.exp(-k / 1500), 0.0)
    return h * np.random.default_rng(seed).uniform(0.5, 1.5, n)


def _ground_tail(seed: int) -> np.ndarray:
    """An order histogram of light that needs few orders (the ground's, entering a cloud's base): orders < 40."""
    return _heavy_tail(seed=seed) * (np.arange(65537) < 40)


def test_band_weights_against_the_explicit_sum_over_orders():
    """c_b(beta) = Σ_k h_k beta^k / Σ_k h_k over each band's orders: exact for bands of at most ORDER_BINS orders
    (one order per sub-bin); for the wider bands (orders 65 to 65536, the similar walks' longest) below the exact
    sum (beta^k is convex in k: each sub-bin's mean order gives at most its mean of beta^k, Jensen) and within
    0.5 % of the band's weight, or 0.3 % of beta^2 where the band's weight is smaller; c_b(1) = 1; shares sum to 1 per band."""
    h = _heavy_tail()
    d = order_distribution(SUN_BANDS, h)
    assert d.shape == (len(SUN_BANDS), ORDER_BINS, 2)
    assert np.allclose(d[..., 0].sum(-1), 1.0)
    for beta in (0.3, 0.9, 0.99, 0.999, 0.9999, 1.0):
        c = band_weights(SUN_BANDS, d, beta)[0]
        for (a, e), cb in zip(SUN_BANDS, c):
            k = np.arange(a, (e or len(h) - 1) + 1)
            exact = float((h[k] * beta ** k).sum() / h[k].sum())
            if e is not None and e - a + 1 <= ORDER_BINS:
                assert cb == pytest.approx(exact, rel=1e-12)
            else:
                assert cb <= exact * (1 + 1e-12)
                # within 0.5 % of the band, or 0.3 % of beta^2 (order 2, the leading term of the multiple
                # scattering the bands compose) where the band's light fades
                assert abs(cb - exact) <= max(0.005 * exact, 0.003 * beta ** 2)
    assert np.allclose(band_weights(SUN_BANDS, d, 1.0), 1.0)
    # a band without light: all of it at its first order
    empty = order_distribution(SUN_BANDS, np.zeros(0))
    assert np.allclose(band_weights(SUN_BANDS, empty, 0.9)[0], [0.9 ** a for a, _ in SUN_BANDS])
    # one distribution per albedo (a GA population at its own table nodes): each row as its own
    per = np.stack([order_distribution(SUN_BANDS, _heavy_tail(seed=s)) for s in range(5)])
    betas = np.array([0.3, 0.9, 0.99, 0.999, 1.0])
    c = band_weights(SUN_BANDS, per, betas)
    for j in range(5):
        assert np.allclose(c[j], band_weights(SUN_BANDS, per[j], betas[j])[0], rtol=1e-12)
    with pytest.raises(ValueError, match="order distributions"):
        band_weights(SUN_BANDS, per, betas[:3])
    with pytest.raises(ValueError):
        check_bands([[2, 3], [5, None]], 2)
    assert band_table(SUN_BANDS, 300)[257] == [a for a, _ in SUN_BANDS].index(257)       # up to max_order 300
    assert band_table(SUN_BANDS, 5000)[5000] == len(SUN_BANDS) - 1


@pytest.mark.parametrize("sigma, g, rate, n", [(1.0, 0.85, 1.0, 8_192), (1.0, 0.85, 1.0, 65_536),
                                               (0.3, 0.0, 0.0, 65_536)])
def test_phase_free_tallies_of_a_walk_sum_to_its_collisions(sigma, g, rate, n):
    """The expected-value estimator of delta tracking: the phase-free tally of one flight (Σ mu_t / mu_bar over its
    tentative collisions) estimates ∫ T mu_t ds, the probability that the flight collides. Summed over every
    flight of every walk, and without the camera weight, the tallies therefore equal the number of real
    collisions times the photon power, in expectation, whatever the cloud, the phase function and the tally rate
    (the same photons, so most of their noise cancels: the two sums differ by about 1 % here). A tracer that
    loses the tallies of some flights, or counts collisions it does not tally, fails: the symbolic loop that
    finished the last walks of an earlier tracer gave 0.65 and 0.94 of the collisions' power at sigma_t 1."""
    from natscene.scatter.photons import trace
    vol = blob_volume(scale=30.0, n=(24, 16, 24))
    scene = Scene(vol, Lighting(SUN, None), default_settings(AllOrdersSettings))
    t = trace(scene.med, scene.grid, scene.sun, sigma, g, CAM.position, n, ((1, 1), (2, None)),
              caches=((4, None),), seed=3, k_min=1, tally_rate=rate, phase=False)
    ratio = t.numerators[0].sum() / (t.collisions * scene.sun.area / n)
    print(f"sigma_t {sigma}, g {g}, {n} photons: tallies / collisions' power {ratio:.4f} ({t.collisions} collisions)")
    assert t.collisions > n / 2
    assert abs(ratio - 1.0) < 0.02


def test_standard_error_of_two_halves_reads_a_known_noise():
    """The two-halves error estimate (meta.yaml's noise figures) on halves with a known relative noise: a lit
    disk, bright in its core and dim at its edge, times 1 + 0.1 ε, ε unit normal noise constant over cells of
    6x6 pixels (the cache's noise is correlated over a cell). The mean of two halves has relative standard error
    0.1 / √2 at every pixel; the estimate's median must read it within -15 / +5 % (a one-degree-of-freedom
    estimate averaged over 3x3 pixels reads it ~20 % low), also at the dim edge (within -25 / +10 %: the pixels
    outside the disk must not dilute the pixels within 3 of them)."""
    from scipy.ndimage import distance_transform_edt
    from natscene.scatter.allorders import standard_error
    rng = np.random.default_rng(1)
    H, W, cell, sigma = 240, 320, 6, 0.1
    yy, xx = np.mgrid[:H, :W]
    r = np.hypot((yy - H / 2) / (H * 0.4), (xx - W / 2) / (W * 0.4))
    lit = r < 1
    edge = lit & (distance_transform_edt(lit) <= 3)          # within 3 pixels of the dark
    m = np.where(lit, 0.05 + 10 * (1 - r) ** 2 * (1 + 0.5 * np.sin(xx / 7.0)), 0.0)

    def noise():
        return np.kron(rng.standard_normal((H // cell + 1, W // cell + 1)), np.ones((cell, cell)))[:H, :W]

    true = sigma / np.sqrt(2)
    med, med_edge, dark = [], [], []
    for _ in range(4):
        a, b = m * (1 + sigma * noise()), m * (1 + sigma * noise())
        se = standard_error(a, b)
        rel = se / np.where(lit, (a + b) / 2, 1.0)
        med.append(np.median(rel[lit]) / true)
        med_edge.append(np.median(rel[edge]) / true)
        dark.append(float(np.abs(se[~lit]).max()))
    assert 0.85 <= np.mean(med) <= 1.05, med
    assert 0.75 <= np.mean(med_edge) <= 1.10, med_edge
    assert max(dark) == 0.0                                  # no light, no error


def test_p1_tallies_are_hg_at_g_0(vol):
    """At g = 0 the phase function's P1 part is HG itself (1 / 4π): tallies from order 2 on in P1 give the same
    band images as plain HG, to float rounding."""
    st = replace(RENDER_SETTINGS, sun_collisions=400_000)
    scene = Scene(vol, Lighting(SUN, None), st)
    plain = view_images(scene, CAM, 0.5, 0.0, seed=3).sun
    p1 = view_images(Scene(vol, Lighting(SUN, None), replace(st, p1_order=2)), CAM, 0.5, 0.0, seed=3).sun
    assert plain.max() > 0
    assert np.allclose(p1, plain, rtol=1e-5, atol=1e-6 * plain.max())


@pytest.mark.parametrize("s", [0.5, 1.0])
def test_p1_tallies_from_order_33_match_volpath(vol, tables, references, s):
    """Tallies in the phase function's P1 part from order 33 on (``p1_order``), at g 0.85, where HG's forward peak
    is strongest: the forward render against volpath, every order, the mean over cloud pixels within 3 % and
    every 8x8 block within 10 % (as the plain tallies; measured 0.998-1.008, blocks 0.943-1.079)."""
    foot = tables.footprint > 0
    with photons_shared_across_beta():
        for b in (0.9, 0.999):
            img = render(vol, CAM, SUN, _params(s, 0.85, b), np.zeros(3, np.float32), {"seed": 5}, skylight=False,
                         all_orders=replace(RENDER_SETTINGS, p1_order=33))[..., 0]
            mean, blk = _ratios(img, references[s, 0.85, b], foot, f"P1 from 33: render sigma_t={s} g=0.85 beta={b}")
            assert abs(mean - 1) <= 0.03 and np.all(np.abs(blk - 1) <= 0.10), (mean, blk.min(), blk.max())


def test_sky_dome_lights_the_shadow_side(vol):
    """The skylight brightens the cloud where the sun does not reach: with the dome on, the darkest cloud
    pixels gain light, and a dome with zero radiance gives exactly the sun-only image."""
    p = dict(c_in=[1.0] * 3, L_in=3.0, g=0.85, extinction=0.5 * K, beta=0.99, kappa_a=[0.0] * 3)
    sky = np.full(3, 0.3, np.float32)
    dark = render(vol, CAM, SUN, p, sky, {"seed": 1}, skylight=False, all_orders=_frames(sun_collisions=1_000_000))
    zero = render(vol, CAM, SUN, p, sky, {"seed": 1, "ground_albedo": 0.0}, dome=Dome(np.zeros((4, 8, 3)), np.zeros(3)),
                  all_orders=_frames(sun_collisions=1_000_000, sky_collisions=50_000))
    lit = render(vol, CAM, SUN, p, sky, {"seed": 1}, dome=uniform_dome(0.3),
                 all_orders=_frames(sun_collisions=1_000_000, sky_collisions=2_000_000))
    assert np.allclose(zero, dark, rtol=1e-5, atol=1e-7)
    cloud = render(vol, CAM, SUN, p, np.zeros(3, np.float32), {"seed": 1}, skylight=False, return_components=True,
                   all_orders=_frames(sun_collisions=100_000))[1]["T"] < 0.5
    shade = dark[..., 0][cloud] < np.percentile(dark[..., 0][cloud], 20)
    assert lit[..., 0][cloud][shade].mean() > 1.2 * dark[..., 0][cloud][shade].mean()


def test_bad_transport_settings(vol):
    with pytest.raises(InputError, match="precompute.transport"):
        precompute(vol, CAM, SUN, extinctions=[0.5 * K], gs=[0.5], transport="bouthors")
    with pytest.raises(InputError, match="precompute.skylight.model"):
        precompute(vol, CAM, SUN, extinctions=[0.5 * K], gs=[0.5], skylight={"model": "hosek"},
                   all_orders=default_settings(AllOrdersSettings, sun_collisions=10_000, sky_collisions=10_000))
    with pytest.raises(ConfigError, match=r"shots\.<name>\.render.*transport.*'bouthors'"):
        render(vol, CAM, SUN, _params(0.5, 0.5, 0.9), np.zeros(3), {"transport": "bouthors"})
    with pytest.raises(InputError, match="precompute.n_m"):
        precompute(vol, CAM, SUN, extinctions=[0.5 * K], gs=[0.5], n_m=0, transport="dobashi")
    with pytest.raises(InputError, match="precompute.spp"):
        precompute(vol, CAM, SUN, extinctions=[0.5 * K], gs=[0.5], spp=0, transport="dobashi")


def test_all_orders_compose_is_the_explicit_sum_over_nodes_and_bands():
    """The GA's fused all-orders composition (both back ends) against the formula written out per individual:
    the bilinear (g, sigma_t) bracket of the band images weighted by c_b(beta), HG single scattering, the dome's
    calibrated R, G, B and the ground light, plus T L_sky (natscene.scatter.compose module docstring)."""
    from natscene.scatter.compose import compose_cloud
    from natscene.scatter.tables import Tables
    rng = np.random.default_rng(3)
    H, W, Ns, Ng = 6, 5, 4, 3
    sb, kb = SUN_BANDS, ((1, 1), (2, 8), (9, None))
    sig, gs = np.array([0.1, 0.2, 0.5, 1.0]), np.array([0.0, 0.5, 0.85])
    t = Tables(extinction=sig, g=gs, orders=[], s_sun=rng.random((Ns, H, W), np.float32),
               s_amb=np.zeros((Ns, H, W), np.float32), transmittance=rng.random((Ns, H, W), np.float32),
               multiple=np.zeros((0, Ng, Ns, H, W), np.float32), t_c=rng.random((H, W), np.float32),
               cos_theta=rng.uniform(-1, 1, (H, W)).astype(np.float32), footprint=np.ones((H, W), np.float32),
               meta={"skylight": {"irradiance_rgb": [0.3, 0.4, 0.6], "sun_elevation_sin": 0.5}},
               transport="all_orders", sun_bands=sb, sky_bands=kb,
               sun_ms=rng.random((len(sb), Ng, Ns, H, W), np.float32),
               sky_ms=rng.random((4, len(kb), Ng, Ns, H, W), np.float32),
               sun_orders=np.stack([[order_distribution(sb, _heavy_tail(seed=Ns * j + i)) for i in range(Ns)]
                                    for j in range(Ng)]),
               sky_orders=np.stack([[order_distribution(kb, [_heavy_tail(seed=99 + Ns * j + i),  # the dome's
                                                             _ground_tail(seed=199 + Ns * j + i)])   # the ground's
                                     for i in range(Ns)] for j in range(Ng)]))
    P = 7
    p = {"L_in": rng.uniform(1, 8, P), "g": rng.uniform(-0.2, 0.95, P), "extinction": rng.uniform(0.05, 1.2, P),
         "beta": rng.uniform(0.9, 1.0, P), "L_amb": np.zeros(P), "c_in": rng.uniform(0.5, 1.5, (P, 3)),
         "sky_scale": rng.uniform(0.5, 2, (P, 3)), "ground_albedo": rng.uniform(0, 0.5, (P, 3))}
    sky = rng.random((H, W, 3), np.float32)
    expect = np.zeros((P, H, W, 3))
    for j in range(P):
        def bracket(grid, x):
            x = min(max(x, grid[0]), grid[-1])
            i = min(int(np.searchsorted(grid, x, side="right")) - 1, grid.size - 2)
            f = (x - grid[i]) / (grid[i + 1] - grid[i])
            return [(i, 1 - f), (i + 1, f)]
        g, b = p["g"][j], p["beta"][j]
        phase = (1 - g * g) / (4 * np.pi * (1 + g * g - 2 * g * t.cos_theta) ** 1.5)
        G = p["ground_albedo"][j] / np.pi * (p["L_in"][j] * p["c_in"][j] * 0.5 + p["sky_scale"][j] * [0.3, 0.4, 0.6])
        for si, ws in bracket(sig, p["extinction"][j]):
            single = p["L_in"][j] * b * phase * t.s_sun[si]
            expect[j] += ws * (single[..., None] * p["c_in"][j] + t.transmittance[si][..., None] * sky)
            for gi, wg in bracket(gs, g):
                cs = band_weights(sb, t.sun_orders[gi, si], b)[0]
                ck = [band_weights(kb, t.sky_orders[gi, si, 0 if c < 3 else 1], b)[0] for c in range(4)]
                sun = np.tensordot(cs, t.sun_ms[:, gi, si], 1)
                k = np.stack([np.tensordot(ck[c], t.sky_ms[c, :, gi, si], 1) for c in range(4)])   # (4, H, W)
                expect[j] += wg * ws * (p["L_in"][j] * sun[..., None] * p["c_in"][j]
                                        + np.moveaxis(k[:3], 0, -1) * p["sky_scale"][j] + k[3][..., None] * G)
    for backend in ("numpy", "auto"):
        got = compose_cloud(t, p, sky, backend=backend)
        assert np.allclose(got, expect, rtol=2e-5, atol=1e-6), backend
        sub = compose_cloud(t, p, sky, pixels=np.arange(0, H * W, 3), backend=backend)
        assert np.allclose(sub, expect.reshape(P, -1, 3)[:, ::3], rtol=2e-5, atol=1e-6), backend
