"""Keyframe interpolation and shots (Dobashi 2012 §5.2, §6): frames at keyframes carry exactly their
parameters, midway frames the linear blend, slerp stays on the unit sphere and moves monotonically in angle,
Catmull-Rom interpolates its keyframes, the Preetham sky behaves as published, and (Snakemake dry run)
editing one keyframe marks only the frames of its adjacent segments out of date."""
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml

from natscene.errors import InputError
from natscene.geometry import Camera, sun_direction
from natscene.keyframes.animation import filmstrip, strip_indices, write_animation
from natscene.keyframes.interpolate import (catmull_rom, direction_to_sun_angles, ease, lerp, segment_t,
                                            slerp)
from natscene.keyframes.shot import (bracket, camera_neighbours, frame_state, keyframe_params,
                                     resolve_keyframe, validate_shot)
from natscene.sky.daylight import preetham_Yxy, shot_sky_radiance, zenith_Yxy

ROOT = Path(__file__).resolve().parents[1]

DAY = {"L_in": 4.0, "g": 0.6, "extinction": 0.05, "beta": 0.9, "L_amb": 0.3, "kappa_a": [0.1, 0.2, 0.3],
       "c_in": [1.0, 1.0, 1.0]}
DUSK = {"L_in": 1.0, "g": 0.8, "extinction": 0.03, "beta": 0.7, "L_amb": 0.1, "kappa_a": 0.5,
        "c_in": [1.45, 0.92, 0.48]}
CAM0 = {"position": [0.0, 0.25, -2.4], "look_at": [0.0, 0.3, 0.0], "up": [0, 1, 0], "fov": 36}  # as validated
CAM1 = {"position": [0.4, 0.2, -2.2], "look_at": [0.1, 0.3, 0.0], "up": [0, 1, 0], "fov": 40}


def _config(shot_keyframes, frames=9, **shot):
    return {"volumes": {"v": {}}, "views": {}, "keyframes": {},
            "shots": {"s": {"volume": "v", "frames": frames, "easing": "linear", "camera_path": "linear",
                            "keyframes": shot_keyframes, **shot}}}


def _keys(cfg, frame):
    shot = cfg["shots"]["s"]
    out = []
    for i in bracket(shot, frame):
        k = resolve_keyframe("s", i, shot["keyframes"][i], cfg)
        k["params"] = keyframe_params(k, None)
        out.append(k)
    return out


def _two_keyframes(**shot):
    return _config([{"at": 0, "params": DAY, "sun": {"azimuth": 130, "elevation": 35}, "camera": CAM0},
                    {"at": 8, "params": DUSK, "sun": {"azimuth": 100, "elevation": 3}, "camera": CAM1}], **shot)


# ------------------------------------------------------------------------------------ interpolation
def test_frame_at_keyframe_has_exactly_its_parameters():
    cfg = _two_keyframes()
    for frame, kf, p in ((0, cfg["shots"]["s"]["keyframes"][0], DAY), (8, cfg["shots"]["s"]["keyframes"][1], DUSK)):
        st = frame_state(frame, _keys(cfg, frame))
        for name in ("L_in", "g", "extinction", "beta", "L_amb"):
            assert st["params"][name] == p[name]
        assert st["params"]["c_in"] == list(map(float, p["c_in"]))
        assert st["params"]["kappa_a"] == list(np.broadcast_to(np.float64(p["kappa_a"]), 3))
        assert st["sun"]["azimuth"] == kf["sun"]["azimuth"] and st["sun"]["elevation"] == kf["sun"]["elevation"]
        np.testing.assert_array_equal(st["sun"]["direction"], sun_direction(kf["sun"]["azimuth"], kf["sun"]["elevation"]))
        assert st["camera"]["position"] == kf["camera"]["position"]
        assert st["camera"]["look_at"] == kf["camera"]["look_at"]
        assert st["camera"]["fov"] == kf["camera"]["fov"]


def test_midway_frame_is_the_blend():
    cfg = _two_keyframes()
    st = frame_state(4, _keys(cfg, 4))
    assert st["t"] == 0.5 and st["keyframes"] == [0, 8]
    assert st["params"]["L_in"] == pytest.approx(2.5)
    assert st["params"]["g"] == pytest.approx(0.7)
    assert st["params"]["c_in"] == pytest.approx([1.225, 0.96, 0.74])
    assert st["params"]["kappa_a"] == pytest.approx([0.3, 0.35, 0.4])
    assert st["camera"]["position"] == pytest.approx([0.2, 0.225, -2.3])
    assert st["camera"]["fov"] == pytest.approx(38)
    # the sun: on the great circle, at equal angles from both keyframe suns
    d0, d1 = sun_direction(130, 35), sun_direction(100, 3)
    d = np.array(st["sun"]["direction"])
    assert np.linalg.norm(d) == pytest.approx(1.0)
    assert np.arccos(d @ d0) == pytest.approx(np.arccos(d @ d1), abs=1e-9)
    assert np.dot(np.cross(d0, d1), d) == pytest.approx(0.0, abs=1e-12)
    # a quarter of the way, with easing: smoothstep(0.25) = 0.15625
    st = frame_state(2, _keys(cfg, 2), easing="smoothstep")
    assert st["t"] == pytest.approx(0.15625)
    assert st["params"]["L_in"] == pytest.approx(4.0 - 3.0 * 0.15625)


def test_frames_outside_keyframes_hold_and_bracket_is_local():
    cfg = _config([{"at": 2, "params": DAY, "sun": {"azimuth": 0, "elevation": 30}, "camera": CAM0},
                   {"at": 5, "params": DUSK, "sun": {"azimuth": 0, "elevation": 10}, "camera": CAM1},
                   {"at": 9, "params": DAY, "sun": {"azimuth": 0, "elevation": 5}, "camera": CAM0}], frames=12)
    shot = cfg["shots"]["s"]
    assert [bracket(shot, f) for f in (0, 2, 3, 5, 7, 9, 11)] == [[0], [0], [0, 1], [1], [1, 2], [2], [2]]
    assert frame_state(0, _keys(cfg, 0))["params"]["L_in"] == DAY["L_in"]
    assert camera_neighbours(shot, 3) == [0, 1, 2] and camera_neighbours(shot, 7) == [0, 1, 2]


def test_slerp_unit_length_and_monotone_angle():
    u, v = sun_direction(130, 35), sun_direction(95, 2)
    t = np.linspace(0, 1, 101)
    d = slerp(u, v, t)
    np.testing.assert_allclose(np.linalg.norm(d, axis=-1), 1.0, atol=1e-12)
    ang_u = np.arccos(np.clip(d @ u, -1, 1))
    ang_v = np.arccos(np.clip(d @ v, -1, 1))
    assert np.all(np.diff(ang_u) > 0) and np.all(np.diff(ang_v) < 0)
    omega = np.arccos(u @ v)
    np.testing.assert_allclose(ang_u, t * omega, atol=1e-9)  # constant angular speed
    np.testing.assert_array_equal(d[0], u)
    np.testing.assert_array_equal(d[-1], v)
    # the sun sets monotonically when both keyframes share an azimuth
    el = [direction_to_sun_angles(x)[1] for x in slerp(sun_direction(120, 40), sun_direction(120, 0), t)]
    assert np.all(np.diff(el) < 0) and el[0] == pytest.approx(40) and el[-1] == pytest.approx(0, abs=1e-9)
    with pytest.raises(ValueError):
        slerp([0, 1, 0], [0, -1, 0], 0.5)


def test_sun_angles_round_trip():
    for az, el in ((0, 0), (130, 35), (270, 80), (359, 3)):
        a, e = direction_to_sun_angles(sun_direction(az, el))
        assert a == pytest.approx(az) and e == pytest.approx(el)


def test_easing_and_segment():
    t = np.linspace(0, 1, 11)
    for kind in ("linear", "smoothstep", "sine"):
        e = ease(t, kind)
        assert e[0] == 0 and e[-1] == 1 and np.all(np.diff(e) > 0)
    assert ease(0.5, "sine") == pytest.approx(0.5)
    assert segment_t(3, 2, 6) == 0.25 and segment_t(9, 2, 6) == 1.0
    assert lerp(1.0, 3.0, 0.25) == pytest.approx(1.5)


def test_catmull_rom_interpolates_and_reproduces_lines():
    pts = np.array([[0.0, 0, 0], [1.0, 2, 0], [3.0, 1, 1], [4.0, 0, 2]])
    knots = [0, 3, 5, 9]
    for p, k in zip(pts, knots):
        np.testing.assert_allclose(catmull_rom(pts, knots, k), p, atol=1e-12)
    # points on a line at knots proportional to arc length: the spline is that line, linear in x
    line = np.array([[0.0, 0, 0], [1.0, 1, 1], [3.0, 3, 3], [4.0, 4, 4]])
    for x in (0.5, 2.0, 3.7):
        np.testing.assert_allclose(catmull_rom(line, [0, 1, 3, 4], x), [x, x, x], atol=1e-12)
    # continuous velocity at an inner knot
    h = 1e-5
    v_left = (catmull_rom(pts, knots, 3) - catmull_rom(pts, knots, 3 - h)) / h
    v_right = (catmull_rom(pts, knots, 3 + h) - catmull_rom(pts, knots, 3)) / h
    np.testing.assert_allclose(v_left, v_right, atol=1e-3)


def test_catmull_rom_camera_path_passes_through_keyframes():
    cams = [CAM0, CAM1, {"position": [0.6, 0.3, -2.0], "look_at": [0.0, 0.3, 0.0], "up": [0, 1, 0], "fov": 40}]
    cfg = _config([{"at": a, "params": DAY, "sun": {"azimuth": 130, "elevation": 35}, "camera": c}
                   for a, c in zip((0, 4, 8), cams)], camera_path="catmull_rom")
    shot = cfg["shots"]["s"]
    path = [resolve_keyframe("s", i, shot["keyframes"][i], cfg) for i in camera_neighbours(shot, 2)]
    st = frame_state(4, _keys(cfg, 4), camera_path="catmull_rom", path_keys=path)
    assert st["camera"]["position"] == CAM1["position"]
    st = frame_state(2, _keys(cfg, 2), camera_path="catmull_rom", path_keys=path)
    lin = frame_state(2, _keys(cfg, 2))
    assert st["camera"]["position"] != pytest.approx(lin["camera"]["position"])  # curved, not the chord


# ------------------------------------------------------------------------------------ keyframe sources
def test_fitted_keyframe_overridden_by_explicit_params():
    cfg = {"volumes": {"v": {}}, "views": {"kite": {"camera": CAM0, "sun": {"azimuth": 130, "elevation": 35}}},
           "keyframes": {"kite": {"photo": "p", "volume": "v", "view": "kite"}},
           "shots": {"s": {"volume": "v", "frames": 4, "keyframes": [
               {"at": 0, "fit": "kite"}, {"at": 3, "fit": "kite", "params": {"L_in": 1.0}}]}}}
    validate_shot("s", cfg["shots"]["s"], cfg)
    fitted = {"chosen": {**{k: v for k, v in DAY.items()}, "rank": 1, "O": 0.1}}
    k0 = resolve_keyframe("s", 0, cfg["shots"]["s"]["keyframes"][0], cfg)
    assert k0["sun"] == {"azimuth": 130, "elevation": 35} and k0["camera"]["position"] == CAM0["position"]
    assert keyframe_params(k0, fitted)["L_in"] == 4.0
    k1 = resolve_keyframe("s", 1, cfg["shots"]["s"]["keyframes"][1], cfg)
    p1 = keyframe_params(k1, fitted)
    assert p1["L_in"] == 1.0 and p1["g"] == DAY["g"]


def test_bad_shots_name_the_key():
    cfg = _config([{"at": 0, "params": {"L_in": 1.0}, "sun": {"azimuth": 0, "elevation": 10}, "camera": CAM0}])
    with pytest.raises(InputError, match=r"shots.s.keyframes\[0\].params"):
        validate_shot("s", cfg["shots"]["s"], cfg)
    cfg = _config([{"at": 0, "params": DAY, "camera": CAM0}])
    with pytest.raises(InputError, match=r"keyframes\[0\].sun"):
        validate_shot("s", cfg["shots"]["s"], cfg)
    cfg = _config([{"at": 12, "params": DAY, "sun": {"azimuth": 0, "elevation": 10}, "camera": CAM0}])
    with pytest.raises(InputError, match=r"keyframes\[0\].at"):
        validate_shot("s", cfg["shots"]["s"], cfg)
    cfg = _config([{"at": 0, "fit": "nope"}])
    with pytest.raises(InputError, match="'nope' is not in 'keyframes'"):
        validate_shot("s", cfg["shots"]["s"], cfg)


# ------------------------------------------------------------------------------------ sky
def test_preetham_zenith_and_published_values():
    d = np.array([[0.0, 1.0, 0.0]])
    for el in (10, 35, 60):
        ts = np.radians(90 - el)
        Y, x, y = preetham_Yxy(d, sun_direction(40, el), turbidity=3.0, min_view_elevation=1.0)
        Yz, xz, yz = zenith_Yxy(ts, 3.0)
        assert Y[0] == pytest.approx(Yz) and x[0] == pytest.approx(xz) and y[0] == pytest.approx(yz)
    # Preetham 1999 eq. (A.2) at T = 2, theta_s = 0: chi = 4pi/9 - pi/60, Yz = 3.1196 tan(chi) + 1.9882
    chi = (4 / 9 - 2 / 120) * np.pi
    assert zenith_Yxy(0.0, 2.0)[0] == pytest.approx(3.1196 * np.tan(chi) + 1.9882)
    # near-white chromaticity of a clear sky zenith
    _, xz, yz = zenith_Yxy(np.radians(45), 3.0)
    assert 0.22 < xz < 0.30 and 0.22 < yz < 0.31


def test_preetham_sky_darkens_and_reddens_at_sunset():
    cam = Camera((0, 0.3, -2.4), (0, 0.3, 0), (0, 1, 0), fov=40, width=32, height=24)
    day = shot_sky_radiance({}, cam.ray_directions(), sun_direction(180, 35))   # the shots' default sky
    dusk = shot_sky_radiance({}, cam.ray_directions(), sun_direction(180, 3))
    assert day.shape == (24, 32, 3) and np.all(day >= 0)
    assert dusk.mean() < day.mean()
    # the sky is bluer by day than at dusk (ratio blue / red)
    assert day[..., 2].mean() / day[..., 0].mean() > dusk[..., 2].mean() / dusk[..., 0].mean()
    # brighter toward the sun than away from it, at the same elevation
    d = np.array([sun_direction(180 + a, 10) for a in (10, 180)])
    rgb = shot_sky_radiance({}, d, sun_direction(180, 10))
    assert rgb[0].sum() > rgb[1].sum()


# ------------------------------------------------------------------------------------ animation
def test_filmstrip_and_animation(tmp_path):
    frames = [np.full((30, 40, 3), 20 * i, np.uint8) for i in range(7)]
    idx = strip_indices(7, 4)
    assert idx == [0, 2, 4, 6]
    strip = filmstrip([frames[i] for i in idx], height=15, gap=2)
    assert strip.shape == (15, 4 * 20 + 3 * 2, 3)
    assert strip[0, 0, 0] == 0 and strip[0, -1, 0] == 120 and strip[0, 20, 0] == 255
    gif = tmp_path / "a.gif"
    write_animation(gif, frames, fps=10)
    import imageio.v3 as iio

    back = iio.imread(gif)
    assert back.shape[0] == 7
    mp4 = tmp_path / "a.mp4"
    write_animation(mp4, [np.full((31, 41, 3), 40 * i, np.uint8) for i in range(5)], fps=10)
    assert mp4.stat().st_size > 0


# ------------------------------------------------------------------------------------ workflow
SNAKEMAKE = [sys.executable, "-m", "snakemake"]


def _snake(repo, workdir, config, *args):
    env = dict(os.environ, PYTHONPATH=str(repo / "src"), PYTHONUNBUFFERED="1")
    cmd = SNAKEMAKE + ["-s", str(repo / "Snakefile"), "--configfile", str(config), "--directory", str(workdir),
                       "--cores", "2", *args]
    proc = subprocess.run(cmd, env=env, capture_output=True, text=True)
    if proc.returncode != 0:
        raise AssertionError(f"snakemake {' '.join(args)} failed:\n{proc.stdout[-3000:]}\n{proc.stderr[-4000:]}")
    return proc.stdout + proc.stderr


def _shot_config(mid_L_in):
    kf = [{"at": 0, "params": DAY, "sun": {"azimuth": 130, "elevation": 35}, "camera": CAM0},
          {"at": 3, "params": {**DAY, "L_in": mid_L_in}, "sun": {"azimuth": 120, "elevation": 20}, "camera": CAM0},
          {"at": 6, "params": DUSK, "sun": {"azimuth": 100, "elevation": 3}, "camera": CAM1}]
    return {"volumes": {"v": {"kind": "cumulus", "resolution": [16, 16, 16]}},
            "shots": {"s": {"volume": "v", "frames": 8, "keyframes": kf}}}


def _scheduled(out: str) -> list[int]:
    return sorted({int(f) for f in re.findall(r"wildcards: shot=s, frame=(\d{4})", out)})


def test_editing_one_keyframe_reruns_only_its_frames(tmp_path):
    repo = tmp_path / "repo"
    repo.mkdir()
    for item in ("Snakefile", "workflow", "scripts", "src"):
        (shutil.copytree if (ROOT / item).is_dir() else shutil.copy2)(ROOT / item, repo / item)
    workdir = tmp_path / "run"
    cfg = tmp_path / "shot.yaml"
    cfg.write_text(yaml.safe_dump(_shot_config(3.0)))
    targets = [f"results/shots/s/params/{f:04d}.yaml" for f in range(8)]
    _snake(repo, workdir, cfg, *targets)
    mid = yaml.safe_load((workdir / targets[1]).read_text())
    assert mid["keyframes"] == [0, 3] and mid["params"]["L_in"] == pytest.approx(4.0 - 1.0 / 3.0)
    assert yaml.safe_load((workdir / targets[7]).read_text())["params"]["L_in"] == DUSK["L_in"]
    at_key = yaml.safe_load((workdir / targets[3]).read_text())  # the middle keyframe, exactly
    assert at_key["keyframes"] == [3] and at_key["params"]["L_in"] == 3.0
    assert at_key["params"]["c_in"] == DAY["c_in"] and at_key["sun"]["elevation"] == 20
    assert _scheduled(_snake(repo, workdir, cfg, "-n", *targets)) == []
    # edit the middle keyframe (frame 3): frames 1..5 depend on it; 0, 6 and 7 do not
    cfg.write_text(yaml.safe_dump(_shot_config(2.0)))
    assert _scheduled(_snake(repo, workdir, cfg, "-n", *targets)) == [1, 2, 3, 4, 5]
    # edit the last keyframe's sun: frames 4..7
    conf = _shot_config(3.0)
    conf["shots"]["s"]["keyframes"][2]["sun"]["elevation"] = 1.0
    cfg.write_text(yaml.safe_dump(conf))
    assert _scheduled(_snake(repo, workdir, cfg, "-n", *targets)) == [4, 5, 6, 7]
    # listing the same keyframes in another order changes nothing
    conf = _shot_config(3.0)
    conf["shots"]["s"]["keyframes"].reverse()
    cfg.write_text(yaml.safe_dump(conf))
    assert _scheduled(_snake(repo, workdir, cfg, "-n", *targets)) == []
