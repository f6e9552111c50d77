"""Rule `render_frame`: one frame of a shot with the forward renderer (Dobashi Eqs. 3-9, no tables) in front of
the analytic sky; EXR (R,G,B) + PNG at the shot's fixed exposure."""
from pathlib import Path

import numpy as np

from natscene import io
from natscene.runner import run


def main(snakemake, log):
    from natscene.geometry import Camera
    from natscene.keyframes.sky import sky_image
    from natscene.scatter.render import render
    from natscene.variant import select_variant
    from natscene.volume.grid import load_volume

    par = snakemake.params
    variant = select_variant(threads=snakemake.threads)
    state = io.read_yaml(snakemake.input.state)
    for key in ("params", "sun", "camera"):
        if key not in (state or {}):
            raise io.InputError(f"{snakemake.input.state}: no '{key}'; rerun the interpolate rule")
    cam = state["camera"]
    w, h = par.resolution
    camera = Camera(tuple(cam["position"]), tuple(cam["look_at"]), tuple(cam["up"]), float(cam["fov"]), int(w), int(h))
    sun = np.asarray(state["sun"]["direction"], np.float64)
    volume = load_volume(Path(snakemake.input.density).parent)
    sky = sky_image(camera, sun, par.sky)
    p = {k: np.asarray(v, np.float64) for k, v in state["params"].items()}
    r = par.render
    log.info(f"frame {state['frame']} ({w}x{h}, {r['spp']} spp, orders {r['orders']}, {variant}): "
             f"sun az/el {state['sun']['azimuth']:.1f}/{state['sun']['elevation']:.1f}")
    img = render(volume, camera, sun, p, sky, orders=r["orders"], spp=r["spp"], seed=r["seed"],
                 step_voxels=r["step_voxels"], supersample=r["supersample"])
    attrs = {"shot": snakemake.wildcards.shot, "frame": int(state["frame"]), "t": float(state["t"]),
             "keyframes": state["keyframes"], "params": state["params"], "sun": state["sun"], "camera": cam,
             "render": dict(r), "sky": dict(par.sky)}
    io.write_exr(snakemake.output.exr, img, ["R", "G", "B"], attrs=attrs, stage="render_frame")
    io.write_png(snakemake.output.png, img, exposure=par.exposure)
    log.info(f"mean RGB {np.round(img.reshape(-1, 3).mean(0), 4).tolist()}")


run(snakemake, main)
