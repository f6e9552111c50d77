"""Weight windows of the all-orders photon tracing (natscene.scatter.importance, photons._walk) and the
sky source's lobe toward the camera.

Truths known independently of the code: splitting and Russian roulette keep every expected tally whatever the
window (any targets, even random ones), and a mixture of two direction densities, each sample weighted by
1 / the mixture's pdf, keeps the expected value of every tally.
"""
import numpy as np

import natscene  # noqa: F401
import mitsuba as mi

from natscene.config import default_settings
from natscene.scatter.allorders import AllOrdersSettings, Lighting, Scene
from natscene.scatter.importance import window_targets
from natscene.scatter.inscatter import voxel_camera_depth
from natscene.scatter.photons import trace
from natscene.scatter.reference_scene import CAM, SUN, blob_volume
from natscene.scatter.skylight import uniform_dome

BANDS = ((2, 4), (5, None))


def _scene(sky=False):
    vol = blob_volume(scale=30.0, n=(24, 16, 24))
    st = default_settings(AllOrdersSettings)
    return vol, Scene(vol, Lighting(SUN, uniform_dome(0.5) if sky else None), st)


def _tally(scene, source, window, seed, n=60_000, sigma=1.0, g=0.6, camera_lobe=0.0):
    """The four totals the paired tests compare (the cache's bands 2-4 and 5+, the order histogram's light of
    orders 2-4 and 5+) and the run's collision count."""
    t = trace(scene.med, scene.grid, source, sigma, g, CAM.position, n, BANDS, caches=((4, None),), seed=seed,
              k_min=1, camera_depth=voxel_camera_depth(scene.med, CAM.position), window=window,
              camera_lobe=camera_lobe)
    bands = t.numerators[0].sum(axis=0)
    return np.array([bands[0].sum(), bands[1].sum(), t.histogram[0, 2:5].sum(), t.histogram[0, 5:].sum()]), t.collisions


def test_any_window_keeps_the_expected_tallies():
    """Random targets (log-uniform over a factor 100) change where the photons go, not what they tally. Paired
    runs (the same seed with and without the window: the photons agree up to their first collision) over 8
    seeds: the bands' totals and the order histogram's light agree within 3-6 % (about 3 standard errors of the
    paired means; roulette without its reweighting, for one, is off by tens of per cent)."""
    vol, scene = _scene()
    rng = np.random.default_rng(1)
    dims = (6, 4, 6)
    targets = np.exp(rng.uniform(np.log(0.1), np.log(10.0), dims[::-1])).astype(np.float32)
    window = (4, dims, mi.Float(targets.ravel()))
    ratios, changed = [], False
    for seed in range(8):
        (fa, ca), (fb, cb) = _tally(scene, scene.sun, None, seed), _tally(scene, scene.sun, window, seed)
        ratios.append(fb / fa)
        changed |= ca != cb
    mean = np.mean(ratios, axis=0)
    print("windowed / plain: bands 2-4, 5+; histogram 2-4, 5+:", np.round(mean, 4))
    assert np.all(np.abs(mean - 1) <= [0.03, 0.05, 0.05, 0.06])
    assert changed      # the window did something: the windowed runs made other numbers of collisions


def test_sky_lobe_keeps_the_expected_tallies():
    """Sky photons drawn half from a lobe toward the camera tally the same light per channel as photons drawn
    from the dome alone (a uniform dome, σ_t 1, g 0.85), means of 10 seeds each: the sky's R channel within 3 %,
    the ground's (a quarter of the photons) within 6 % (about 3 standard errors of the difference)."""
    vol, scene = _scene(sky=True)
    lobe = scene.sky.toward(CAM.position, 0.7, 0.5)
    depth = voxel_camera_depth(scene.med, CAM.position)
    tot = {}
    for name, src in (("dome", scene.sky), ("lobe", lobe)):
        tot[name] = np.mean([[t.numerators[0][c].sum() for c in (0, 3)]
                             for t in (trace(scene.med, scene.grid, src, 1.0, 0.85, CAM.position, 100_000, BANDS,
                                             caches=((4, None),), seed=s, k_min=1, camera_depth=depth)
                                       for s in range(10))], axis=0)
    ratio = tot["lobe"] / tot["dome"]
    print(f"lobe / dome: sky R {ratio[0]:.4f}, ground {ratio[1]:.4f}")
    assert abs(ratio[0] - 1) <= 0.03 and abs(ratio[1] - 1) <= 0.06


def test_sky_source_power_is_the_irradiance_of_the_box():
    """The power the sky photons carry into the box, with and without the lobe toward the camera, equals the
    analytic flux of a uniform dome of radiance L through the box's faces: π L on the top face and π L / 2 on
    each side face for the upper hemisphere (the R channel), the same with the bottom face for the unit-radiance
    ground; each photon weighted by 1 / the mixture's pdf. 400,000 photons per source (the lobe at g 0.9 and half
    the photons): within 1 %."""
    import drjit as dr
    vol, scene = _scene(sky=True)
    ext = scene.sky.hi - scene.sky.lo
    top, sides = ext[0] * ext[2], 2 * (ext[0] * ext[1] + ext[1] * ext[2])
    want = np.array([0.5 * np.pi * (top + sides / 2), np.pi * (top + sides / 2)])     # R (L 0.5), ground (L 1)
    for src in (scene.sky, scene.sky.toward(CAM.position, 0.9, 0.5)):
        n = 400_000
        rng = mi.PCG32(size=n, initstate=dr.arange(mi.UInt64, n), initseq=7)
        o, d, wts = src.sample(n, rng)
        got = np.array([dr.sum(wts[0])[0], dr.sum(wts[3])[0]])
        print("power / analytic (sky R, ground):", np.round(got / want, 4))
        assert np.all(np.abs(got / want - 1) <= 0.01)


def test_camera_lobe_keeps_the_expected_tallies():
    """Scatterings biased toward the camera (a mixture of HG around the incoming direction and HG around the
    direction to the camera, weighted by HG / the mixture's pdf) tally the same light as plain HG sampling:
    σ_t 1, g 0.85, a heavy lobe (0.8 of the visible scatterings), 8 paired seeds (the photons agree up to their
    first scattering): the bands' totals and the order histogram's light within 2-5 % (about 3 standard errors
    of the paired means; without the weight HG / q they come out 4-9 times too bright). The lobe must also
    change the walk (other collision counts)."""
    vol, scene = _scene()
    ratios, changed = [], False
    for seed in range(8):
        (fa, ca), (fb, cb) = (_tally(scene, scene.sun, None, seed, n=200_000, g=0.85, camera_lobe=lobe)
                              for lobe in (0.0, 0.8))
        ratios.append(fb / fa)
        changed |= ca != cb
    mean = np.mean(ratios, axis=0)
    print("lobe / plain: bands 2-4, 5+; histogram 2-4, 5+:", np.round(mean, 4),
          "standard errors", np.round(np.std(ratios, axis=0) / np.sqrt(7), 4))
    assert np.all(np.abs(mean - 1) <= [0.02, 0.04, 0.03, 0.05])
    assert changed


def test_window_targets():
    """T follows the flux where the camera sees (uniform photon density there), is 1/floor higher where it
    does not, lower in optically thin cells, 1 in empty cells, and 1 on average at the first collisions."""
    shape = (4, 4, 8)
    occ = np.ones(shape, bool)
    occ[..., 7] = False
    flux = np.ones(shape)
    flux[..., :2] = 10.0                    # a bright lit side
    vis = np.zeros(shape)
    vis[0] = 1.0                            # the camera sees the first layer only
    first = np.zeros(shape)
    first[..., 0] = 1.0
    t = window_targets(flux, first, vis, occ, floor=0.05, smooth=1e-3)
    assert np.allclose(t[..., 7], 1.0)
    assert abs(np.average(t, weights=first) - 1) < 1e-5
    assert abs(t[0, 0, 0] / t[0, 0, 4] - 10) < 1e-3       # visible: T follows the flux
    assert abs(t[2, 0, 4] / t[0, 0, 4] - 20) < 1e-3     # hidden: 1 / floor
    thin = np.where(np.arange(8) == 4, 0.1, 5.0) * np.ones(shape)
    t2 = window_targets(flux, first, vis, occ, thin, floor=0.05, smooth=1e-3)
    assert abs((t2[0, 0, 4] / t2[0, 0, 3]) / (t[0, 0, 4] / t[0, 0, 3]) - 0.1) < 1e-3
