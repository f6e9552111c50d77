"""Rule `render_frame`: one frame of a shot (natscene.keyframes.frame.render_shot_frame): the forward renderer
in front of the analytic sky, the OIDN denoiser fed with the cloud's albedo/normal features, and for
`phase: mie_blend` the Mie/HG ratio of this sun's point-to-point solutions. Writes the frame (EXR R,G,B; for
mie_blend also its HG twin hg.R,hg.G,hg.B), the frame before the denoiser with the feature images
(`.raw.exr`); rule `frame_preview` draws its PNG."""
from pathlib import Path

import numpy as np

from natscene import io
from natscene.runner import run


def main(snakemake, log):
    from natscene.keyframes.frame import render_shot_frame
    from natscene.variant import select_variant
    from natscene.volume.grid import load_volume

    par = snakemake.params
    shot = dict(par.shot)
    variant = select_variant(threads=snakemake.threads)
    state = io.read_yaml(snakemake.input.state)
    for key in ("params", "sun", "camera"):
        if key not in (state or {}):
            raise io.InputError(f"{snakemake.input.state}: no '{key}'; rerun the interpolate rule")
    volume = load_volume(Path(snakemake.input.density).parent)
    name = snakemake.wildcards.shot
    denoiser = None
    if shot["denoise"] == "oidn":
        from natscene.denoise.oidn import OIDN
        denoiser = OIDN(key=f"shots.{name}.denoise", threads=snakemake.threads, quality=shot["denoiser"]["quality"])
    mie = None
    if shot["phase"] == "mie_blend":
        from natscene.mie.phase import hg_table, read_table
        from natscene.mie.solver import load_solution
        table = read_table(snakemake.input.table)
        mie = {"solution_mie": load_solution(snakemake.input.mie), "solution_hg": load_solution(snakemake.input.hg),
               "table_mie": table, "table_hg": hg_table(float(table.g[1])), "render": dict(par.mie_render)}
        ext = float(state["params"]["extinction"])
        log.info(f"mie_blend: sun {par.mie_sun} (frame az/el {state['sun']['azimuth']:.2f}/"
                 f"{state['sun']['elevation']:.2f}), droplet table {snakemake.input.table}, solver sigma_t "
                 f"{par.mie_sigma_t:g} (frame extinction {ext:.3g} /m)")
    r = shot["render"]
    w, h = shot["resolution"]
    log.info(f"frame {state['frame']} ({w}x{h}, {r['spp']} spp, orders {r['orders']}, {variant}, "
             f"phase {shot['phase']}, denoise {shot['denoise']}): sun az/el {state['sun']['azimuth']:.1f}/"
             f"{state['sun']['elevation']:.1f}")
    out = render_shot_frame(volume, state, shot, mie=mie, denoiser=denoiser, log=log.info)
    cam = state["camera"]
    attrs = {"shot": name, "frame": int(state["frame"]), "t": float(state["t"]), "keyframes": state["keyframes"],
             "params": state["params"], "sun": state["sun"], "camera": cam, "resolution": [int(w), int(h)],
             "fov_axis": "y", "render": dict(r), "sky": dict(shot["sky"]), "phase": shot["phase"],
             "denoise": shot["denoise"]}   # no timings: a rerun must write the same bytes (they go to the log)
    if mie is not None:
        attrs.update(mie_sun=par.mie_sun, mie_table=shot["mie_table"], mie_solver_sigma_t=par.mie_sigma_t)
    f = out["features"]
    chans, names = [out["final"]], ["R", "G", "B"]
    raw_chans, raw_names = [out["raw"]], ["R", "G", "B"]
    if mie is not None:
        chans.append(out["hg_final"])
        names += ["hg.R", "hg.G", "hg.B"]
        raw_chans += [out["hg_raw"], out["ratio"]]
        raw_names += ["hg.R", "hg.G", "hg.B", "mie_ratio.R", "mie_ratio.G", "mie_ratio.B"]
    raw_chans += [f["albedo"], f["normal"], f["opacity"][..., None], f["coverage"][..., None]]
    raw_names += ["albedo.R", "albedo.G", "albedo.B", "normal.X", "normal.Y", "normal.Z", "A", "coverage"]
    io.write_exr(snakemake.output.raw, np.concatenate(raw_chans, axis=-1), raw_names,
                 attrs={**attrs, "denoised": False}, stage="render_frame")
    io.write_exr(snakemake.output.exr, np.concatenate(chans, axis=-1), names,
                 attrs={**attrs, "denoised": shot["denoise"] != "none"}, stage="render_frame")
    log.info(f"mean RGB {np.round(out['final'].reshape(-1, 3).mean(0), 4).tolist()}; timings "
             f"{ {k: round(v, 2) for k, v in out['timings'].items()} }")


run(snakemake, main)
