"""Rule `point_scatter`: point cloud from the sun + scattering passes (Eqs. 1-5) for one volume and sun.
The `hg` variant uses a Henyey-Greenstein table with the Mie table's asymmetry (like-for-like comparison)."""
import time

from natscene.geometry import sun_direction
from natscene.io import write_png, write_yaml
from natscene.mie.phase import hg_table, read_table
from natscene.mie.points import generate_points
from natscene.mie.ratio_slice import ratio_image
from natscene.mie.solver import save_solution, solve
from natscene.runner import run
from natscene.volume.grid import load_volume


def main(snakemake, log):
    s = dict(snakemake.params.settings)
    sun = snakemake.params.sun
    phase = snakemake.wildcards.phase
    vol = load_volume(snakemake.input.meta.rsplit("/", 1)[0])
    table = read_table(snakemake.input.table)
    if phase.startswith("hg"):
        table = hg_table(float(table.g[1]))
    sd = sun_direction(sun["azimuth"], sun["elevation"])
    t = time.perf_counter()
    pts = generate_points(vol, sd, s["sigma_t"], s["spacing_voxels"], s["density_threshold"])
    log.info(f"{len(pts.density)} points on a {pts.shape} lattice (h = {pts.spacing:.4g}), "
             f"sigma_e {pts.sigma_e:.4g}, {time.perf_counter() - t:.1f} s")
    sol = solve(pts, table, s["passes"], s["radius"], s["coherence_scale"], s["albedo"], s["min_attenuation"],
                log=log.info)
    elapsed = time.perf_counter() - t
    log.info(f"solved in {elapsed:.1f} s")
    save_solution(snakemake.output.solution, sol)
    write_png(snakemake.output.ratio, ratio_image(sol), exposure=1.0)
    write_yaml(snakemake.output.summary, {
        "volume": snakemake.wildcards.volume, "sun": sun, "phase": phase, "points": len(pts.density),
        "lattice": list(pts.shape), "spacing": pts.spacing, "sigma_e": pts.sigma_e,
        "sun_in": pts.sun_in, "energy_per_pass_G": sol.energy[:, 1], "mean_ratio": float(sol.ratio.mean()),
        "settings": s})


run(snakemake, main)  # noqa: F821
