"""Converged Mitsuba 3 ``volpath`` renders of thick clouds (issue 39): tests/data/transport_volpath_thick.npz.

Three sun-only scenes, every scattering order (max_depth 100001, Russian roulette from depth 10000):

- ``blob_t100`` / ``blob_t300``: the all-orders tests' procedural heap (tests/test_transport.py, 48x36) at a
  mean optical depth over its cloud pixels of 100 and 300 (camera rays), g 0.85, beta 0.9999;
- ``cb_day``: the main job's cumulonimbus (config/config.yaml, seed 3) from the first camera of the
  ``day_to_sunset`` shot at 160x120 under the day sun (azimuth 120, elevation 30) at the kite fit's
  droplets (extinction 0.0244 /m, g 0.70, beta 0.9999): the converged reference of the equal-error comparison
  in benchmarks/thick_transport.py.

Each scene is rendered in chunks of independent seeds for a wall-clock budget; the file stores the two halves
(even and odd chunks) so that the reference's own noise is known. At these optical depths a volpath walk has
thousands of collisions: a GPU renders the set in a few minutes (cuda_ad_rgb), two CPU cores would need hours.

    .venv/bin/python tools/thick_references.py prepare DIR      # writes DIR/cases.npz (here)
    python3 tools/thick_references.py render DIR OUT [--budget S] # renders them (a GPU machine; numpy + mitsuba)
    .venv/bin/python tools/thick_references.py install OUT/refs.npz   # -> tests/data/transport_volpath_thick.npz
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
STORED = ROOT / "tests" / "data" / "transport_volpath_thick.npz"
BLOB_DEPTHS = (100.0, 300.0)
BLOB_G, BLOB_BETA = 0.85, 0.9999
CB = {"extinction": 0.0244, "g": 0.70, "beta": 0.9999, "azimuth": 120.0, "elevation": 30.0,
      "resolution": (160, 120)}
# seconds of the render budget per scene (fractions of --budget)
SHARE = {"blob_t100": 0.25, "blob_t300": 0.35, "cb_day": 0.40}


def mean_view_depth(vol, camera, mask_depth: float = 1e-3) -> float:
    """Mean optical depth per unit sigma_t over the camera rays that meet the cloud (4x4 rays per pixel)."""
    from natscene.scatter.medium import make_medium
    from natscene.scatter.single import march_view
    sigma = 1e-3
    T = march_view(make_medium(vol), camera, [sigma], supersample=4)["T"][0]
    tau = -np.log(np.clip(T, 1e-30, 1.0)) / sigma
    return float(tau[tau > mask_depth].mean())


def prepare(out_dir: Path) -> None:
    sys.path.insert(0, str(ROOT / "src"))
    import natscene  # noqa: F401
    from natscene.scatter.reference_scene import CAM, SUN, blob_volume

    from natscene.config import load_yaml_config, validate_config
    from natscene.geometry import sun_direction
    from natscene.keyframes.shot import frame_camera
    from natscene.volume.build import build_volume

    cases = {}
    blob = blob_volume()
    per_sigma = mean_view_depth(blob, CAM)
    for tau in BLOB_DEPTHS:
        cases[f"blob_t{tau:g}"] = dict(vol=blob, cam=CAM, sun=SUN, sigma=tau / per_sigma, g=BLOB_G, beta=BLOB_BETA)
    cfg = validate_config(load_yaml_config(ROOT / "config" / "config.yaml"),
                          ROOT / "workflow" / "schemas" / "config.schema.yaml")
    cb, _ = build_volume(cfg["volumes"]["cumulonimbus"], "cumulonimbus")
    cam = frame_camera(cfg["shots"]["day_to_sunset"]["keyframes"][0]["camera"], CB["resolution"])
    cases["cb_day"] = dict(vol=cb, cam=cam, sun=sun_direction(CB["azimuth"], CB["elevation"]),
                           sigma=CB["extinction"] / cb.extinction_scale, g=CB["g"], beta=CB["beta"])
    arrays = {}
    for name, c in cases.items():
        v, k = c["vol"], c["cam"]
        arrays.update({f"{name}.density": np.asarray(v.density, np.float32), f"{name}.bbox_min": v.bbox_min,
                       f"{name}.bbox_max": v.bbox_max, f"{name}.extinction_scale": v.extinction_scale,
                       f"{name}.camera": np.array([*k.position, *k.look_at, *k.up, k.fov, k.width, k.height]),
                       f"{name}.sun": np.asarray(c["sun"], np.float64),
                       f"{name}.params": np.array([c["sigma"], c["g"], c["beta"]])})
        print(f"{name}: sigma_t {c['sigma']:.4g} (extinction {c['sigma'] * v.extinction_scale:.4g} /unit), "
              f"{k.width}x{k.height}, density {v.density.shape}")
    out_dir.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(out_dir / "cases.npz", **arrays)


def _case(z, name):
    from types import SimpleNamespace
    c = z[f"{name}.camera"]
    cam = SimpleNamespace(position=c[0:3], look_at=c[3:6], up=c[6:9], fov=float(c[9]), width=int(c[10]),
                          height=int(c[11]))
    vol = SimpleNamespace(density=z[f"{name}.density"], bbox_min=z[f"{name}.bbox_min"],
                          bbox_max=z[f"{name}.bbox_max"], extinction_scale=float(z[f"{name}.extinction_scale"]))
    return vol, cam, z[f"{name}.sun"], z[f"{name}.params"]


def render(cases: Path, out: Path, budget: float, only: str | None = None, first_seed: int = 1000) -> None:
    from natscene.scatter.mitsuba_scene import mi, render_reference
    z = np.load(cases / "cases.npz")
    names = [only] if only else sorted({k.split(".")[0] for k in z.files})
    res = {"mitsuba": np.array(str(mi.__version__)), "variant": np.array(str(mi.variant()))}
    for name in names:
        vol, cam, sun, (sigma, g, beta) = _case(z, name)
        t_end = time.perf_counter() + budget * (1.0 if only else SHARE[name])
        halves, spp, seed, chunk, times = [0.0, 0.0], [0, 0], 0, 16, []
        while True:
            t0 = time.perf_counter()
            img = render_reference(vol, cam, sun, sigma, g, beta, orders=100_000, spp=chunk,
                                   seed=first_seed + seed)[..., 0]
            dt = time.perf_counter() - t0
            halves[seed % 2] = halves[seed % 2] + img.astype(np.float64) * chunk
            spp[seed % 2] += chunk
            times.append((chunk, dt))
            seed += 1
            left = t_end - time.perf_counter()
            if seed % 2 == 0 and left < 2.2 * dt:
                break
            if seed % 2 == 0 and dt < 0.1 * left:
                chunk = min(chunk * 2, 4096)
        a, b = halves[0] / spp[0], halves[1] / spp[1]
        m = (a + b) > 0
        print(f"{name}: {spp[0] + spp[1]} spp, halves' means {a[m].mean():.5g} / {b[m].mean():.5g}, "
              f"{sum(t for _, t in times):.0f} s ({times[-1][0]} spp in {times[-1][1]:.1f} s)", flush=True)
        res.update({f"{name}.half_a": a.astype(np.float32), f"{name}.half_b": b.astype(np.float32),
                    f"{name}.spp": np.array(spp), f"{name}.seconds": np.array(sum(t for _, t in times)),
                    f"{name}.params": np.array([sigma, g, beta]), f"{name}.sun": sun,
                    f"{name}.camera": z[f"{name}.camera"], "variant": np.array(str(mi.variant()))})
        out.mkdir(parents=True, exist_ok=True)
        np.savez_compressed(out / "refs.npz", **res)       # after each scene: a timeout keeps what is done


def install(refs: list[Path]) -> None:
    """Merge render outputs (the halves of a scene rendered in several runs weighted by their spp)."""
    merged: dict = {}
    for f in refs:
        with np.load(f, allow_pickle=True) as z:      # this tool's own output: the version strings
            new = {k: (np.array(str(z[k])) if z[k].dtype == object else z[k]) for k in z.files}
        for name in {k.split(".")[0] for k in new if k.endswith(".spp")}:
            if f"{name}.spp" not in merged:
                continue
            n_old, n_new = merged[f"{name}.spp"], new[f"{name}.spp"]
            for i, half in enumerate(("half_a", "half_b")):
                k = f"{name}.{half}"
                new[k] = ((merged[k] * n_old[i] + new[k] * n_new[i]) / (n_old[i] + n_new[i])).astype(np.float32)
            new[f"{name}.spp"] = n_old + n_new
            new[f"{name}.seconds"] = merged[f"{name}.seconds"] + new[f"{name}.seconds"]
        merged.update(new)
    tmp = STORED.with_suffix(".tmp.npz")
    np.savez_compressed(tmp, **merged)
    tmp.replace(STORED)
    with np.load(STORED) as z:
        for k in z.files:
            if k.endswith(".spp"):
                print(k, z[k], z[k.replace(".spp", ".seconds")])
    print(f"wrote {STORED}")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    p = sub.add_parser("prepare")
    p.add_argument("dir", type=Path)
    r = sub.add_parser("render")
    r.add_argument("dir", type=Path)
    r.add_argument("out", type=Path)
    r.add_argument("--budget", type=float, default=360.0, help="seconds of rendering for all scenes together")
    r.add_argument("--only", help="render this scene alone for the whole budget")
    r.add_argument("--first-seed", type=int, default=1000, help="seed of the first chunk (another run: another)")
    i = sub.add_parser("install")
    i.add_argument("refs", type=Path, nargs="+", help="render outputs; a scene in several is merged by spp")
    a = ap.parse_args()
    if a.cmd == "prepare":
        prepare(a.dir)
    elif a.cmd == "render":
        sys.path.insert(0, str(ROOT / "src"))
        render(a.dir, a.out, a.budget, a.only, a.first_seed)
    else:
        install(a.refs)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
