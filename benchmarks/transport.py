"""Benchmark of the all-orders transport against Dobashi's (issue 16), one run, both models side by side.

For the main job's cloud and view (config/config.yaml: volume `cumulus`, view `kite`, its precompute
settings), per transport model (`all_orders`, `dobashi`):

- ``precompute_s``: the whole precompute (tables for every (sigma_t, g) node);
- ``noise``: the per-pixel relative standard error of the composed multiple-scattering term (median, p95
  over the cloud pixels and every node; from the precompute's own estimate);
- ``ga_iteration_ms``: one GA iteration of the fit (20 candidates composed at the 320x240 footprint and the
  kappa_a line search) on the kite photo;
- ``frame_s``: one forward-rendered frame of the same view at the tables' resolution (the direct render a
  fit would need per candidate without tables) and the fit speed-up 20 x frame / iteration (Dobashi
  reports about 6,000x);
- ``noise_repeated``: the same figure measured without the two-halves shortcut, at two nodes (sigma_t 0.2 and
  0.5, g 0.85, beta 0.99): each node traced 3 times with other seeds, 6 independent half-runs per pixel (5 degrees
  of freedom; the meta's two-halves estimate of one run, :func:`natscene.scatter.allorders.standard_error`, reads
  them within a few per cent), with the weight windows and sky lobe on and off, at the collision budget alone;
- ``noise_target_repeated``: item 3's figure (sun and sky composed, beta 0.9 / 0.99 / 0.999) the same way at two
  thick nodes (sigma_t 0.5 and 1, g 0.85) traced as the precompute traces them, noise target and top-ups
  included, beside the runs' own two-halves estimate (``--noise-target`` runs only this part and writes it into
  an existing transport.json);
- agreement with Mitsuba 3 ``volpath`` of every order (max_depth -1, no Russian roulette) on the tests'
  procedural cloud: keys ``volpath_mean_ratio`` and ``volpath_block_err_max`` (largest 8x8 block error)
  per (sigma_t, g, beta), for the composed tables.

Writes results/benchmarks/transport.json. Takes about half an hour on 2 cores (the all-orders precompute
dominates).   .venv/bin/python benchmarks/transport.py

``--baseline DIR`` (a checkout of an older version, e.g. ``git worktree add /tmp/base 9c1d408``) runs only the
main job's figures, once on this checkout's code and once on DIR's, each on its own code and config
(benchmarks/transport_version.py: precompute time and noise, one GA iteration, the 640x480 frame of the main shot
at the thick cloud's extinction with its noise figure), and writes them with their ratios into the ``versions``
entry of results/benchmarks/transport.json (made if missing). About 35 min on 2 cores; ``--keep-baseline`` keeps
the baseline's figures of the previous run and measures this checkout only.
"""
from __future__ import annotations

import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from _common import ROOT, write_result

import natscene  # noqa: F401
from natscene.config import load_yaml_config, resolve_path, validate_config
from natscene.geometry import Camera, sun_direction

from natscene.scatter.transport import TRANSPORTS  # noqa: E402


def main_job():
    cfg = load_yaml_config(ROOT / "config" / "config.yaml")
    validate_config(cfg, ROOT / "workflow" / "schemas" / "config.schema.yaml", source="config/config.yaml")
    return cfg


def kite_setup():
    """(config, camera, sun direction, volume) of the main job's cumulus seen from the kite view."""
    cfg = main_job()
    view = cfg["views"]["kite"]
    camera = Camera.from_view(view)
    sun = sun_direction(view["sun"]["azimuth"], view["sun"]["elevation"])
    return cfg, camera, sun, volume(cfg)


def photo_products(cfg, w, h):
    """The kite photo's L_sky, photo, cloud mask and c_in at the view's resolution (the sky stage in-process)."""
    from natscene.io import read_photo
    from natscene.sky.extract import extract_sky
    from natscene.sky.resample import area_resample, resample_labels
    photo = read_photo(resolve_path(cfg["photos"]["kite"]["path"], ROOT))
    res = extract_sky(photo)
    return {"photo": area_resample(res.photo, w, h), "sky": area_resample(res.sky, w, h),
            "cloud": resample_labels(res.labels.astype(np.float32), w, h) == 1, "c_in": np.asarray(res.sun.c_in)}, res


def volume(cfg):
    from natscene.volume.build import build_volume
    vol, _ = build_volume(cfg["volumes"]["cumulus"], "cumulus")
    return vol


def noise_figures(meta, transport):
    if transport == "all_orders":
        # sun (orders >= 2), sky, the two together, and the two together relative to the composed cloud pixel
        # (the measure of the Dobashi figure "sum" below) at beta 0.9, 0.99, 0.999
        return dict(meta["pixel_relative_standard_error"])
    return {"sum_of_orders": meta["pixel_relative_standard_error"]["sum"],
            **{k: v for k, v in meta["pixel_relative_standard_error"].items() if k != "sum"}}


def repeated_noise(vol, camera, sun, settings, nodes=((0.2, 0.85), (0.5, 0.85)), reps: int = 3,
                   beta: float = 0.99):
    """Per-pixel relative standard error of the composed sun (orders >= 2) and sky (R+G+B, orders >= 1) terms at
    ``beta`` from ``reps`` independent runs of a node (2 halves each): median and p95 over the cloud pixels, and
    the seconds per node."""
    from natscene.scatter.allorders import Lighting, Scene, view_images
    from natscene.scatter.bands import band_weights, channel_weights
    from natscene.scatter.single import march_view
    from natscene.scatter.transport.all_orders import skylight_dome
    out = {}
    for label, st in (("importance_on", settings),
                      ("importance_off", replace(settings, importance=False, sky_lobe_share=0.0))):
        scene = Scene(vol, Lighting(np.asarray(sun), skylight_dome(sun, None)), st)
        for sigma, g in nodes:
            foot = march_view(scene.med, camera, [sigma])["footprint"].reshape(camera.height, camera.width) > 0
            halves = {"sun": [], "sky": []}
            t0 = time.perf_counter()
            for r in range(reps):
                vi = view_images(scene, camera, sigma, g, seed=1000 + r)
                cs = band_weights(st.sun_bands, vi.sun_orders, beta)[0]
                ck = channel_weights(st.sky_bands, vi.sky_orders, beta)[0]
                for h in range(2):
                    halves["sun"].append(np.tensordot(cs, vi.sun_halves[h], 1))
                    halves["sky"].append(np.tensordot(ck[:3], vi.sky_halves[h][:3], 2))
            per_node = (time.perf_counter() - t0) / reps
            for key, x in halves.items():
                x = np.asarray(x, np.float64)
                m = x.mean(0)
                ok = foot & (m > 0)
                rel = x.std(0, ddof=1)[ok] / np.sqrt(2) / m[ok]      # one run = the mean of 2 halves
                out.setdefault(label, {})[f"{key}_s{sigma}_g{g}_beta{beta}"] = {
                    "median": round(float(np.median(rel)), 4), "p95": round(float(np.percentile(rel, 95)), 4)}
            out[label][f"node_s_s{sigma}_g{g}"] = round(per_node, 2)
    return out


def repeated_noise_target(vol, camera, sun, settings, sky=None, nodes=((0.5, 0.85), (1.0, 0.85)), reps: int = 3):
    """Item 3's figure at the main job's settings without the two-halves shortcut: each node traced ``reps``
    times with the noise target on, as the precompute traces it (budget, then top-ups), and the composed sun and
    sky in luminance (:func:`natscene.scatter.transport.all_orders.sky_luminance_weights`) at beta 0.9 / 0.99 / 0.999 taken
    from the 2 x ``reps`` independent half-runs per pixel (relative standard error of one run: median and p95
    over the cloud pixels), beside the runs' own two-halves estimate (the figure the top-up aims at and
    ``meta.yaml`` reports, the mean over the runs), their budget scales and the seconds per node."""
    from natscene.phase import hg
    from natscene.scatter.allorders import Lighting, Scene, view_images
    from natscene.scatter.single import march_view
    from natscene.scatter.transport.all_orders import (NOISE_BETAS, composed_halves, node_noise, skylight_dome,
                                                       sky_luminance_weights, target_figure)
    dome = skylight_dome(sun, sky)
    scene = Scene(vol, Lighting(np.asarray(sun), dome), settings)
    sky_w = sky_luminance_weights(sun, dome)
    cos_q = camera.ray_directions() @ (np.asarray(sun, np.float64) / np.linalg.norm(sun))
    out = {}
    for sigma, g in nodes:
        single = march_view(scene.med, camera, [sigma])
        foot = single["footprint"].reshape(camera.height, camera.width) > 0
        single_sun = hg(cos_q, g) * single["S_sun"][0]
        halves = {b: [] for b in NOISE_BETAS}
        estimates, scales = [], []
        t0 = time.perf_counter()
        for r in range(reps):
            vi = view_images(scene, camera, sigma, g, seed=2000 + r,
                             noise=lambda v: target_figure(node_noise(v, settings.sun_bands, settings.sky_bands,
                                                                       sky_w, foot, single_sun)))
            est = node_noise(vi, settings.sun_bands, settings.sky_bands, sky_w, foot, single_sun)
            estimates.append({b: est[f"sun_and_sky.beta{b:g}"] for b in NOISE_BETAS})
            scales.append(float(vi.stats.get("budget_scale", 1.0)))
            for b in NOISE_BETAS:
                halves[b] += composed_halves(vi, settings.sun_bands, settings.sky_bands, sky_w, b)["sun_and_sky"]
        node = {"seconds_per_node": round((time.perf_counter() - t0) / reps, 1), "budget_scale": scales}
        for b in NOISE_BETAS:
            x = np.asarray(halves[b], np.float64)
            m = x.mean(0)
            ok = foot & (m > 0)
            rel = x.std(0, ddof=1)[ok] / np.sqrt(2) / m[ok]          # one run = the mean of 2 halves
            node[f"beta{b:g}"] = {
                "repeated": {"median": round(float(np.median(rel)), 4), "p95": round(float(np.percentile(rel, 95)), 4)},
                "two_halves": {"median": round(float(np.mean([np.median(e[b]) for e in estimates])), 4),
                               "p95": round(float(np.mean([np.percentile(e[b], 95) for e in estimates])), 4)}}
        out[f"s{sigma}_g{g}"] = node
        print(f"noise target, repeated: sigma_t {sigma} g {g}: {node}")
    return out


def volpath_agreement(transport):
    """Composed tables vs Mitsuba volpath (every order, the tests' 8192-spp renders in
    tests/data/transport_volpath.npz) on the tests' procedural cloud, 48x36, with the tests' settings
    (all_orders: natscene.scatter.reference_scene.SETTINGS; dobashi: 4 orders, 4096 spp, and the orders above 4
    missing)."""
    from natscene.scatter.reference_scene import (CAM, GS, NOSKY, SETTINGS, SIGMAS, SUN, blob_volume, block_ratios,
                                                  volpath_references)
    from natscene.scatter.compose import compose
    from natscene.scatter.tables import precompute
    vol = blob_volume()
    refs = volpath_references(ROOT / "tests" / "data" / "transport_volpath.npz")
    tb = precompute(vol, CAM, SUN, sigmas=[0.0, *SIGMAS], gs=list(GS), seed=1, transport=transport, n_m=4,
                    spp=4096, all_orders=SETTINGS)
    foot = tb.footprint > 0
    out = {}
    for (s, g, b), ref in refs.items():
        p = dict(c_in=[1.0] * 3, L_in=1.0, g=g, sigma_t=s, beta=b, L_amb=0.0, kappa_a=[0.0] * 3, **NOSKY)
        ours = compose(tb, p, np.zeros((CAM.height, CAM.width, 3), np.float32))[0][..., 0]
        m = foot & (ref > 0)
        blk = block_ratios(ours, ref, m)
        out[f"s{s}_g{g}_b{b}"] = {"volpath_mean_ratio": round(float(ours[m].mean() / ref[m].mean()), 4),
                                  "volpath_block_err_max": round(float(np.abs(blk - 1).max()), 4)}
    return out


def noise_target_only():
    """``--noise-target``: only :func:`repeated_noise_target` on the main job's settings, written into the
    ``all_orders`` entry of an existing results/benchmarks/transport.json (a run of the whole benchmark makes it)."""
    import json
    from natscene.scatter.allorders import settings_from_config
    from natscene.variant import select_variant
    select_variant(threads=2)
    cfg, camera, sun, vol = kite_setup()
    path = ROOT / "results" / "benchmarks" / "transport.json"
    if not path.exists():
        sys.exit(f"{path} does not exist: run the whole benchmark first")
    result = json.loads(path.read_text())
    result["all_orders"]["noise_target_repeated"] = repeated_noise_target(
        vol, camera, sun, settings_from_config(cfg["precompute"]), cfg["precompute"].get("skylight"))
    tmp = path.with_suffix(".json.tmp")
    tmp.write_text(json.dumps(result, indent=2))
    tmp.replace(path)


def versions(base: Path, extinction: float = 0.0243, keep_baseline: bool = False):
    """``--baseline``: transport_version.py on this checkout and on ``base``, each in a subprocess on its own code,
    written into the ``versions`` entry of results/benchmarks/transport.json. ``keep_baseline``
    (``--keep-baseline``): measure this checkout only and keep the baseline's figures of the previous run (the
    same machine; its ``baseline_kept_from_previous_run`` says so)."""
    import json
    import os
    import subprocess
    import tempfile
    base = base.resolve()
    if not (base / "src" / "natscene").is_dir():
        sys.exit(f"--baseline {base}: not a natscene checkout (no src/natscene)")
    path = ROOT / "results" / "benchmarks" / "transport.json"
    result = json.loads(path.read_text()) if path.exists() else {"benchmark": "transport"}
    figures = {}
    if keep_baseline:
        if "baseline" not in result.get("versions", {}):
            sys.exit(f"--keep-baseline: {path} holds no baseline figures: run without it first")
        figures["baseline"] = dict(result["versions"]["baseline"], baseline_kept_from_previous_run=True)
    with tempfile.TemporaryDirectory() as tmp:
        for name, root in (("current", ROOT), ("baseline", base)):
            if name in figures:
                continue
            out = Path(tmp, f"{name}.json")
            subprocess.run([sys.executable, str(ROOT / "benchmarks" / "transport_version.py"), "--root", str(root),
                            "--out", str(out), "--extinction", str(extinction)], check=True,
                           env={**os.environ, "PYTHONPATH": str(root / "src")})
            figures[name] = json.loads(out.read_text())
    cur, old = figures["current"], figures["baseline"]
    figures["ratio_baseline_over_current"] = {
        "precompute_s": round(old["precompute_s"] / cur["precompute_s"], 3),
        "ga_iteration_ms": round(old["ga_iteration_ms"] / cur["ga_iteration_ms"], 3),
        "frame_640x480_s": round(old["frame_640x480"]["seconds"] / cur["frame_640x480"]["seconds"], 3)}
    result["versions"] = {k: figures[k] for k in ("current", "baseline", "ratio_baseline_over_current")}
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(".json.tmp")
    tmp.write_text(json.dumps(result, indent=2))
    tmp.replace(path)
    print(json.dumps(figures, indent=2))


def main():
    from natscene.fit.keyframe import fit_keyframe
    from natscene.scatter.allorders import settings_from_config
    from natscene.scatter.render import render
    from natscene.scatter.tables import precompute
    from natscene.variant import select_variant

    select_variant(threads=2)
    cfg, camera, sun, vol = kite_setup()
    pre = cfg["precompute"]
    products, _ = photo_products(cfg, camera.width, camera.height)
    result = {"volume": "cumulus", "view": "kite", "resolution": [camera.width, camera.height],
              "grid": {"extinction": pre["extinction"], "g": pre["g"]}}
    for transport in TRANSPORTS:
        st = settings_from_config(pre)
        t0 = time.perf_counter()
        tables = precompute(vol, camera, sun, extinctions=pre["extinction"], gs=pre["g"], n_m=pre["n_m"], spp=pre["spp"],
                            seed=pre["seed"], step_voxels=pre["step_voxels"], supersample=pre["supersample"],
                            transport=transport, all_orders=st, skylight=pre.get("skylight"), log=print)
        t_pre = time.perf_counter() - t0
        fit_settings = dict(cfg["fit"], n_max=30, epsilon_O=0.0, n_suc=0)
        fit_keyframe(tables, products["photo"], products["cloud"], products["sky"], products["c_in"],
                     dict(fit_settings, n_max=1), seed=0)     # warm-up (kernel compilation)
        t0 = time.perf_counter()
        fit = fit_keyframe(tables, products["photo"], products["cloud"], products["sky"], products["c_in"],
                           fit_settings, seed=0)
        t_fit = time.perf_counter() - t0
        per_iter = t_fit / (fit["result"].iterations + 1)
        chosen = fit["params"]["chosen"]
        p = {k: chosen[k] for k in ("L_in", "g", "extinction", "beta", "L_amb", "c_in", "kappa_a")}
        p.update({k: chosen[k] for k in ("sky_scale", "ground_albedo") if k in chosen})
        if transport == "dobashi":
            shot = {"transport": transport, "orders": pre["n_m"], "spp": 16}
        else:
            shot = {"transport": transport, "sun_collisions": st.sun_collisions, "sky_collisions": st.sky_collisions}
        render(vol, camera, sun, p, products["sky"], shot)                # warm-up
        t0 = time.perf_counter()
        render(vol, camera, sun, p, products["sky"], shot)
        t_frame = time.perf_counter() - t0
        result[transport] = {
            "precompute_s": round(t_pre, 1), "noise": noise_figures(tables.meta, transport),
            **({"noise_repeated": repeated_noise(vol, camera, sun, replace(st, noise_target=(0.0, 0.0))),
                "noise_target_repeated": repeated_noise_target(vol, camera, sun, st, pre.get("skylight"))}
               if transport == "all_orders" else {}),
            "ga_iteration_ms": round(1000 * per_iter, 2), "frame_s": round(t_frame, 2),
            "fit_speedup_over_direct_rendering": round(20 * t_frame / per_iter, 1),
            "fit_O": round(fit["result"].best.objective, 4),
            "fitted": {k: chosen[k] for k in ("L_in", "g", "extinction", "beta", "L_amb")},
            "table_megabytes": round(tables.nbytes() / 1e6, 1),
            "volpath": volpath_agreement(transport),
        }
        print(result[transport])
    write_result("transport", result)


if __name__ == "__main__":
    if "--noise-target" in sys.argv[1:]:
        noise_target_only()
    elif "--baseline" in sys.argv[1:]:
        versions(Path(sys.argv[sys.argv.index("--baseline") + 1]), keep_baseline="--keep-baseline" in sys.argv[1:])
    else:
        main()
