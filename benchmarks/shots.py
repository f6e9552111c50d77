"""Benchmark: shot frames (issue 18) on the main job's cumulonimbus (194x122x194) at the main shot's render
settings (config shots.day_to_sunset.render: 16 spp, orders up to 4), each number measured in this one run:

- the whole frame (natscene.keyframes.frame.render_shot_frame: Preetham sky, forward renderer, albedo/normal
  features, OIDN) at 640x480 and at 1920x1080, with the time of each part;
- the noise figure (natscene.denoise.noise: two renders with seeds 0 and 1, over the cloud pixels
  median|a - b| / median((a + b)/2) / sqrt 2) of the 640x480 frame before and after the denoiser, and the
  denoiser's change of the cloud's mean radiance;
- the Mie frame (phase mie_blend; the sun's point-to-point solutions loaded and their per-sun fields warm, as
  for every frame after the first of a sun) against the HG frame (phase hg) of the same view and settings, a
  frame of the main job's `sunset_mie` shot (the sun 1 deg behind the anvil's edge), and the time of one
  point-to-point solve (when this run has to solve it; reused from results/mie/pointcloud otherwise);
- the noise figure of the shot's other keyframes (frames 12 and 23: the sun at el 15 and 3 deg), denoiser off;
- the same 640x480 frame with ``transport: dobashi`` (path-traced orders 2-4, the frames before issue 16):
  its time and noise figure before and after the denoiser;
- side-by-side crops for the docs: Dobashi raw | denoised | all-orders raw | denoised (shots_denoise.png) and
  Mie | HG around the hidden sun (shots_mie_sunset.png), in results/benchmarks/.

The day frame is keyframe 0 of day_to_sunset (the kite fit with the shot's explicit parameters and sun). Wall
times on this machine vary with the load of other jobs: the load average is recorded; compare ratios.

Usage: nice .venv/bin/python benchmarks/shots.py [--volume results/volumes/cumulonimbus] [--skip-1080]
"""
import argparse
import os
import time
from pathlib import Path

import numpy as np

from _common import ROOT, write_result
from natscene.config import load_yaml_config, validate_config
from natscene.denoise.noise import cloud_pixels, noise_figure
from natscene.denoise.oidn import OIDN
from natscene.geometry import sun_direction
from natscene.io import to_srgb8, write_png
from natscene.keyframes.frame import render_shot_frame
from natscene.keyframes.shot import (bracket, frame_state, keyframe_params, quantised_sun, resolve_keyframe,
                                     sun_key)
from natscene.variant import select_variant
from natscene.volume.grid import load_volume

# the kite fit of the main job (results/fit/kite/params.yaml when it exists: see _kite_params)
PARAMS = {"L_in": 6.35, "g": 0.698, "extinction": 0.0243, "beta": 0.9998, "L_amb": 0.0,
          "kappa_a": [0.0, 0.1, 0.6], "c_in": [0.971, 1.002, 1.065]}


def _kite_params() -> dict:
    """The chosen parameters of the main job's kite fit, or PARAMS when the fit has not run."""
    from natscene.io import read_yaml
    f = ROOT / "results" / "fit" / "kite" / "params.yaml"
    if not f.is_file():
        return dict(PARAMS)
    ch = read_yaml(f)["chosen"]
    return {k: ch[k] for k in PARAMS}


def shot_state(params, az, el, camera):
    """A frame state (params, sun, camera) as natscene.keyframes.shot.frame_state writes it."""
    return {"params": params, "sun": {"direction": sun_direction(az, el).tolist(), "azimuth": az, "elevation": el},
            "camera": camera}


def _crop(img, cy, cx, h, w):
    H, W = img.shape[:2]
    y0 = int(np.clip(cy - h // 2, 0, H - h))
    x0 = int(np.clip(cx - w // 2, 0, W - w))
    return img[y0:y0 + h, x0:x0 + w]


def _side_by_side(path, images, k, gap=4):
    tiles = [to_srgb8(i, k) for i in images]
    sep = np.full((tiles[0].shape[0], gap, 3), 255, np.uint8)
    row = [tiles[0]]
    for t in tiles[1:]:
        row += [sep, t]
    write_png(path, np.concatenate(row, axis=1), encoded=True)


def _solutions(cfg, vol, shot, state, log):
    """The Mie and HG point-to-point solutions of the frame's (rounded) sun: from results/ or solved here."""
    from natscene.mie.phase import compute_mie_table, hg_table, read_table
    from natscene.mie.points import generate_points
    from natscene.mie.solver import load_solution, solve

    az, el = quantised_sun(state["sun"]["azimuth"], state["sun"]["elevation"], shot["mie_sun_step"])
    key = sun_key(az, el)
    tpath = ROOT / "results" / "mie" / "table.exr"
    if tpath.is_file():
        table = read_table(tpath)
    else:
        t = cfg["mie"]["table"]
        table = compute_mie_table(t["r_eff_um"], t["v_eff"], t["n_radii"], spectral_nm=())
    hg = hg_table(float(table.g[1]))
    sols, solve_s = {}, None
    s = cfg["mie"]["solver"]
    for ph, tab in (("mie", table), ("hg", hg)):
        p = ROOT / "results" / "mie" / "pointcloud" / shot["volume"] / key / ph / "solution.npz"
        if p.is_file():
            sols[ph] = load_solution(p)
            continue
        t0 = time.perf_counter()
        pts = generate_points(vol, sun_direction(az, el), s["sigma_t"], s["spacing_voxels"], s["density_threshold"])
        sols[ph] = solve(pts, tab, s["passes"], s["radius"], s["coherence_scale"], s["albedo"], s["min_attenuation"])
        solve_s = time.perf_counter() - t0
        log(f"solved {ph} for {key} in {solve_s:.1f} s")
    return {"solution_mie": sols["mie"], "solution_hg": sols["hg"], "table_mie": table, "table_hg": hg,
            "render": cfg["mie"]["render"]}, key, solve_s


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--volume", default=str(ROOT / "results" / "volumes" / "cumulonimbus"))
    ap.add_argument("--skip-1080", action="store_true", help="leave out the 1920x1080 frame")
    a = ap.parse_args()
    log = print
    cfg = load_yaml_config(ROOT / "config" / "config.yaml")
    validate_config(cfg, ROOT / "workflow" / "schemas" / "config.schema.yaml")
    day = cfg["shots"]["day_to_sunset"]
    variant = select_variant(threads=2)
    if Path(a.volume, "density.vol").is_file():
        vol = load_volume(a.volume)
    else:
        from natscene.volume.build import build_volume

        vol, _ = build_volume(cfg["volumes"]["cumulonimbus"], "cumulonimbus")
    oidn = OIDN(key="benchmark", threads=2)
    shot = {**day, "phase": "hg", "denoise": "oidn"}
    # keyframe 0 as the interpolate rule resolves it: the kite fit with the shot's explicit parameters (its storm
    # cloud's extinction), its sun and its camera (metres)
    fitted = {"chosen": _kite_params()}
    r0 = resolve_keyframe("day_to_sunset", 0, day["keyframes"][0], cfg)
    state = frame_state(r0["at"], [{**r0, "params": keyframe_params(r0, fitted)}])
    render_shot_frame(vol, state, {**shot, "resolution": [32, 24], "render": {**shot["render"], "spp": 1}},
                      denoiser=oidn)                                         # compile the kernels once
    load0 = os.getloadavg()[0]
    res = {"variant": variant, "render": dict(day["render"]), "load_average_1min_at_start": round(load0, 2)}

    # --- 640x480: frame time + the noise figure before / after the denoiser
    outs = []
    for seed in (0, 1):
        t0 = time.perf_counter()
        outs.append(render_shot_frame(vol, state, {**shot, "resolution": [640, 480],
                                                   "render": {**shot["render"], "seed": seed}}, denoiser=oidn))
        if seed == 0:
            res["seconds_frame_640x480"] = round(time.perf_counter() - t0, 2)
            res["seconds_640x480_parts"] = {k: round(v, 2) for k, v in outs[0]["timings"].items()}
    cloud = cloud_pixels(outs[0]["features"]["opacity"])
    n_raw = noise_figure(outs[0]["raw"], outs[1]["raw"], cloud)
    n_den = noise_figure(outs[0]["final"], outs[1]["final"], cloud)
    mean_change = float(outs[0]["final"][cloud].mean() / outs[0]["raw"][cloud].mean() - 1)
    res.update({"cloud_pixels_640x480": int(cloud.sum()), "noise_figure_raw_640x480": round(n_raw, 4),
                "noise_figure_denoised_640x480": round(n_den, 4), "noise_reduction": round(n_raw / n_den, 2),
                "denoised_mean_radiance_change": round(mean_change, 4),
                "photons_640x480": outs[0]["photons"],
                "target_noise_figure_raw": 0.05, "target_noise_figure_denoised": 0.01})
    log(f"640x480: {res['seconds_frame_640x480']} s, noise figure {n_raw:.4f} -> {n_den:.4f}")

    # --- the shot's other keyframes (warmer light, the sun at el 15 and 3 deg): their noise figure
    res["noise_figure_raw_keyframes"] = {}
    for i, kf in enumerate(day["keyframes"][1:], start=1):
        r = resolve_keyframe("day_to_sunset", i, kf, cfg)
        st = frame_state(r["at"], [{**r, "params": keyframe_params(r, fitted if r.get("fit") else None)}])
        pair = [render_shot_frame(vol, st, {**shot, "resolution": [640, 480], "denoise": "none",
                                            "render": {**shot["render"], "seed": seed}}) for seed in (0, 1)]
        n_k = noise_figure(pair[0]["raw"], pair[1]["raw"], cloud_pixels(pair[0]["features"]["opacity"]))
        res["noise_figure_raw_keyframes"][f"frame_{r['at']}"] = round(n_k, 4)
        log(f"keyframe at {r['at']}: noise figure {n_k:.4f}")

    # --- the same frame with the paper's transport (path-traced orders 2-4, the frames before issue 16)
    dob = []
    for seed in (0, 1):
        t0 = time.perf_counter()
        dob.append(render_shot_frame(vol, state, {**shot, "resolution": [640, 480],
                                                  "render": {**shot["render"], "transport": "dobashi",
                                                             "seed": seed}}, denoiser=oidn))
        if seed == 0:
            res["seconds_frame_640x480_dobashi"] = round(time.perf_counter() - t0, 2)
    d_raw = noise_figure(dob[0]["raw"], dob[1]["raw"], cloud)
    d_den = noise_figure(dob[0]["final"], dob[1]["final"], cloud)
    res.update({"noise_figure_raw_640x480_dobashi": round(d_raw, 4),
                "noise_figure_denoised_640x480_dobashi": round(d_den, 4),
                "noise_reduction_dobashi": round(d_raw / d_den, 2)})
    log(f"dobashi 640x480: {res['seconds_frame_640x480_dobashi']} s, noise figure {d_raw:.4f} -> {d_den:.4f}")
    ys, xs = np.nonzero(cloud)
    k = 1.0 / float(np.percentile(outs[0]["final"][cloud], 99.5))
    crop = [_crop(o, int(ys.mean()), int(xs.mean()), 200, 300)
            for o in (dob[0]["raw"], dob[0]["final"], outs[0]["raw"], outs[0]["final"])]
    out_dir = ROOT / "results" / "benchmarks"
    out_dir.mkdir(parents=True, exist_ok=True)
    _side_by_side(out_dir / "shots_denoise.png", crop, k)

    # --- Mie frame against the HG frame (sunset_mie, frame 2: the sun 1 deg behind the anvil's edge)
    sm = cfg["shots"]["sunset_mie"]
    keys = []
    for i in bracket(sm, 2):
        kf = resolve_keyframe("sunset_mie", i, sm["keyframes"][i], cfg)
        keys.append({**kf, "params": keyframe_params(kf, None)})
    st = frame_state(2, keys)
    mie, key, solve_s = _solutions(cfg, vol, sm, st, log)
    ms = {**sm, "resolution": [640, 480], "denoise": "oidn"}
    render_shot_frame(vol, st, {**ms, "resolution": [64, 48]}, mie=mie, denoiser=oidn)  # per-sun fields: warm
    t0 = time.perf_counter()
    mie_out = render_shot_frame(vol, st, ms, mie=mie, denoiser=oidn)
    t_mie = time.perf_counter() - t0
    t0 = time.perf_counter()
    render_shot_frame(vol, st, {**ms, "phase": "hg"}, denoiser=oidn)
    t_hg = time.perf_counter() - t0
    cam = mie_out["camera"]
    angle = np.degrees(np.arccos(np.clip(cam.ray_directions() @ np.asarray(st["sun"]["direction"]), -1, 1)))
    alpha = mie_out["features"]["opacity"]
    lum = lambda img: img @ np.array([0.2126, 0.7152, 0.0722])  # noqa: E731
    rim = (angle < 2.0) & (alpha > 0.05)
    far = (angle > 20.0) & (alpha > 0.5)
    res.update({"mie_sun": key, "seconds_frame_mie_blend_640x480": round(t_mie, 2),
                "seconds_frame_hg_640x480_same_view": round(t_hg, 2), "ratio_mie_to_hg": round(t_mie / t_hg, 2),
                "seconds_mie_part": round(mie_out["timings"].get("mie_s", 0.0), 2),
                "seconds_point_scatter_solve_per_sun_and_phase": None if solve_s is None else round(solve_s, 1),
                "target_ratio_mie_to_hg": 2.0,
                "mie_over_hg_rim_within_2deg_of_sun": round(float(lum(mie_out["raw"])[rim].mean()
                                                                  / lum(mie_out["hg_raw"])[rim].mean()), 3)
                if rim.any() else None,
                "mie_over_hg_cloud_beyond_20deg": round(float(lum(mie_out["raw"])[far].mean()
                                                              / lum(mie_out["hg_raw"])[far].mean()), 3)
                if far.any() else None})
    iy, ix = np.unravel_index(int(np.argmin(angle)), angle.shape)
    k = 1.0 / float(np.percentile(lum(mie_out["hg_final"]), 99.9))   # exposed for the HG rim: Mie's burns out
    _side_by_side(out_dir / "shots_mie_sunset.png",
                  [_crop(o, iy + 60, ix, 240, 320) for o in (mie_out["final"], mie_out["hg_final"])], k)
    log(f"Mie {t_mie:.1f} s vs HG {t_hg:.1f} s")

    # --- 1920x1080
    if not a.skip_1080:
        t0 = time.perf_counter()
        big = render_shot_frame(vol, state, {**shot, "resolution": [1920, 1080]}, denoiser=oidn)
        res["seconds_frame_1920x1080"] = round(time.perf_counter() - t0, 2)
        res["seconds_1920x1080_parts"] = {k: round(v, 2) for k, v in big["timings"].items()}
        res["ratio_1920x1080_to_640x480"] = round(res["seconds_frame_1920x1080"] / res["seconds_frame_640x480"], 2)
        res["pixel_ratio_1920x1080_to_640x480"] = round(1920 * 1080 / (640 * 480), 2)
    res["targets_seconds"] = {"frame_640x480": 30, "frame_1920x1080": 180}
    res["load_average_1min_at_end"] = round(os.getloadavg()[0], 2)
    write_result("shots", res)


if __name__ == "__main__":
    main()
