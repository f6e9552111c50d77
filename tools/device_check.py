"""Timings of the cloud chain on the Mitsuba variant ``natscene.variant.select_variant`` picks (``cuda_ad_rgb``
where a CUDA GPU works): one all-orders precompute node (σ_t 0.5, g 0.85, twice: the first compiles the
kernels), the main job's whole precompute (cumulus, ``kite`` view), and the day frame of ``day_to_sunset`` at
640×480 and 1920×1080 (raw: no denoiser). Writes ``<out>/device_check.json`` and the raw 640×480 frame
(``frame640.npy``, float16) to compare with a CPU render of the same frame. With ``--budget-scales 1,4,8,16``
instead: the precompute's noise figures and time against the photon budget (:func:`budget_study`). ``--parts``
picks some of the three (e.g. ``--parts precompute``); ``--dump-config cfg.json --overlay config/gpu.yaml`` merges an
overlay into the config JSON.

A GPU machine may lack the workflow's tools (Snakemake, jsonschema, OIDN): validate the config where they are
installed and carry the JSON along:

    .venv/bin/python tools/device_check.py --dump-config cfg.json        # here
    python3 tools/device_check.py --config-json cfg.json --out OUT       # there (mitsuba, drjit, OpenImageIO,
                                                                         # colour-science, numba, scipy on the path)
"""
import argparse
import json
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))
sys.path.insert(0, str(ROOT / "benchmarks"))


PARTS = ("node", "precompute", "frames")


def validated_config(overlays=()) -> dict:
    """The main job's config with the ``overlays`` (paths, e.g. ``config/gpu.yaml``) merged the way Snakemake
    merges several ``--configfile`` arguments, validated."""
    from snakemake.utils import update_config

    from natscene.config import load_yaml_config, validate_config
    cfg = load_yaml_config(ROOT / "config" / "config.yaml")
    for path in overlays:
        update_config(cfg, load_yaml_config(Path(path)))
    return validate_config(cfg, ROOT / "workflow" / "schemas" / "config.schema.yaml",
                           source=" + ".join(["config/config.yaml", *map(str, overlays)]))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--dump-config", help="write the validated main config as JSON and stop")
    ap.add_argument("--overlay", action="append", default=[],
                    help="with --dump-config: a config overlay merged onto the main job (repeatable)")
    ap.add_argument("--config-json", help="the validated main config (from --dump-config)")
    ap.add_argument("--out", default=str(ROOT / "results" / "benchmarks"))
    ap.add_argument("--budget-scales", help="instead: the noise and time of the nodes at extinction 0.1 and 0.2 /m (g 0.85) "
                    "with the collision budgets times each of these comma-separated factors, then the whole "
                    "precompute at the largest factor if it fits in --budget-s seconds")
    ap.add_argument("--budget-s", type=float, default=300.0)
    ap.add_argument("--parts", default="node,precompute,frames",
                    help="comma-separated, in this order: node (one node twice), precompute (the main job's whole "
                    "precompute), frames (the day frame at 640x480 and 1920x1080)")
    a = ap.parse_args()
    parts = set(a.parts.split(","))
    if not parts <= set(PARTS):
        ap.error(f"--parts: unknown {sorted(parts - set(PARTS))}; choose from {', '.join(PARTS)}")
    if a.dump_config:
        Path(a.dump_config).write_text(json.dumps(validated_config(a.overlay), default=str))
        return
    cfg = json.loads(Path(a.config_json).read_text()) if a.config_json else validated_config()
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    res = {}

    def dump():
        (out / "device_check.json").write_text(json.dumps(res, indent=1, default=str))

    import numpy as np

    from natscene.variant import select_variant
    res["variant"] = select_variant()
    from natscene.geometry import Camera, sun_direction
    from natscene.keyframes.frame import render_shot_frame
    from natscene.scatter.allorders import Lighting, Scene, settings_from_config, view_images
    from natscene.scatter.transport.all_orders import skylight_dome
    from natscene.volume.build import build_volume
    from shots import PARAMS, shot_state

    view = cfg["views"]["kite"]
    camera = Camera.from_view(view)
    sun = sun_direction(view["sun"]["azimuth"], view["sun"]["elevation"])
    vol, _ = build_volume(cfg["volumes"]["cumulus"], "cumulus")
    pre = cfg["precompute"]
    st = settings_from_config(pre)
    if a.budget_scales:
        return budget_study(res, dump, vol, camera, sun, pre, st, [float(x) for x in a.budget_scales.split(",")],
                            a.budget_s)
    scene = (Scene(vol, Lighting(np.asarray(sun, np.float64), skylight_dome(sun, pre.get("skylight"))), st)
             if "node" in parts else None)
    for rep in range(2 if scene is not None else 0):
        t0 = time.perf_counter()
        vi = view_images(scene, camera, 0.5, 0.85, seed=0)
        res[f"node_s_{rep}"] = round(time.perf_counter() - t0, 2)
        res["node_stats"] = vi.stats
        res["node_sun_band_sums"] = [float(x) for x in vi.sun.sum((1, 2))]
        print(rep, res[f"node_s_{rep}"], vi.stats, flush=True)
        dump()
    if "precompute" in parts:
        t0 = time.perf_counter()
        tables = all_orders_precompute(vol, camera, sun, pre, st, pre["extinction"], pre["g"])
        res["precompute_main_job_s"] = round(time.perf_counter() - t0, 1)
        res["precompute_noise"] = tables.meta.get("pixel_relative_standard_error")
        res["precompute_budget_scale"] = tables.meta.get("budget_scale")
        dump()
    if "frames" not in parts:
        return
    day = cfg["shots"]["day_to_sunset"]
    cvol, _ = build_volume(cfg["volumes"]["cumulonimbus"], "cumulonimbus")
    cam = dict(day["keyframes"][0]["camera"])
    cam.setdefault("up", [0, 1, 0])
    state = shot_state(dict(PARAMS), 120.0, 30.0, cam)
    shot = {**day, "phase": "hg", "denoise": "none"}
    render_shot_frame(cvol, state, {**shot, "resolution": [32, 24], "render": {**shot["render"], "spp": 1}})
    for w, h in ((640, 480), (1920, 1080)):
        t0 = time.perf_counter()
        o = render_shot_frame(cvol, state, {**shot, "resolution": [w, h]})
        res[f"frame_{w}x{h}_s"] = round(time.perf_counter() - t0, 2)
        res[f"frame_{w}x{h}_parts"] = {k: round(v, 2) for k, v in o["timings"].items()}
        if w == 640:
            np.save(out / "frame640.npy", o["raw"].astype(np.float16))
        print(w, h, res[f"frame_{w}x{h}_s"], flush=True)
        dump()


def all_orders_precompute(vol, camera, sun, pre, settings, extinctions, gs):
    """The precompute of the validated ``precompute`` section ``pre`` with all-orders ``settings`` on a grid."""
    from natscene.scatter.tables import precompute
    return precompute(vol, camera, sun, extinctions=extinctions, gs=gs, seed=pre["seed"], step_voxels=pre["step_voxels"],
                      supersample=pre["supersample"], rho_threshold=pre["rho_threshold"], transport="all_orders",
                      all_orders=settings, skylight=pre.get("skylight"), log=print)


def budget_study(res, dump, vol, camera, sun, pre, st, scales, budget_s):
    """Noise figures (the meta's ``pixel_relative_standard_error``) and time of the precompute on the nodes
    (0.1 /m, 0.85) and (0.2 /m, 0.85) with the sun's and the sky's collision budgets (and photon caps) scaled; then the
    main job's whole grid at the largest scale when the two nodes' time, scaled to the grid, fits ``budget_s``."""
    import dataclasses

    def run(scale, extinctions, gs):
        scaled = dataclasses.replace(st, sun_collisions=int(st.sun_collisions * scale),
                                     sky_collisions=int(st.sky_collisions * scale),
                                     sun_photons_max=int(st.sun_photons_max * scale),
                                     sky_photons_max=int(st.sky_photons_max * scale))
        t0 = time.perf_counter()
        meta = all_orders_precompute(vol, camera, sun, pre, scaled, extinctions, gs).meta
        return (round(time.perf_counter() - t0, 1), {k: [round(v["median"], 4), round(v["p95"], 4)]
                                                      for k, v in meta["pixel_relative_standard_error"].items()},
                meta["photons"])

    run(0.05, [0.0, 0.1], [0.85])                         # compiles the kernels
    for scale in scales:
        s, noise, photons = run(scale, [0.0, 0.1, 0.2], [0.85])
        res[f"nodes_x{scale:g}"] = {"s": s, "noise": noise, "photons": photons}
        print(scale, s, noise, flush=True)
        dump()
    top = max(scales)
    nodes = sum(1 for x in pre["extinction"] if x > 0) * len(pre["g"])
    estimate = res[f"nodes_x{top:g}"]["s"] / 2 * nodes
    res["grid_estimate_s"] = round(estimate, 1)
    if estimate <= budget_s:
        s, noise, photons = run(top, pre["extinction"], pre["g"])
        res[f"grid_x{top:g}"] = {"s": s, "noise": noise, "photons": photons}
    dump()


if __name__ == "__main__":
    main()
