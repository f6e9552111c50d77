"""Thick clouds (issue 39): the all-orders transport against converged Mitsuba ``volpath`` renders.

References (tests/data/transport_volpath_thick.npz, tools/thick_references.py, rendered on a GPU; every order,
sun only, each stored as two independent halves):

- the all-orders tests' procedural heap (tests/test_transport.py) at a mean optical depth of 100 and 300 over
  its cloud pixels (camera rays), g 0.85, beta 0.9999: 24.5k and 28.6k spp; the halves agree within 0.3 % in
  the mean and 4.4 % in every 8x8 block;
- the main job's cumulonimbus from the day shot's first camera at 160x120 under the day sun at the kite fit's
  droplets (0.0244 /m: optical depth up to about 120 through the core, g 0.70, beta 0.9999): 188k spp.

Checked: the composed tables and the forward renderer, mean over the cloud's pixels within 3 % and every 8x8
block within 10 % (the heap, at the all-orders tests' settings); the ratio to volpath by opacity band at the
shot's own render settings (the cumulonimbus); and the white furnace at a mean optical depth of 300.
"""
from pathlib import Path

import numpy as np
import pytest

import natscene  # noqa: F401
from natscene.config import default_settings
from natscene.geometry import Camera
from natscene.scatter.allorders import AllOrdersSettings, Lighting, Scene, frame_settings, view_images
from natscene.scatter.bands import channel_weights
from natscene.scatter.compose import compose
from natscene.scatter.reference_scene import CAM, K, NOSKY, SETTINGS, SUN, band_ratios, blob_volume
from natscene.scatter.render import render
from natscene.scatter.single import march_view
from natscene.scatter.skylight import uniform_dome
from natscene.scatter.tables import load_tables, precompute, save_tables

from test_transport import RENDER_SETTINGS, _ratios

REFS = Path(__file__).parent / "data" / "transport_volpath_thick.npz"
HEAP = ("blob_t100", "blob_t300")


@pytest.fixture(scope="module")
def refs():
    with np.load(REFS) as z:
        return {k: z[k] for k in z.files}


def _ref(refs, name):
    return (refs[f"{name}.half_a"].astype(np.float64) + refs[f"{name}.half_b"]) / 2


def _params(refs, name, scale):
    sigma, g, beta = (float(x) for x in refs[f"{name}.params"])
    return dict(c_in=[1.0] * 3, L_in=1.0, g=g, extinction=sigma * scale, beta=beta, kappa_a=[0.0] * 3, **NOSKY)


@pytest.fixture(scope="module")
def heap_tables(refs, tmp_path_factory):
    vol = blob_volume()
    tb = precompute(vol, CAM, SUN, extinctions=[0.0, *(float(refs[f"{n}.params"][0]) * K for n in HEAP)],
                    gs=[0.85], seed=1, all_orders=SETTINGS)
    d = tmp_path_factory.mktemp("thick")
    save_tables(d, tb)
    return vol, load_tables(d)


def _agree(img, ref, foot, label):
    mean, blk = _ratios(img, ref, foot, label)
    assert abs(mean - 1) <= 0.03
    assert np.all(np.abs(blk - 1) <= 0.10), blk


@pytest.mark.parametrize("name", HEAP)
def test_thick_heap_tables_match_volpath(refs, heap_tables, name):
    _, tb = heap_tables
    img = compose(tb, _params(refs, name, K), np.zeros((CAM.height, CAM.width, 3), np.float32))[0][..., 0]
    _agree(img, _ref(refs, name), tb.footprint > 0, f"tables {name}")


@pytest.mark.parametrize("name", ["blob_t100", pytest.param("blob_t300", marks=[pytest.mark.gaps, pytest.mark.xfail(
    strict=True, reason="the far 8x8 block 12 % high at depth 300 (1.06 and 1.18 in the two runs: the light of more "
                        "than 4096 collisions that lights it comes from few photons; the tables' are within 3.3 %)")])])
def test_thick_heap_render_matches_volpath(refs, heap_tables, name):
    """The forward renderer: the mean of two runs (one run's 8x8 blocks scatter by up to 8 % at depth 300)."""
    vol, tb = heap_tables
    img = np.mean([render(vol, CAM, SUN, _params(refs, name, K), np.zeros(3, np.float32), {"seed": s}, skylight=False,
                          all_orders=RENDER_SETTINGS)[..., 0] for s in (5, 6)], axis=0)
    _agree(img, _ref(refs, name), tb.footprint > 0, f"render {name}")


@pytest.mark.parametrize("name", HEAP)
def test_thick_heap_render_by_similarity_matches_volpath(refs, heap_tables, name):
    """The forward renderer with the high orders by similarity (from order 32, walks up to 65536 orders): the mean
    of two runs within 3 %, every 8x8 block within 10 % (the exact walk's depth-300 block that reads 13 % low is
    light that needs more than 4096 collisions)."""
    from dataclasses import replace
    vol, tb = heap_tables
    st = replace(RENDER_SETTINGS, similarity_order=32, max_order=65536)
    img = np.mean([render(vol, CAM, SUN, _params(refs, name, K), np.zeros(3, np.float32), {"seed": s}, skylight=False,
                          all_orders=st)[..., 0] for s in (5, 6)], axis=0)
    _agree(img, _ref(refs, name), tb.footprint > 0, f"render by similarity {name}")


def test_white_furnace_at_depth_300():
    """Sun off, a uniform dome of radiance L, beta = 1, the heap at a mean optical depth of 300 over its cloud
    pixels: radiance L everywhere (2 % in the mean over the cloud). A run's mean over the cloud scatters by
    about 1.5 % (its photons' walks are hundreds of collisions long, so few of them light each part of the
    skin): four runs of 24 M collisions are averaged (standard error about 0.7 %)."""
    vol = blob_volume()
    L = 0.7
    st = default_settings(AllOrdersSettings, sun_collisions=20_000, sky_collisions=24_000_000, fine_voxels=1,
                          coarse_voxels=1, camera_lobe=0.6)
    scene = Scene(vol, Lighting(SUN, uniform_dome(L)), st)
    with np.load(REFS) as z:
        sigma = float(z["blob_t300.params"][0])
    T = march_view(scene.med, CAM, [sigma])["T"][0]
    cloud = T < 0.9
    means = []
    for seed in (4, 5, 6, 7):
        vi = view_images(scene, CAM, sigma, 0.85, seed=seed)
        c = channel_weights(st.sky_bands, vi.sky_orders, 1.0)[0]
        sky = np.einsum("cb,cbhw->chw", c, vi.sky)
        img = sky[0] + sky[3] * L + T * L
        means.append(img[cloud].mean() / L)
    print(f"white furnace, mean depth 300: runs {np.round(means, 4)}, mean {np.mean(means):.4f}")
    assert abs(np.mean(means) - 1) <= 0.02


def test_band_ratios_split_by_opacity():
    """The bands are [lo, hi): opacity 0.05 is in none, 0.5 in the second, an opaque pixel (1.0) in the last."""
    opacity = np.array([0.05, 0.2, 0.4, 0.5, 0.95, 0.99, 1.0])
    ours = np.array([9.0, 1.0, 1.2, 0.9, 1.0, 1.0, 1.04])
    got = band_ratios(ours, np.ones(7), opacity)
    assert got == pytest.approx({"0.1-0.5": 1.1, "0.5-0.9": 0.9, "0.9-0.99": 1.0, "0.99-1": 1.02})


def test_cumulonimbus_by_opacity_band_at_shot_settings(refs):
    """The day shot's render settings (config shots.day_to_sunset.render, its cache cells) on the
    cumulonimbus at 160x120: the ratio to volpath within 3 % in each opacity band, mean of two runs."""
    from natscene.config import load_yaml_config
    from natscene.scatter.medium import make_medium
    from natscene.volume.build import build_volume
    root = Path(__file__).resolve().parents[1]
    cfg = load_yaml_config(root / "config" / "config.yaml")
    vol, _ = build_volume(cfg["volumes"]["cumulonimbus"], "cumulonimbus")
    c = refs["cb_day.camera"]
    cam = Camera(tuple(c[0:3]), tuple(c[3:6]), tuple(c[6:9]), float(c[9]), int(c[10]), int(c[11]))
    sun = refs["cb_day.sun"]
    p = _params(refs, "cb_day", vol.extinction_scale)
    st = frame_settings(cfg["shots"]["day_to_sunset"]["render"])
    img = np.mean([render(vol, cam, sun, p, np.zeros(3, np.float32),
                          {"seed": s, "step_voxels": st.step_voxels, "supersample": st.supersample},
                          skylight=False, all_orders=st)[..., 0] for s in (0, 1)], axis=0)
    ref = _ref(refs, "cb_day")
    opacity = 1 - march_view(make_medium(vol), cam, [float(refs["cb_day.params"][0])])["T"][0]
    ratios = {k: round(r, 4) for k, r in band_ratios(img, ref, opacity).items()}
    print("cumulonimbus, ratio to volpath by opacity band:", ratios)
    assert all(abs(r - 1) <= 0.03 for r in ratios.values()), ratios
