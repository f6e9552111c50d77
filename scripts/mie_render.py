"""Rule `mie_render`: one demo shot (glory / fogbow / silver lining) shaded with the Mie/isotropic blend
(Eqs. 6-8) beside the same view with Henyey-Greenstein (same marcher, same solver, same exposure: like-for-
like), and the Mie render's single-scattering (direct sunlight) term on its own. Glory and fogbow look at a
thin deck of narrow droplets with the sun behind the camera; the silver lining looks at the sun hidden just
behind the demo volume's upper edge. The summary holds the measured glory-ring contrast (Mie vs HG) and the
silver-lining rim peak ratio."""
import numpy as np

from natscene.geometry import sun_direction
from natscene.io import auto_exposure, to_srgb8, write_exr, write_png, write_yaml
from natscene.mie.cameras import deck_camera, effect_camera, scattering_angle_at_centre, silver_lining_camera
from natscene.mie.march import render_mie
from natscene.mie.measure import angular_profile, rim_peak, ring_contrast
from natscene.mie.phase import fogbow_peak_deg, glory_ring_deg, hg_table, read_table
from natscene.mie.solver import load_solution
from natscene.runner import run
from natscene.volume.grid import load_volume


def main(snakemake, log):
    demo, r = snakemake.params.demo, dict(snakemake.params.render)
    name = snakemake.wildcards.shot
    shot = demo[name]
    for k in ("L_amb", "sky_color"):
        if shot[k] is not None:
            r[k] = shot[k]
    vol = load_volume(snakemake.input.meta.rsplit("/", 1)[0])
    mie = read_table(snakemake.input.table)
    hg = hg_table(float(mie.g[1]))
    sols = {"mie": load_solution(snakemake.input.mie), "hg": load_solution(snakemake.input.hg)}
    sd = sun_direction(demo["sun"]["azimuth"], demo["sun"]["elevation"])
    res = demo["resolution"]
    if name == "silver_lining":
        cam = silver_lining_camera(vol, sd, sols["mie"].points.sigma_e, shot["distance"], shot["fov"], res,
                                   shot["edge_deg"], shot["hide_tau"])
    elif shot["cloud"] == "deck":
        cam = deck_camera(name, vol, sd, shot["distance"], shot["fov"], res, shot["angle"])
    else:
        cam = effect_camera(name, vol, sd, shot["distance"], shot["fov"], res, fogbow_angle=shot["angle"])
    log.info(f"{name}: {shot['cloud']} cloud, droplets {shot['droplets'] or 'default'}, scattering angle at "
             f"the view centre {scattering_angle_at_centre(cam, sd):.1f} deg, {cam.width}x{cam.height}")
    sky = np.broadcast_to(np.asarray(r["sky_color"], np.float32), (cam.height, cam.width, 3))
    imgs, terms = {}, {}
    for ph, table in (("mie", mie), ("hg", hg)):
        terms[ph] = {}
        imgs[ph] = render_mie(vol, cam, sd, sols[ph], table, r, sky, terms=terms[ph])
        log.info(f"{ph}: mean {imgs[ph].mean(axis=(0, 1)).round(4).tolist()}, single scattering "
                 f"{terms[ph]['direct'].mean(axis=(0, 1)).round(5).tolist()}")
    summary = {"shot": name, "cloud": shot["cloud"], "droplets": mie.meta, "hg_g": float(mie.g[1]),
               "glory_first_ring_deg_rgb": glory_ring_deg(mie), "fogbow_peak_deg_rgb": fogbow_peak_deg(mie),
               "single_scattering_share_mie": float(terms["mie"]["direct"].mean() / imgs["mie"].mean())}
    if name == "glory":  # the ring around the antisolar point, full renders
        for ph in ("mie", "hg"):
            c, prof = angular_profile(imgs[ph], cam, -sd, min(4.0, shot["fov"] / 2), 0.1)
            ang, con = ring_contrast(c, prof)
            summary[f"ring_{ph}"] = {"angle_from_antisolar_deg": ang, "contrast": con}
        log.info(f"glory ring (full render): Mie {summary['ring_mie']}, HG {summary['ring_hg']}")
    if name == "silver_lining":
        summary["rim_peak_mie"], summary["rim_peak_hg"] = rim_peak(imgs["mie"]), rim_peak(imgs["hg"])
        summary["rim_peak_ratio"] = summary["rim_peak_mie"] / summary["rim_peak_hg"]
        log.info(f"silver lining rim peak Mie/HG = {summary['rim_peak_ratio']:.2f}")
    both = np.concatenate([imgs["mie"], imgs["hg"], terms["mie"]["direct"], terms["hg"]["direct"]], axis=-1)
    write_exr(snakemake.output.exr, both, ["mie.R", "mie.G", "mie.B", "hg.R", "hg.G", "hg.B", "mie_single.R",
                                           "mie_single.G", "mie_single.B", "hg_single.R", "hg_single.G",
                                           "hg_single.B"], stage="mie_render",
              attrs={"shot": name, "render": r, "sun": demo["sun"], "hg_g": float(mie.g[1]), "fov": shot["fov"]})
    # One exposure for the Mie and HG renders (the Mie render's), so the comparison is fair; the third
    # panel is the Mie render's single-scattering term alone, at its own exposure.
    k = auto_exposure(imgs["mie"])
    summary["exposure"] = k
    gap = np.full((cam.height, 4, 3), 255, np.uint8)
    png = np.concatenate([to_srgb8(imgs["mie"], k), gap, to_srgb8(imgs["hg"], k), gap,
                          to_srgb8(terms["mie"]["direct"], auto_exposure(terms["mie"]["direct"]))], axis=1)
    write_png(snakemake.output.png, png, encoded=True)
    write_yaml(snakemake.output.summary, summary)


run(snakemake, main)  # noqa: F821
