"""Shot frames (issue 18): the denoiser (Intel Open Image Denoise with the cloud's feature images), the noise
figure, the `phase: mie_blend` shading mode through the workflow, and the resolution / field of view.

What is known independently of the code:
- the noise figure of two renders with independent Gaussian relative noise sigma is 0.6745 sigma (the median of
  |N(0, 2 sigma^2)| / sqrt 2);
- a constant-density sphere seen through its centre has opacity 1 - exp(-sigma_e 2 R) and its first-scattering
  normal there points back at the camera;
- a learned denoiser must remove most of the Monte Carlo noise of a frame (>= 3x, issue 18) without moving the
  cloud's mean radiance (2 %): the raw frame is an unbiased estimate;
- the Mie phase function of cloud droplets exceeds Henyey-Greenstein of the same g by ~20-60x within 1 degree of
  the forward direction (diffraction) and falls 3-5x below it at side-scattering angles (80-110 degrees; the
  droplet tables, both normalised over the sphere), so a cloud rim next to the sun is brighter with Mie, and a
  cloud seen at 90-100 degrees from the sun is not brighter, nor darker than if all its light were scattered
  once (multiple scattering, alike for both phase functions, only dilutes the difference);
- the camera's fov is vertical: the cloud covers the same fraction of the frame's height squared at any
  resolution, and 0.75x the area fraction at 16:9 against 4:3.
"""
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml

from natscene.config import load_yaml_config
from natscene.denoise.features import frame_features, view_features
from natscene.denoise.noise import cloud_pixels, noise_figure
from natscene.errors import InputError
from natscene.geometry import Camera
from natscene.io import read_exr, read_yaml
from natscene.keyframes.frame import apply_ratio, mie_ratio, unscattered
from natscene.keyframes.shot import frame_camera, quantised_sun, sun_key, validate_shot
from helpers import sphere_volume

ROOT = Path(__file__).resolve().parents[1]
SMOKE = load_yaml_config(ROOT / "config" / "smoke.yaml")
DAY = {"L_in": 6.0, "g": 0.6, "extinction": 0.18, "beta": 0.97, "L_amb": 0.3, "kappa_a": [0.1, 0.1, 0.2],
       "c_in": [1.0, 0.98, 0.95]}
# the smoke cloud's parameters as the GA fits them to the kite photo (results/smoke fit/tiny, rounded)
FIT = {"L_in": 9.9, "g": 0.03, "extinction": 0.088, "beta": 0.966, "L_amb": 0.57, "kappa_a": [0.5, 0.6, 0.8],
       "c_in": [0.97, 1.0, 1.06]}
SUN = np.array([0.63, 0.57, -0.53]) / np.linalg.norm([0.63, 0.57, -0.53])
# the smoke config's tiny cumulus (a 2 km box whose base is at 1500 m; the cloud fills x 400-1400 m, y 1850-2250 m
# of it) seen from the side at its own height, 3.2 km away (metres, y up)
SIDE_CAM = {"position": [0.0, 2000.0, -3200.0], "look_at": [0.0, 2100.0, 0.0], "up": [0, 1, 0], "fov": 36}


@pytest.fixture(scope="module")
def tiny():
    from natscene.volume.build import build_volume

    return build_volume(SMOKE["volumes"]["tiny"], "tiny")[0]


# ------------------------------------------------------------------------------------------ noise figure
def test_noise_figure_of_gaussian_grain():
    rng = np.random.default_rng(0)
    level = np.full((200, 300, 3), 0.4)
    mask = np.ones((200, 300), bool)
    assert noise_figure(level, level, mask) == 0.0
    for sigma in (0.01, 0.05):
        a = level * (1 + sigma * rng.standard_normal((200, 300, 1)))
        b = level * (1 + sigma * rng.standard_normal((200, 300, 1)))
        assert noise_figure(a, b, mask) == pytest.approx(0.6745 * sigma, rel=0.03)


# ------------------------------------------------------------------------------------------ features
def test_features_of_a_sphere():
    vol = sphere_volume(n=40, radius=0.3, ext=10.0)
    cam = Camera((0.0, 0.5, -2.0), (0.0, 0.5, 0.0), (0, 1, 0), 30.0, 41, 41)
    sigma = 0.1                                                     # sigma_e = 1: tau through the centre 0.6
    alpha, normal, cover = view_features(vol, cam, sigma, supersample=1, step_voxels=0.25)
    assert alpha[20, 20] == pytest.approx(1 - np.exp(-0.6), rel=0.02)
    n = normal[20, 20] / np.linalg.norm(normal[20, 20])
    assert n @ np.array([0.0, 0.0, -1.0]) > 0.99                     # back toward the camera
    assert np.linalg.norm(normal[20, 20]) <= alpha[20, 20] + 1e-6    # |n| <= alpha (unit normals, weights sum alpha)
    assert alpha[0, 0] == 0 and cover[0, 0] == 0 and not normal[0, 0].any()
    assert 0 < cover[20, 20] <= 1
    # the upper rim's normal points up, the right rim's to the camera's right (+x is the image's left here:
    # right = forward x up = (0,0,1) x (0,1,0) = (-1, 0, 0))
    col = alpha[:, 20]
    top = int(np.argmax(col > 0.05))
    assert normal[top, 20, 1] > 0.5 * np.linalg.norm(normal[top, 20])
    row = alpha[20]
    right = int(len(row) - 1 - np.argmax(row[::-1] > 0.05))
    assert normal[20, right, 0] < -0.5 * np.linalg.norm(normal[20, right])
    f = frame_features(vol, cam, {"extinction": sigma * vol.extinction_scale, "beta": 0.9, "c_in": [2.0, 1.0, 0.5]},
                       sky=np.full((41, 41, 3), 0.3, np.float32), settings={"feature_supersample": 2})
    assert f["albedo"].min() >= 0 and f["albedo"].max() <= 1 and np.abs(f["normal"]).max() <= 1
    a = f["opacity"][20, 20]
    assert f["albedo"][20, 20] == pytest.approx(a * 0.9 * np.array([1.0, 0.5, 0.25]) + (1 - a) * 1.0, abs=1e-5)


# ------------------------------------------------------------------------------------------ denoiser
def test_denoiser_cuts_the_noise_and_keeps_the_mean(tiny):
    pytest.importorskip("pyoidn")
    from natscene.denoise.oidn import OIDN, denoise_frame
    from natscene.keyframes.sky import sky_image
    from natscene.scatter.render import render

    # 160x120: OIDN needs some context (a cloud a few pixels across, as in the 64x48 smoke frames, is left
    # almost as it is: measured 1.0-1.9x there). The path-traced transport (dobashi: orders 2-4 by independent
    # paths per pixel, 4 spp) gives the per-pixel Monte Carlo grain the denoiser is for; the all-orders
    # transport's photon cache is smooth per pixel (noise figure 0.004 here, which OIDN leaves as it is)
    cam = frame_camera(SIDE_CAM, (160, 120))
    sky = sky_image(cam, SUN, {})
    p = {k: np.asarray(v, np.float64) for k, v in FIT.items()}
    raw = [render(tiny, cam, SUN, p, sky, {"transport": "dobashi", "orders": 4, "spp": 4, "seed": s}) for s in (0, 1)]
    f = frame_features(tiny, cam, p, sky)
    cloud = cloud_pixels(f["opacity"])
    assert cloud.sum() > 300
    oidn = OIDN(key="shots.test.denoise", threads=2)
    den = [denoise_frame(r, f, oidn) for r in raw]
    n_raw, n_den = noise_figure(*raw, cloud), noise_figure(*den, cloud)
    assert n_raw > 0.02                                   # the frame is grainy to start with
    assert n_den <= n_raw / 3, (n_raw, n_den)             # measured 0.138 -> 0.033 on this frame
    for r, d in zip(raw, den):
        assert d[cloud].mean() == pytest.approx(r[cloud].mean(), rel=0.02)
    # the sky (no cloud in the pixel) is left exactly as rendered
    sky_px = f["coverage"] == 0
    assert np.array_equal(den[0][sky_px], raw[0][sky_px])


def test_missing_denoiser_names_the_key(monkeypatch):
    from natscene.denoise.oidn import OIDN, DenoiserUnavailable

    monkeypatch.setitem(sys.modules, "pyoidn", None)                 # import pyoidn -> ImportError
    with pytest.raises(DenoiserUnavailable, match=r"shots\.day\.denoise.*Open Image Denoise.*none"):
        OIDN(key="shots.day.denoise")
    assert issubclass(DenoiserUnavailable, InputError)


# ------------------------------------------------------------------------------------------ resolution
def test_1920x1080_frame_has_the_field_of_view_of_640x480(tiny):
    from natscene.scatter.render import render

    p = {k: np.asarray(v, np.float64) for k, v in DAY.items()}
    cover = {}
    for res in ((640, 480), (1920, 1080)):
        cam = frame_camera(SIDE_CAM, res)
        assert (cam.width, cam.height) == res and cam.fov == 36
        # the cloud's silhouette (transmittance T of the view march) is what is measured: single scattering only
        _, comp = render(tiny, cam, SUN, p, np.zeros(3),
                         {"transport": "dobashi", "orders": 1, "spp": 1, "supersample": 1}, return_components=True)
        cloud = comp["T"] < 0.5
        rows = np.flatnonzero(cloud.any(axis=1))
        cover[res] = (cloud.sum() / res[1] ** 2, cloud.mean(), rows[0] / res[1], (rows[-1] + 1) / res[1])
    (h4, a4, t4, b4), (h16, a16, t16, b16) = cover[(640, 480)], cover[(1920, 1080)]
    assert h16 == pytest.approx(h4, rel=0.02)             # same solid angle in units of the vertical fov
    assert a16 / a4 == pytest.approx((4 / 3) / (16 / 9), rel=0.02)   # wider frame, same cloud: 0.75 of the area
    assert t16 == pytest.approx(t4, abs=2 / 480) and b16 == pytest.approx(b4, abs=2 / 480)


# ------------------------------------------------------------------------------------------ mie_blend
def test_mie_ratio_and_its_application():
    m_hg = np.full((4, 4, 3), 0.2)
    m_mie = m_hg.copy()
    m_mie[0, 0] = 2.0
    m_hg[3, 3] = m_mie[3, 3] = 0.0                        # no cloud in either march: ratio 1
    r = mie_ratio(m_mie, m_hg, eps_rel=0.01)
    assert np.allclose(r[1:3, 1:3], 1.0) and np.allclose(r[3, 3], 1.0) and r[0, 0, 0] == pytest.approx(2.002 / 0.202)
    sky = np.full((4, 4, 3), 0.5)
    L_b, t_c = 0.25 * sky, np.full((4, 4), 2.0)
    B = unscattered(L_b, t_c, [0.1, 0.2, 0.3], sky)
    e = np.exp(-2.0 * np.array([0.1, 0.2, 0.3]))
    assert np.allclose(B, 0.125 * e + (1 - e) * 0.5)
    frame = B + 0.3
    out = apply_ratio(frame, B, r)
    assert np.allclose(out[1, 1], frame[1, 1]) and np.allclose(out[0, 0], B[0, 0] + 0.3 * r[0, 0])


def test_sun_key_quantisation():
    assert sun_key(*quantised_sun(130.0, 35.0)) == "az130_el35"
    assert sun_key(*quantised_sun(-5.0, 6.1)) == "az355_el6"
    assert sun_key(*quantised_sun(112.26, 2.74)) == "az112.5_el2.5"
    assert sun_key(*quantised_sun(359.9, -0.1)) == "az0_el0"
    assert quantised_sun(10.3, 20.2, step=1.0) == (10.0, 20.0)


def test_mie_table_must_be_a_droplet_population():
    cfg = {"volumes": {"v": {}}, "keyframes": {}, "views": {}, "mie": {"droplets": {"strato": {}}},
           "shots": {"s": {"volume": "v", "frames": 2, "phase": "mie_blend", "mie_table": "fog", "keyframes": [
               {"at": 0, "params": DAY, "sun": {"azimuth": 1, "elevation": 2},
                "camera": {"position": [0, 0, -1], "look_at": [0, 0, 0]}}]}}}
    with pytest.raises(InputError, match=r"shots\.s\.mie_table.*'fog'.*mie\.droplets"):
        validate_shot("s", cfg["shots"]["s"], cfg)
    cfg["shots"]["s"]["mie_table"] = "strato"
    validate_shot("s", cfg["shots"]["s"], cfg)
    cfg["shots"]["s"]["phase"] = "hg"
    with pytest.raises(InputError, match=r"shots\.s\.mie_table.*mie_blend"):
        validate_shot("s", cfg["shots"]["s"], cfg)


def _snake(repo: Path, workdir: Path, cfg: Path, *args):
    env = dict(os.environ, PYTHONPATH=str(repo / "src"), PYTHONUNBUFFERED="1")
    cmd = [sys.executable, "-m", "snakemake", "-s", str(repo / "Snakefile"), "--configfile", str(cfg),
           "--directory", str(workdir), "--cores", "2", *args]
    proc = subprocess.run(cmd, env=env, capture_output=True, text=True)
    if proc.returncode != 0:
        raise AssertionError(f"snakemake {' '.join(args)} failed:\n{proc.stdout[-4000:]}\n{proc.stderr[-6000:]}")
    return proc.stdout + proc.stderr


def _job_count(out: str, rule: str) -> int:
    table = out.split("Job stats", 1)[1] if "Job stats" in out else ""
    for line in table.splitlines():
        parts = line.split()
        if len(parts) == 2 and parts[0] == rule:
            return int(parts[1])
    return 0


@pytest.fixture(scope="module")
def mie_shot(tmp_path_factory):
    """The smoke workflow's two-frame `tiny_mie` shot (phase mie_blend), run by Snakemake."""
    base = tmp_path_factory.mktemp("mie_shot")
    repo = base / "repo"
    repo.mkdir()
    for item in ("Snakefile", "workflow", "scripts", "src", "resources"):   # resources: the config checks its inputs
        (shutil.copytree if (ROOT / item).is_dir() else shutil.copy2)(ROOT / item, repo / item)
    cfg = base / "smoke.yaml"
    shutil.copy2(ROOT / "config" / "smoke.yaml", cfg)
    workdir = base / "run"
    frames = [f"results/shots/tiny_mie/frames/{f:04d}.exr" for f in range(2)]
    out = _snake(repo, workdir, cfg, *frames)
    return repo, workdir, cfg, out


def test_mie_blend_shot_renders_a_silver_lining(mie_shot):
    repo, workdir, cfg, out = mie_shot
    shot = workdir / "results" / "shots" / "tiny_mie"
    assert _job_count(out, "point_scatter") == 4          # two suns x (Mie, HG)
    ratios = {}
    for f in (0, 1):
        final = read_exr(shot / "frames" / f"{f:04d}.exr")
        raw = read_exr(shot / "frames" / f"{f:04d}.raw.exr")
        assert final.channels[:6] == ["R", "G", "B", "hg.R", "hg.G", "hg.B"]
        assert final.attrs["phase"] == "mie_blend" and final.attrs["denoised"] is True
        for ch in ("A", "albedo.R", "normal.X", "mie_ratio.G"):
            assert ch in raw.channels
        state = read_yaml(shot / "params" / f"{f:04d}.yaml")
        cam = frame_camera(state["camera"], (64, 48))
        angle = np.degrees(np.arccos(np.clip(cam.ray_directions() @ np.asarray(state["sun"]["direction"]), -1, 1)))
        alpha = raw.pixels[..., raw.channels.index("A")]
        y = lambda img: img @ np.array([0.2126, 0.7152, 0.0722])  # noqa: E731
        mie, hg = y(raw.pixels[..., 0:3]), y(raw.pixels[..., 3:6])  # same render, same noise: a clean ratio
        ratios[f] = (angle, alpha, mie, hg)
    # frame 1: the sun hidden just behind the upper edge; the cloud's rim within 3 deg of it is brighter with Mie
    angle, alpha, mie, hg = ratios[1]
    rim = (angle < 3.0) & (alpha > 0.05)
    assert rim.sum() >= 10
    assert mie[rim].mean() > 1.3 * hg[rim].mean()          # measured 6.4
    # frame 0: the day view from the ground (the camera looks up at the cloud, the sun behind its shoulder):
    # every cloud pixel sees side scattering, where Mie's phase function is far below HG's. The frame's Mie/HG
    # over the cloud lies between the single-scattering phase ratio at the pixels' angles and 1
    angle, alpha, mie, hg = ratios[0]
    cloud = alpha > 0.5
    assert cloud.sum() >= 50 and 85 < angle[cloud].min() and angle[cloud].max() < 115
    from natscene.mie.phase import hg_table, read_table
    table = read_table(workdir / "results" / "mie" / "table.exr")
    ref = hg_table(float(table.g[1]))
    th = np.radians(angle[cloud])
    single = (np.stack([np.interp(th, table.theta, table.rgb[:, c]) for c in range(3)], -1)
              @ np.array([0.2126, 0.7152, 0.0722])) / np.interp(th, ref.theta, ref.rgb[:, 1])
    assert single.max() < 0.5                              # the phase functions differ here (measured 0.17-0.3)
    assert single.min() < mie[cloud].mean() / hg[cloud].mean() < 1.0   # measured 0.84
    # one solution per distinct sun: a camera move under a fixed sun needs one Mie + one HG solve for 3 frames
    conf = yaml.safe_load(cfg.read_text())
    s = conf["shots"]["tiny_mie"]
    s["frames"] = 3
    s["keyframes"][1]["at"] = 2
    s["keyframes"][1]["sun"] = {"azimuth": 130.2, "elevation": 35.1}     # rounds to the sun of keyframe 0
    cfg2 = cfg.parent / "fixed_sun.yaml"
    cfg2.write_text(yaml.safe_dump(conf))
    dry = _snake(repo, workdir, cfg2, "-n", "--forceall", *[f"results/shots/tiny_mie/frames/{f:04d}.exr" for f in range(3)])
    assert _job_count(dry, "render_frame") == 3 and _job_count(dry, "point_scatter") == 2
