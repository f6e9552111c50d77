"""The shots' cache cells: error against volpath on the thick cumulonimbus, by cell size, raw and with OIDN.

The all-orders transport caches the orders <= 4 in cells of ``fine_voxels`` and the higher orders in cells of
``coarse_voxels`` (``shots.<name>.render``); coarse cells average the cloud's diffuse inside into its thin edges.
Renders the main job's cumulonimbus from the day shot's first camera at 160x120, sun only, at the kite fit's
0.0244 /m (g 0.70, beta 0.9999), with the day shot's render settings and each pair of cells of the arguments
(``fine,coarse`` or ``fine,coarse,collision_scale``), seeds 0 and 1, against the stored converged Mitsuba
``volpath`` render (tests/data/transport_volpath_thick.npz, ``cb_day``; tools/thick_references.py):

    .venv/bin/python experiments/shot_cells/run.py 2,4 2,2 1,1 1,1,0.61 [--seeds 0 1] [--sheet out.png]

Printed per render: seconds; raw and denoised (OIDN fed the view's opacity and normals) the relative RMSE per
pixel over the cloud (opacity >= 0.5, the reference's own noise taken out), of 8x8-block means, and the ratio to
volpath by opacity band (0.1-0.5, 0.5-0.9, 0.9-0.99, > 0.99). A setting that ends in ``:q`` (``2,2:q``) gathers
the caches as the view march did before it weighted the cells by their confidence: C and Q interpolated, then
divided (each cell weighted by its Q; ``natscene.scatter.inscatter.interpolation_fields``), one in ``:p`` weights
every cell the camera sees alike (by position alone). ``--sheet``: a PNG of
the cloud (cropped, enlarged 3 times) in the reference and in each setting's render of the first seed (one
exposure), and under each render its ratio to the reference (0.8 blue, 1 white, 1.2 red); the docs' image is
``run.py 2,2:q 2,2 --seeds 0 --sheet docs/img/precompute_cache_interpolation.png``.
Quoted in docs/stages/precompute.md.
"""
import argparse
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

import natscene.scatter.inscatter as inscatter
from natscene.config import load_yaml_config, validate_config
from natscene.denoise.features import view_features
from natscene.denoise.oidn import OIDN
from natscene.geometry import Camera
from natscene.io import to_srgb8, write_png
from natscene.scatter.allorders import frame_settings
from natscene.scatter.medium import make_medium
from natscene.scatter.reference_scene import NOSKY, band_ratios
from natscene.scatter.render import render
from natscene.scatter.single import march_view
from natscene.volume.build import build_volume

ROOT = Path(__file__).resolve().parents[2]


def _blocks(x: np.ndarray) -> np.ndarray:
    H, W = x.shape
    return x[:H // 8 * 8, :W // 8 * 8].reshape(H // 8, 8, W // 8, 8).mean((1, 3))


def _ratio_rgb(ratio: np.ndarray, cloud: np.ndarray) -> np.ndarray:
    """0.8 blue, 1 white, 1.2 red (display-encoded), grey outside the cloud."""
    t = np.clip((np.nan_to_num(ratio, nan=1.0) - 1.0) / 0.2, -1, 1)[..., None]
    white = np.ones(ratio.shape + (3,))
    rgb = np.where(t > 0, white + t * (np.array([1.0, 0.0, 0.0]) - white),
                   white - t * (np.array([0.0, 0.2, 1.0]) - white))
    return np.where(cloud[..., None], rgb, 0.5)


def _q_weighted(caches, denominators):
    """The fields of the view march that interpolates C and Q and divides (each cell weighted by its Q)."""
    return np.asarray(caches, np.float32), np.asarray(denominators, np.float32)[None]


def main(args, sheet=None, seeds=(0, 1)):
    confidence, scale = inscatter.interpolation_fields, inscatter.CONFIDENT_Q
    with np.load(ROOT / "tests" / "data" / "transport_volpath_thick.npz") as z:
        refs = {k: z[k] for k in z.files if k.startswith("cb_day")}
    cfg = validate_config(load_yaml_config(ROOT / "config" / "config.yaml"),
                          ROOT / "workflow" / "schemas" / "config.schema.yaml")
    vol, _ = build_volume(cfg["volumes"]["cumulonimbus"], "cumulonimbus")
    c = refs["cb_day.camera"]
    cam = Camera(tuple(c[0:3]), tuple(c[3:6]), tuple(c[6:9]), float(c[9]), int(c[10]), int(c[11]))
    sigma, g, beta = (float(x) for x in refs["cb_day.params"])
    p = dict(c_in=[1.0] * 3, L_in=1.0, g=g, extinction=sigma * vol.extinction_scale, beta=beta, kappa_a=[0.0] * 3,
             **NOSKY)
    ref = (refs["cb_day.half_a"].astype(np.float64) + refs["cb_day.half_b"]) / 2
    ref_noise = np.abs(refs["cb_day.half_a"].astype(np.float64) - refs["cb_day.half_b"]) / 2
    opacity = 1 - march_view(make_medium(vol), cam, [sigma])["T"][0]
    cloud = opacity >= 0.5
    full = _blocks(cloud.astype(float)) > 0.99
    alpha, normal, cover = view_features(vol, cam, sigma, 2, 1.0)
    oidn = OIDN(threads=2, quality="high")
    shot = cfg["shots"]["day_to_sunset"]["render"]
    level = ref[cloud].mean()
    exposure = 0.5 / np.percentile(ref[cloud], 90)
    rows, cols = np.nonzero(opacity >= 0.1)
    crop = np.s_[max(rows.min() - 4, 0):rows.max() + 5, max(cols.min() - 4, 0):cols.max() + 5]
    top, bottom = [to_srgb8(ref[crop][..., None], exposure)], [np.full(ref[crop].shape + (3,), 128, np.uint8)]
    for arg in args:
        spec, _, how = arg.partition(":")
        inscatter.interpolation_fields = _q_weighted if how == "q" else confidence
        inscatter.CONFIDENT_Q = 1e-30 if how == "p" else scale     # ":p": every cell with Q > 0 weighs 1
        fine, coarse, *scale = (float(x) for x in spec.split(","))
        st0 = frame_settings(shot)
        st = replace(st0, fine_voxels=int(fine), coarse_voxels=int(coarse),
                     sun_collisions=int(st0.sun_collisions * (scale[0] if scale else 1.0)))
        for seed in seeds:
            t0 = time.perf_counter()
            raw = render(vol, cam, refs["cb_day.sun"], p, np.zeros(3, np.float32), dict(shot, seed=seed),
                         skylight=False, all_orders=st)[..., 0]
            seconds = time.perf_counter() - t0
            den = oidn(np.repeat(raw[..., None], 3, -1).astype(np.float32),
                       np.repeat(alpha[..., None], 3, -1).astype(np.float32), normal).mean(-1)
            den = raw + cover * (den - raw)
            parts = []
            for name, img in (("raw", raw), ("oidn", den)):
                e2 = np.mean(((img - ref)[cloud] / level) ** 2) - np.mean((ref_noise[cloud] / level) ** 2)
                blocks = np.sqrt(np.mean(((_blocks(img) - _blocks(ref)) / _blocks(ref))[full] ** 2))
                bands = band_ratios(img, ref, opacity).values()
                parts.append(f"{name}: pixel {np.sqrt(max(e2, 0.0)):.4f}, blocks {blocks:.4f}, bands "
                             + " / ".join(f"{b:.3f}" for b in bands))
            print(f"cells {arg} seed {seed}: {seconds:.1f} s | " + " | ".join(parts), flush=True)
            if seed == seeds[0]:
                top.append(to_srgb8(raw[crop][..., None], exposure))
                bottom.append(np.round(_ratio_rgb(raw[crop] / ref[crop], opacity[crop] >= 0.1) * 255).astype(np.uint8))
    inscatter.interpolation_fields, inscatter.CONFIDENT_Q = confidence, scale
    if sheet:
        big = [[np.kron(a, np.ones((3, 3, 1), np.uint8)) for a in r] for r in (top, bottom)]
        gap = np.full((big[0][0].shape[0], 6, 3), 255, np.uint8)
        lines = [np.concatenate(sum([[a, gap] for a in r], [])[:-1], 1) for r in big]
        write_png(sheet, np.concatenate([lines[0], np.full((6, lines[0].shape[1], 3), 255, np.uint8), lines[1]]),
                  encoded=True)


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("settings", nargs="*", default=["2,4", "2,2"])
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1])
    ap.add_argument("--sheet")
    a = ap.parse_args()
    with np.errstate(divide="ignore", invalid="ignore"):  # the blocks outside the cloud are masked after dividing
        main(a.settings, a.sheet, tuple(a.seeds))
