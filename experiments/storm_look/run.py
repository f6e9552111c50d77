"""What sets the day storm cloud's contrast: frame 0 of ``day_to_sunset`` under changes of its light and droplets.

Issue 39 asks for the ``day_to_sunset`` cumulonimbus to read as a dense storm cloud (shaded sides and base clearly
darker than the sunlit towers); at the physical extinction it still reads as a bright cumulus. Which part of the
frame's light flattens it? Frame 0's interpolated state (``results/shots/day_to_sunset/params/0000.yaml``: the kite
fit's droplets at the storm cloud's 0.0244 /m, the sun at azimuth 60 and elevation 30) is rendered with the shot's
render settings (HG phase, no denoiser) at 320x240 for each variant, given as ``name=JSON`` with the keys
``sun`` ([azimuth, elevation]), ``params`` (frame parameters: ``extinction``, ``g``, ...), ``render`` (the shot's
``render:`` keys, e.g. ``ground_albedo``) and ``sky`` (the shot's ``sky:`` keys, e.g. a black constant sky):

    make run    # the main job's volumes and frame states
    .venv/bin/python experiments/storm_look/run.py 'defaults={}' 'no_ground={"render": {"ground_albedo": 0}}' \
        'sun_only={"sky": {"model": "constant", "color": [0, 0, 0]}}' 'side_sun={"sun": [90, 30]}'

Per variant it prints the luminance of the opaque cloud pixels (opacity > 0.99): the 5th, 50th and 95th
percentile, their contrast p5 / p95, the share above 1 (clipped by the PNG preview), the mean of the top 30 % and
the bottom 15 % of the cloud's rows (its top: the anvil, and its base) and the sky beside the cloud. Written to
``results/experiments/storm_look.json`` and ``results/experiments/storm_look/<name>.png`` (the cloud's crop at the
shot's exposure) and ``sheet.png`` (the crops side by side, 3x).
"""
import argparse
import copy
import json
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "benchmarks"))

from natscene import io  # noqa: E402
from natscene.color import luminance  # noqa: E402
from natscene.config import load_yaml_config, validate_config  # noqa: E402
from natscene.io import write_png  # noqa: E402
from natscene.keyframes.frame import render_shot_frame  # noqa: E402
from natscene.variant import select_variant  # noqa: E402
from natscene.volume.grid import load_volume  # noqa: E402
from shots import shot_state  # noqa: E402


def look(img: np.ndarray, opacity: np.ndarray) -> dict:
    """Luminance statistics of the opaque cloud pixels (above)."""
    y = luminance(img[..., :3])
    m = opacity > 0.99
    rows = np.where(m.any(1))[0]
    r0, r1 = rows.min(), rows.max()
    h = r1 - r0 + 1
    top, base = m.copy(), m.copy()
    top[r0 + int(0.3 * h):] = False
    base[:r1 - int(0.15 * h)] = False
    beside = opacity < 0.01
    beside[:r0], beside[r1:] = False, False
    p5, p50, p95 = (float(v) for v in np.percentile(y[m], [5, 50, 95]))
    return {"opaque_pixels": int(m.sum()), "p5": round(p5, 4), "p50": round(p50, 4), "p95": round(p95, 4),
            "contrast_p5_p95": round(p5 / p95, 3), "clipped": round(float(np.mean(img[m].max(-1) > 1)), 3),
            "top": round(float(y[top].mean()), 4), "base": round(float(y[base].mean()), 4),
            "base_over_top": round(float(y[base].mean() / y[top].mean()), 3),
            "sky_beside": round(float(y[beside].mean()), 4) if beside.any() else None}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("variants", nargs="+", help="name=JSON (keys sun, params, render, sky)")
    ap.add_argument("--results", default=str(ROOT / "results"))
    ap.add_argument("--resolution", type=int, nargs=2, default=[320, 240])
    a = ap.parse_args()
    select_variant(threads=2)
    cfg = load_yaml_config(ROOT / "config" / "config.yaml")
    validate_config(cfg, ROOT / "workflow" / "schemas" / "config.schema.yaml")
    day = cfg["shots"]["day_to_sunset"]
    res = Path(a.results)
    state_f = res / "shots" / "day_to_sunset" / "params" / "0000.yaml"
    vol_dir = res / "volumes" / day["volume"]
    if not state_f.exists() or not (vol_dir / "meta.yaml").exists():
        raise SystemExit(f"{state_f} or {vol_dir}: missing; run make run first")
    cloud = load_volume(vol_dir)
    base_state = io.read_yaml(state_f)
    shot = {**day, "phase": "hg", "denoise": "none", "resolution": list(a.resolution)}
    out_dir = res / "experiments" / "storm_look"
    out_dir.mkdir(parents=True, exist_ok=True)
    rows, crops = [], []
    for arg in a.variants:
        name, _, text = arg.partition("=")
        over = json.loads(text or "{}")
        unknown = set(over) - {"sun", "params", "render", "sky"}
        if unknown:
            raise SystemExit(f"{name}: unknown keys {sorted(unknown)} (sun, params, render, sky)")
        state = copy.deepcopy(base_state)
        if "sun" in over:
            az, el = (float(v) for v in over["sun"])
            state.update(shot_state(state["params"], az, el, state["camera"]))
        state["params"].update(over.get("params", {}))
        frame = {**shot, "render": {**shot["render"], **over.get("render", {})},
                 "sky": {**shot["sky"], **over.get("sky", {})}}
        t0 = time.perf_counter()
        out = render_shot_frame(cloud, state, frame, denoiser=None)
        seconds = round(time.perf_counter() - t0, 1)
        img, opacity = out["final"], out["features"]["opacity"]
        row = {"name": name, "overrides": over, "seconds": seconds, **look(img, opacity)}
        print(json.dumps(row), flush=True)
        rows.append(row)
        rr, cc = np.where((opacity > 0.01).any(1))[0], np.where((opacity > 0.01).any(0))[0]
        crop = img[max(rr.min() - 6, 0):rr.max() + 6, max(cc.min() - 6, 0):cc.max() + 6, :3]
        write_png(out_dir / f"{name}.png", crop, exposure=float(day["exposure"]))
        crops.append(crop)
    h = max(c.shape[0] for c in crops)
    parts = []
    for c in crops:                                   # the crops padded to one height, 4 black columns apart
        if parts:
            parts.append(np.zeros((h, 4, 3), np.float32))
        parts.append(np.pad(c, ((0, h - c.shape[0]), (0, 0), (0, 0))))
    sheet = np.concatenate(parts, axis=1)
    write_png(out_dir / "sheet.png", np.repeat(np.repeat(sheet, 3, 0), 3, 1), exposure=float(day["exposure"]))
    (res / "experiments" / "storm_look.json").write_text(json.dumps(rows, indent=1) + "\n")
    print(f"wrote {res / 'experiments' / 'storm_look.json'} and {out_dir}/")


if __name__ == "__main__":
    main()
