"""Benchmark: peak memory of every rule over several input sizes, and the fitted model of natscene.resources.

Each case is a small config (the smoke config with some sizes raised) run through Snakemake in a temporary
directory. Every job logs its exact peak resident memory (getrusage, natscene.runner); this script collects
those lines, computes each job's features with natscene.resources.job_features (the same function the
workflow uses to declare mem_mb), fits ``peak = base + sum coef * feature`` per rule by non-negative least
squares, and writes rows, fits and the ratio measured / declared to results/benchmarks/memory.json.

    .venv/bin/python benchmarks/memory.py [case ...]      # default: all cases (about 15-25 min on 2 cores)
    .venv/bin/python benchmarks/memory.py --merge case    # rerun some cases, keep the other rows of memory.json

Paste the printed MODEL into src/natscene/resources.py after a change to a stage's memory use.
"""
from __future__ import annotations

import copy
import json
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import yaml

from _common import ROOT, write_result
from natscene.config import load_yaml_config, validate_config
from natscene.resources import MARGIN, MODEL, SLACK_MB, estimate_mem_mb, job_features, model_mb

PEAK = re.compile(r"peak memory (\d+) MB(?: of mem_mb \d+)? \(rule (\w+)(?:, (.*))?\)")


def _smoke() -> dict:
    return load_yaml_config(ROOT / "config" / "smoke.yaml")


def _big_photo(tmp: Path, scale: int) -> str:
    """The kite photo resampled to ``scale`` x its size (a larger photo of the same content)."""
    import cv2

    from natscene import io
    ph = io.read_photo(ROOT / "resources" / "photos" / "kite_cumulus_left.jpg")
    big = cv2.resize(ph, (ph.shape[1] * scale, ph.shape[0] * scale), interpolation=cv2.INTER_CUBIC)
    out = tmp / f"kite_x{scale}.png"
    io.write_png(out, np.clip(big, 0, 1), exposure=1.0)
    return str(out)


def _npy_volume(tmp: Path, n: int, dtype=np.float32) -> str:
    from natscene.volume.procedural import generate
    d = generate("cumulus", (n, n // 2, n), seed=1)
    out = tmp / f"user_{n}_{np.dtype(dtype).name}.npy"
    np.save(out, np.asarray(d, dtype))
    return str(out)


def case_configs(tmp: Path) -> dict[str, tuple[dict, list[str]]]:
    """name -> (config, targets under results/)."""
    cases = {}
    base = _smoke()
    cases["smoke"] = (copy.deepcopy(base), [])  # every rule at the smallest sizes

    c = copy.deepcopy(base)
    c["volumes"]["tiny"].update(resolution=[128, 96, 128], blobs=40)
    c["views"]["tiny"]["resolution"] = [160, 120]
    c["sky"]["fit_resolutions"] = [[160, 120]]
    c["shots"]["tiny"].update(resolution=[160, 120], frames=2)
    c["shots"]["tiny"]["keyframes"][1]["at"] = 1
    c["composite"]["garden"].update(frames=[0], spp=2)  # at the shot's resolution
    c["tiles"]["grass"].update(path="resources/textures/grass_meadow_256.png", tile_size=80, sizes=[[1024, 1024]])
    c["patterns"]["tiny_spot"]["size"] = [256, 256]
    c["leaves"]["size"] = 128
    c["volumes"]["deck"]["resolution"] = [96, 24, 96]
    c["mie"]["demo"]["resolution"] = [160, 120]
    c["photos"]["kite"]["path"] = _big_photo(tmp, 2)
    cases["medium"] = (c, [])

    c = copy.deepcopy(base)
    c["volumes"]["tiny"].update(resolution=[256, 192, 256], blobs=40)
    c["views"]["tiny"]["resolution"] = [320, 240]
    c["shots"]["tiny"].update(resolution=[320, 240], frames=1, keyframes=[{"at": 0, "fit": None,
        "params": {"L_in": 3.0, "g": 0.8, "extinction": 0.3, "beta": 0.99, "L_amb": 0.1, "c_in": [1, 1, 1],
                   "kappa_a": 0.1}, "sun": {"azimuth": 130, "elevation": 35},
        "camera": {"position": [0.0, 1.7, -3000.0], "look_at": [0.0, 2200.0, 0.0], "fov": 36}}])
    c["tiles"]["grass"].update(sizes=[[4096, 4096]])
    c["patterns"]["tiny_spot"]["size"] = [549, 528]
    c["photos"]["kite"]["path"] = _big_photo(tmp, 4)
    c["composite"] = {}
    c["keyframes"] = {}
    c["mie"]["demo"]["volume"] = None
    targets = ["volumes/tiny/preview.png", "precompute/tiny/tiny/contact_sheet.png", "shots/tiny/frames/0000.png",
               "tiles/grass/synth_4096x4096.png", "patterns/tiny_spot/preview.png", "sky/kite/preview.png"]
    cases["large"] = (c, targets)

    # the main job's composite: a 640x480 shot frame at 4 spp, a 2048^2 ground, the main meadow (its flowers
    # all of one 549x528 pattern, its leaves of the smoke dates)
    c = copy.deepcopy(base)
    main = load_yaml_config(ROOT / "config" / "config.yaml")
    meadow = copy.deepcopy(next(iter(main["composite"].values()))["meadow"])
    for f in meadow["flowers"]:
        f["pattern"] = "tiny_spot"
    meadow["leaves"]["textures"] = copy.deepcopy(base["composite"]["garden"]["meadow"]["leaves"]["textures"])
    c["composite"]["garden"].update(frames=[0], spp=4, meadow=meadow)
    c["patterns"]["tiny_spot"]["size"] = [549, 528]
    c["leaves"]["size"] = main["leaves"]["size"]
    c["shots"]["tiny"].update(resolution=[640, 480], frames=1,
                              keyframes=[c["shots"]["tiny"]["keyframes"][1] | {"at": 0}])
    c["shots"]["tiny"]["keyframes"][0]["fit"] = None
    c["shots"]["tiny"]["keyframes"][0]["params"] = {"L_in": 3.0, "g": 0.8, "extinction": 0.3, "beta": 0.99,
                                                    "L_amb": 0.1, "c_in": [1, 1, 1], "kappa_a": 0.1}
    c["tiles"]["grass"]["sizes"] = [[2048, 2048]]
    c["composite"]["garden"]["ground"]["texture"] = {"product": "tiles/grass/synth_2048x2048.exr"}
    cases["composite"] = (c, ["composite/garden/0000/final.png", "composite/garden/0000/compare.png"])

    c = copy.deepcopy(base)
    c["volumes"]["tiny"].update(resolution=[512, 512, 512], blobs=40)
    cases["volume512"] = (c, ["volumes/tiny/preview.png"])

    for n, dtype in ((256, np.float32), (384, np.float32), (256, np.float64)):
        c = copy.deepcopy(base)
        c["volumes"]["tiny"] = {"kind": "file", "path": _npy_volume(tmp, n, dtype)}
        c["views"]["tiny"]["resolution"] = [64, 48]
        cases[f"npy{n}_{np.dtype(dtype).name}"] = (c, ["volumes/tiny/preview.png"] + (
            ["precompute/tiny/tiny/contact_sheet.png"] if n == 256 and dtype == np.float32 else []))

    # a large flower photo to recolour and a large ground texture file for the composite
    import cv2

    from natscene import io
    flower = io.read_photo(ROOT / "resources" / "photos" / "freshflower.jpg")
    big_flower = tmp / "flower_x3.png"
    io.write_png(big_flower, cv2.resize(flower, (1920, 1443), interpolation=cv2.INTER_CUBIC), exposure=1.0)
    grass = io.read_photo(ROOT / "resources" / "textures" / "grass_meadow_256.png")
    big_ground = tmp / "grass_4096.png"
    io.write_png(big_ground, np.tile(grass, (16, 16, 1)), exposure=1.0)
    c = copy.deepcopy(base)
    c["recolour"]["tiny_flower"]["photo"] = str(big_flower)
    c["shots"]["tiny"]["resolution"] = [320, 240]
    c["composite"]["garden"].update(frames=[0], spp=1, reference=False,
                                    ground={"texture": {"path": str(big_ground)}, "extent": [6.0, 6.0]})
    cases["big_images"] = (c, ["patterns/recolour/tiny_flower/recoloured.png", "composite/garden/0000/final.png"])

    # the main job's sizes: its cumulus and kite view at 256 spp (2 million paths per pass), a 640x480 frame
    main = load_yaml_config(ROOT / "config" / "config.yaml")
    c = copy.deepcopy(base)
    c["volumes"]["tiny"] = dict(main["volumes"]["cumulus"])
    c["views"]["tiny"] = dict(main["views"]["kite"])
    c["precompute"]["spp"] = 256
    c["shots"]["tiny"].update(resolution=[640, 480], frames=1, render={"spp": 16, "orders": 4},
                              keyframes=copy.deepcopy(cases["large"][0]["shots"]["tiny"]["keyframes"]))
    c["shots"]["tiny"]["keyframes"][0]["camera"] = dict(main["views"]["kite"]["camera"])
    c["composite"]["garden"]["frames"] = [0]
    cases["main_sizes"] = (c, ["precompute/tiny/tiny/contact_sheet.png", "shots/tiny/frames/0000.png"])
    return cases


def run_case(name: str, config: dict, targets: list[str], tmp: Path) -> tuple[dict, Path]:
    work = tmp / name
    work.mkdir(parents=True, exist_ok=True)
    cfg_path = work / "config.yaml"
    cfg_path.write_text(yaml.safe_dump(config, sort_keys=False))
    env = dict(os.environ, PYTHONPATH=str(ROOT / "src"), NATSCENE_MEMORY_MB=str(10 ** 7))
    cmd = [sys.executable, "-m", "snakemake", "-s", str(ROOT / "Snakefile"), "--configfile", str(cfg_path),
           "--directory", str(work), "--cores", "2", "--keep-going",
           *[f"results/{t}" for t in targets]]
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, env=env, capture_output=True, text=True)
    print(f"case {name}: exit {proc.returncode} in {time.perf_counter() - t0:.0f} s", flush=True)
    if proc.returncode:
        print(proc.stderr[-3000:])
    return validate_config(copy.deepcopy(config), ROOT / "workflow" / "schemas" / "config.schema.yaml"), work


def collect(config: dict, workdir: Path, case: str) -> list[dict]:
    rows = []
    for log in sorted(workdir.rglob("*.log")):
        for line in log.read_text(errors="replace").splitlines():
            m = PEAK.search(line)
            if not m:
                continue
            peak, rule = float(m.group(1)), m.group(2)
            wc = dict(kv.split("=", 1) for kv in (m.group(3) or "").split(", ") if "=" in kv)
            try:
                model, feats, _ = job_features(rule, config, wc, ROOT)
                declared, _ = estimate_mem_mb(rule, config, wc, ROOT)
            except (KeyError, TypeError) as e:
                print(f"  {rule} {wc}: no features ({e})")
                continue
            rows.append({"case": case, "rule": rule, "model": model, "wildcards": wc, "features": feats,
                         "peak_mb": peak, "declared_mb": declared})
    return rows


def fit(rows: list[dict]) -> dict:
    from scipy.optimize import nnls
    out = {}
    for model in sorted({r["model"] for r in rows}):
        rs = [r for r in rows if r["model"] == model]
        names = sorted({f for r in rs for f in r["features"]})
        A = np.array([[1.0] + [float(r["features"].get(f, 0.0)) for f in names] for r in rs])
        y = np.array([r["peak_mb"] for r in rs])
        scale = np.maximum(np.abs(A).max(0), 1e-12)
        # only features that vary across the measured sizes can be fitted
        varies = [0] + [j for j in range(1, A.shape[1]) if np.ptp(A[:, j]) > 0]
        coef = np.zeros(A.shape[1])
        sol, _ = nnls(A[:, varies] / scale[varies], y)
        coef[varies] = sol / scale[varies]
        out[model] = {"base": round(float(coef[0]), 1),
                      **{f: float(f"{coef[j + 1]:.4g}") for j, f in enumerate(names)}, "n": len(rs),
                      "max_abs_residual_mb": round(float(np.abs(A @ coef - y).max()), 1)}
    return out


def main(argv: list[str]) -> None:
    rows = []
    previous = ROOT / "results" / "benchmarks" / "memory.json"
    merge = argv[:1] == ["--merge"]
    argv = argv[1:] if merge else argv
    with tempfile.TemporaryDirectory(prefix="natscene-memory-") as d:
        tmp = Path(d)
        cases = case_configs(tmp)
        names = argv or list(cases)
        if merge and previous.is_file():
            rows = [r for r in json.loads(previous.read_text())["rows"] if r["case"] not in names and r["case"] in cases]
            for r in rows:  # features of the current natscene.resources
                cfg = validate_config(copy.deepcopy(cases[r["case"]][0]), ROOT / "workflow" / "schemas" /
                                      "config.schema.yaml")
                r["model"], r["features"], _ = job_features(r["rule"], cfg, r["wildcards"], ROOT)
                r["declared_mb"] = estimate_mem_mb(r["rule"], cfg, r["wildcards"], ROOT)[0]
        for name in names:
            config, targets = cases[name]
            cfg, work = run_case(name, config, targets, tmp)
            rows += collect(cfg, work, name)
    fitted = fit(rows)
    for r in rows:
        r["model_mb"] = round(model_mb(r["model"], r["features"]), 1)
    worst = max((r["peak_mb"] / r["declared_mb"] for r in rows), default=0.0)
    write_result("memory", {"margin": MARGIN, "slack_mb": SLACK_MB, "fitted": fitted, "current_model": MODEL,
                            "max_peak_over_declared": round(worst, 3), "rows": rows})
    print("\nMODEL = {  # bytes per unit / MB")
    for model, c in fitted.items():
        terms = ", ".join(f'"{k}": {v * 1024 * 1024:.4g} / MB' if k != "base" else f'"base": {v}'
                          for k, v in c.items() if k not in ("n", "max_abs_residual_mb"))
        print(f'    "{model}": {{{terms}}},  # n={c["n"]}, max residual {c["max_abs_residual_mb"]} MB')
    print("}")


if __name__ == "__main__":
    main(sys.argv[1:])
