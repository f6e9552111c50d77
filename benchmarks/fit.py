"""Benchmark of the fit stage (issue 5): time per GA iteration (20 individuals, kappa_a search included) at
320x240, against rendering each candidate directly with the forward renderer (Dobashi: 0.1 s per iteration
on a GPU, ~6,000x faster than direct rendering).

Uses the real precompute of the main job (results/precompute/cumulus/kite) and the kite photo's sky products
when they exist, else a synthetic sphere table at 320x240 with the real ``natscene.scatter.compose``.
Writes results/benchmarks/fit.json.

    .venv/bin/python benchmarks/fit.py [--render-spp 16] [--iterations 30]
"""
from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))

from natscene.fit.genetic import run_ga  # noqa: E402
from natscene.fit.objective import Levels  # noqa: E402
from natscene.fit.problem import FitProblem  # noqa: E402
from natscene.io import read_exr, read_yaml, write_text  # noqa: E402


def synthetic(w=320, h=240):
    from natscene.fit.synthetic import gradient_sky, sphere_tables
    from natscene.scatter.tables import Tables

    t = sphere_tables(w, h)
    tab = Tables(t.extinction, t.g, t.orders, t.s_sun, t.s_amb, t.transmittance, t.multiple, t.t_c, t.cos_theta,
                 t.footprint)
    sky = gradient_sky(w, h)
    photo = sky.copy()
    photo[tab.footprint > 0.5] = 0.8
    return tab, sky, photo, tab.footprint > 0.5, np.array([1.0, 0.95, 0.85]), "synthetic sphere 320x240"


def real(results: Path):
    from natscene.scatter.tables import load_tables

    pre = results / "precompute" / "cumulus" / "kite"
    sky_dir = results / "sky" / "kite"
    tab = load_tables(pre)
    h, w = tab.t_c.shape
    photo = read_exr(sky_dir / f"{w}x{h}" / "photo_linear.exr").channel("R", "G", "B")
    label = read_exr(sky_dir / f"{w}x{h}" / "cloud_mask.exr").channel("label")
    sky = read_exr(sky_dir / f"{w}x{h}" / "sky.exr").channel("R", "G", "B")
    c_in = read_yaml(sky_dir / "sun.yaml")["c_in"]
    return tab, sky, photo, np.rint(label) == 1, np.asarray(c_in), f"main job precompute cumulus/kite {w}x{h}"


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--results", default=str(ROOT / "results"))
    ap.add_argument("--iterations", type=int, default=30)
    ap.add_argument("--render-spp", type=int, default=16)
    args = ap.parse_args()
    results = Path(args.results)
    try:
        tab, sky, photo, cloud, c_in, source = real(results)
    except Exception as e:  # noqa: BLE001 - fall back to the synthetic table
        print(f"no main-job precompute ({e}); using a synthetic table")
        tab, sky, photo, cloud, c_in, source = synthetic()
    from natscene.fit.settings import fit_settings
    from natscene.scatter.transport import of
    # the settings the fit composes with every candidate (all_orders: the calibrated dome, fit.ground_albedo)
    fixed = of(tab).fit_fixed(tab, sky, fit_settings(None), print)
    prob = FitProblem(tab, sky, photo, cloud, c_in, levels=Levels(256, "srgb"), fixed=fixed)
    ranges = {"g": (0.0, float(tab.g.max()))}
    # warm-up, then the GA with every criterion but n_max disabled
    run_ga(prob, ranges, names=prob.names, n_max=2, epsilon_o=0, n_suc=0)
    t0 = time.perf_counter()
    r = run_ga(prob, ranges, names=prob.names, n_max=args.iterations, epsilon_o=0, n_suc=0, seed=1)
    ga_s = time.perf_counter() - t0
    per_iter = ga_s / (r.iterations + 1)

    # components of one iteration: composition of 20 candidates, kappa search, full-image composition
    vals = np.array([[r.best.values[p] for p in prob.names]] * 20)
    reps = 10
    t0 = time.perf_counter()
    for _ in range(reps):
        lc = prob.cloud(vals)
    compose_s = (time.perf_counter() - t0) / reps
    t0 = time.perf_counter()
    for _ in range(reps):
        prob.search.search(lc)
    kappa_s = (time.perf_counter() - t0) / reps
    from natscene.fit.kappa import KappaSearch
    numpy_search = KappaSearch(prob.search.sky.T, prob.search.t_c, photo[cloud], backend="numpy")
    t0 = time.perf_counter()
    for _ in range(3):
        numpy_search.search(lc)
    kappa_numpy_s = (time.perf_counter() - t0) / 3
    from natscene.scatter.compose import compose_cloud
    params = {"c_in": c_in, **{p: vals[:, i] for i, p in enumerate(prob.names)}, **prob.fixed}
    t0 = time.perf_counter()
    for _ in range(3):
        compose_cloud(tab, params, sky)
    compose_full_s = (time.perf_counter() - t0) / 3

    # baseline: render one candidate directly with the forward renderer (no tables)
    render_s = None
    try:
        from natscene.geometry import Camera, sun_direction
        from natscene.scatter.render import render
        from natscene.volume.grid import load_volume
        from natscene.config import load_yaml_config, validate_config
        cfg = validate_config(load_yaml_config(ROOT / "config" / "config.yaml"),
                              ROOT / "workflow" / "schemas" / "config.schema.yaml")
        view = cfg["views"]["kite"]
        vol = load_volume(results / "volumes" / "cumulus")
        cam = Camera.from_view(view)
        sun = sun_direction(view["sun"]["azimuth"], view["sun"]["elevation"])
        one = {"c_in": c_in, **{p: float(vals[0, i]) for i, p in enumerate(prob.names)}, "kappa_a": r.best.kappa}
        render(vol, cam, sun, one, sky, {"orders": 4, "spp": 4})  # warm-up (kernel compilation)
        t0 = time.perf_counter()
        render(vol, cam, sun, one, sky, {"orders": 4, "spp": args.render_spp})
        render_s = time.perf_counter() - t0
    except Exception as e:  # noqa: BLE001
        print(f"direct render baseline unavailable: {e}")

    out = {
        "source": source,
        "pixels": {"image": list(tab.t_c.shape[::-1]), "synthetic_cloud": prob.n_pixels,
                   "photo_cloud": int(cloud.sum())},
        "population": 20, "kappa_samples": int(len(prob.search.kappas)), "n_levels": 256,
        "ga_iteration_s": per_iter, "ga_iterations_timed": r.iterations + 1,
        "target_iteration_s": 0.05, "dobashi_gpu_iteration_s": 0.1,
        "components_s": {"compose_20_at_footprint": compose_s, "kappa_search_20x3x11": kappa_s,
                         "kappa_search_backend": prob.search.backend, "kappa_search_numpy_backend": kappa_numpy_s,
                         "compose_20_full_image": compose_full_s},
        "fit_100_iterations_s_estimate": per_iter * 101,
    }
    if render_s is not None:
        out["direct_render"] = {"spp": args.render_spp, "orders": 4, "seconds_per_image": render_s,
                                "seconds_per_iteration_20": 20 * render_s,
                                "speedup": 20 * render_s / per_iter}
    path = results / "benchmarks" / "fit.json"
    write_text(path, json.dumps(out, indent=2) + "\n")
    print(json.dumps(out, indent=2))


if __name__ == "__main__":
    main()
