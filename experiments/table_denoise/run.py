"""Denoising the all-orders tables with OIDN: the error of a node at the collision budget against a 16x reference.

A route weighed for issue 39's precompute time: trace a node at its collision budget only (no noise-target
top-ups) and remove the noise with Intel Open Image Denoise (the ``RT`` filter of :mod:`natscene.denoise.oidn`,
fed with the node's opacity and normal images from :func:`natscene.denoise.features.view_features`), band image
by band image and half by half. Each node of the arguments (``extinction,g``, /m) of the main job's precompute
(``config/config.yaml``: the kite view of the cumulus, its all-orders settings) is traced at 1x and at 16x the
budget (independent seeds); the composed cloud pixel (single scattering + the sun's and the sky's multiple
scattering in luminance, as :func:`natscene.scatter.transport.all_orders.node_noise`) of the 1x run, raw and
denoised, is compared with the 16x run over the footprint:

    make run    # the main job's volumes (results/volumes/cumulus)
    .venv/bin/python experiments/table_denoise/run.py 0.02,0.75 0.01,0.9

Printed and written to results/experiments/table_denoise.json per node and albedo: the median and p95 relative
error against the reference, the median relative half-difference, the reference's own noise, the ratio of the
means, and the seconds of each run and of the denoising.
"""
import copy
import json
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from natscene.config import load_yaml_config, validate_config
from natscene.denoise.features import view_features
from natscene.denoise.oidn import OIDN
from natscene.geometry import Camera, sun_direction
from natscene.phase import hg
from natscene.scatter.allorders import Lighting, Scene, settings_from_config, view_images
from natscene.scatter.medium import make_medium
from natscene.scatter.single import march_view
from natscene.scatter.transport.all_orders import composed_halves, skylight_dome, sky_luminance_weights
from natscene.sky.daylight import skylight
from natscene.volume.grid import load_volume

ROOT = Path(__file__).resolve().parents[2]


def _denoised(vi, oidn, albedo, normal):
    """The node's band images, each half and band denoised on its own (grey in all three channels)."""
    out = copy.deepcopy(vi)
    grey = lambda img: np.repeat(img[..., None], 3, -1).astype(np.float32)  # noqa: E731
    for h in range(2):
        for b in range(out.sun_halves.shape[1]):
            out.sun_halves[h, b] = oidn(grey(vi.sun_halves[h, b]), albedo, normal).mean(-1)
        for c in range(out.sky_halves.shape[1]):
            for b in range(out.sky_halves.shape[2]):
                out.sky_halves[h, c, b] = oidn(grey(vi.sky_halves[h, c, b]), albedo, normal).mean(-1)
    return out


def main(args):
    cfg = validate_config(load_yaml_config(ROOT / "config/config.yaml"), ROOT / "workflow/schemas/config.schema.yaml")
    pre, view = cfg["precompute"], cfg["views"]["kite"]
    volume = load_volume(ROOT / "results/volumes/cumulus")
    camera = Camera.from_view(view)
    med = make_medium(volume, sun_direction(view["sun"]["azimuth"], view["sun"]["elevation"]))
    st = replace(settings_from_config(pre), noise_target=(0.0, 0.0))
    nodes = [tuple(float(x) for x in a.split(",")) for a in args] or [(0.02, 0.75)]
    sigmas = np.array([e / volume.extinction_scale for e, _ in nodes])
    single = march_view(med, camera, sigmas, step_voxels=pre["step_voxels"], supersample=pre["supersample"],
                        rho_threshold=pre["rho_threshold"])
    dome = skylight_dome(med.sun_dir, skylight(pre["skylight"], "precompute.skylight"))
    s_dir = np.asarray(med.sun_dir)
    sky_w = sky_luminance_weights(s_dir, dome)
    cos_q = camera.ray_directions() @ s_dir
    foot = single["footprint"] > 0
    oidn = OIDN(threads=2, quality="high")
    out = {}
    for n, (e, g) in enumerate(nodes):
        runs = {}
        for scale in (1, 16):
            scene = Scene(volume, Lighting(s_dir, dome), replace(
                st, sun_collisions=st.sun_collisions * scale, sky_collisions=st.sky_collisions * scale,
                sun_photons_max=st.sun_photons_max * scale, sky_photons_max=st.sky_photons_max * scale))
            t0 = time.perf_counter()
            runs[scale] = (view_images(scene, camera, float(sigmas[n]), g, seed=11 + scale), time.perf_counter() - t0)
        opacity, normal, _ = view_features(volume, camera, float(sigmas[n]), 2, 1.0)
        t0 = time.perf_counter()
        den = _denoised(runs[1][0], oidn, np.repeat(opacity[..., None], 3, -1), normal)
        row = {"seconds_1x": round(runs[1][1], 1), "seconds_16x": round(runs[16][1], 1),
               "seconds_denoise": round(time.perf_counter() - t0, 1)}
        single_sun = hg(cos_q, g) * single["S_sun"][n]
        for beta in (0.9, 0.999):
            def pixel(vi):  # noqa: B023
                ms = composed_halves(vi, st.sun_bands, st.sky_bands, sky_w, beta)["sun_and_sky"]
                return [beta * single_sun + m for m in ms]
            r0, r1 = pixel(runs[16][0])
            ref = (r0 + r1) / 2
            ok = foot & (ref > 0)
            for name, vi in (("raw", runs[1][0]), ("oidn", den)):
                a0, a1 = pixel(vi)
                err = (np.abs((a0 + a1) / 2 - ref) / ref)[ok]
                row[f"{name}.beta{beta:g}"] = {
                    "error_median": round(float(np.median(err)), 4), "error_p95": round(float(np.percentile(err, 95)), 4),
                    "halves_median": round(float(np.median((np.abs(a0 - a1) / 2 / ref)[ok])), 4),
                    "reference_noise_median": round(float(np.median((np.abs(r0 - r1) / 2 / ref)[ok])), 4),
                    "mean_ratio": round(float(((a0 + a1) / 2)[ok].sum() / ref[ok].sum()), 4)}
        out[f"{e:g}/m, g {g:g}"] = row
        print(f"{e:g}/m, g {g:g}:", json.dumps(row), flush=True)
    dest = ROOT / "results/experiments/table_denoise.json"
    dest.parent.mkdir(parents=True, exist_ok=True)
    dest.write_text(json.dumps(out, indent=1))


if __name__ == "__main__":
    with np.errstate(divide="ignore", invalid="ignore"):  # pixels off the footprint are masked after dividing
        main(sys.argv[1:])
