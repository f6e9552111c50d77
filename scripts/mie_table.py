"""Rule `mie_table`: the Mie phase table of cloud droplets (RGB + spectral) with the plots of Fig. 3."""
from natscene.io import write_yaml
from natscene.mie.phase import (compute_mie_table, fogbow_peak_deg, glory_ring_deg, hg_table, plot_table,
                                write_table)
from natscene.runner import run


def main(snakemake, log):
    s = dict(snakemake.params.settings)
    log.info(f"Mie table: r_eff {s['r_eff_um']} µm, v_eff {s['v_eff']}, {s['n_radii']} radii, "
             f"{len(s['spectral_nm'])} spectral wavelengths")
    table = compute_mie_table(s["r_eff_um"], s["v_eff"], s["n_radii"], spectral_nm=tuple(s["spectral_nm"]),
                              log=log.info)
    g = table.g
    log.info(f"asymmetry g (R, G, B) = {g.round(4).tolist()}")
    write_table(snakemake.output.table, table)
    plot_table(table, snakemake.output.cartesian, snakemake.output.polar, hg=hg_table(float(g[1])))
    write_yaml(snakemake.output.summary, {
        **table.meta, "g_rgb": g, "fogbow_peak_deg_rgb": fogbow_peak_deg(table),
        "glory_first_ring_deg_rgb": glory_ring_deg(table), "n_angles": len(table.theta),
        "spectral_nm": list(s["spectral_nm"])})


run(snakemake, main)  # noqa: F821
