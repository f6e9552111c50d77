"""Rule `mie_render`: one demo shot (glory / fogbow / silver lining) shaded with the Mie/isotropic blend
(Eqs. 6-8) beside the same view with Henyey-Greenstein (same marcher, same solver: like-for-like), and the
Mie render's single-scattering (direct sunlight) term on its own, where the glory and fogbow live."""
import numpy as np

from natscene.geometry import sun_direction
from natscene.io import to_srgb8, write_exr, write_png
from natscene.mie.demo import demo_camera, scattering_angle_at_centre
from natscene.mie.march import render_mie
from natscene.mie.phase import hg_table, read_table
from natscene.mie.solver import load_solution
from natscene.runner import run
from natscene.volume.grid import load_volume


def main(snakemake, log):
    demo, r = snakemake.params.demo, dict(snakemake.params.render)
    shot = snakemake.wildcards.shot
    vol = load_volume(snakemake.input.meta.rsplit("/", 1)[0])
    mie = read_table(snakemake.input.table)
    hg = hg_table(float(mie.g[1]))
    sd = sun_direction(demo["sun"]["azimuth"], demo["sun"]["elevation"])
    fov = demo["glory_fov"] if shot == "glory" else demo["fov"]
    cam = demo_camera(shot, vol, sd, demo["distance"], fov, demo["resolution"], demo["fogbow_angle"],
                      demo["silver_offset"])
    log.info(f"{shot}: scattering angle at the cloud centre {scattering_angle_at_centre(cam, sd):.1f} deg, "
             f"{cam.width}x{cam.height}")
    sky = np.broadcast_to(np.asarray(r["sky_color"], np.float32), (cam.height, cam.width, 3))
    imgs, terms = {}, {}
    for name, table, sol_path in (("mie", mie, snakemake.input.mie), ("hg", hg, snakemake.input.hg)):
        terms[name] = {}
        imgs[name] = render_mie(vol, cam, sd, load_solution(sol_path), table, r, sky, terms=terms[name])
        log.info(f"{name}: mean {imgs[name].mean(axis=(0, 1)).round(4).tolist()}, single scattering "
                 f"{terms[name]['direct'].mean(axis=(0, 1)).round(5).tolist()}")
    both = np.concatenate([imgs["mie"], imgs["hg"], terms["mie"]["direct"], terms["hg"]["direct"]], axis=-1)
    write_exr(snakemake.output.exr, both, ["mie.R", "mie.G", "mie.B", "hg.R", "hg.G", "hg.B", "mie_single.R",
                                           "mie_single.G", "mie_single.B", "hg_single.R", "hg_single.G",
                                           "hg_single.B"], stage="mie_render",
              attrs={"shot": shot, "render": r, "sun": demo["sun"], "hg_g": float(mie.g[1]), "fov": fov})
    # One exposure for the Mie and HG renders (the Mie render's), so the comparison is fair; the third
    # panel is the Mie render's single-scattering term alone, at its own exposure.
    from natscene.io import auto_exposure
    k = auto_exposure(imgs["mie"])
    gap = np.full((cam.height, 4, 3), 255, np.uint8)
    png = np.concatenate([to_srgb8(imgs["mie"], k), gap, to_srgb8(imgs["hg"], k), gap,
                          to_srgb8(terms["mie"]["direct"], auto_exposure(terms["mie"]["direct"]))], axis=1)
    write_png(snakemake.output.png, png, encoded=True)


run(snakemake, main)  # noqa: F821
