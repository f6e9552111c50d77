"""Rule leaf_season: seasonal maple leaf colour (Dong 2007 Ch. 4, Eqs. 4.3-4.8) with PROSPECT-D optics."""
import numpy as np

from natscene.config import settings_from_section
from natscene.io import write_exr, write_png, write_text
from natscene.leaves.season import SeasonParams, apply_case, normal_climate, parse_date, simulate_season, stage_days
from natscene.leaves.texture import base_map, leaf_texture, maple_mask, maple_venation
from natscene.runner import run


def main(snakemake, log):
    spec, case = snakemake.params.spec, snakemake.params.case
    normal = normal_climate(**spec["climate"])
    s = simulate_season(apply_case(normal, case), normal, settings_from_section(SeasonParams, spec["season"], "leaves.season"))
    log.info(f"climate {snakemake.wildcards.climate} ({case.get('kind')}): stages {stage_days(s)}")
    size = int(spec["size"])
    mask = maple_mask(size)
    ven = maple_venation(size)
    m, detail = base_map(mask, ven, seed=snakemake.params.seed)
    tiles = []
    for date, out in zip(snakemake.params.dates, snakemake.output.leaves):
        d = parse_date(date)
        c = (float(s.chlorophyll[d]), float(s.carotene[d]), float(s.anthocyanin[d]))
        tex = leaf_texture(*c, mask, m, detail, optics=spec["optics"])
        write_exr(out, tex, channels=["R", "G", "B", "A"], stage="leaf_season",
                  attrs={"date": str(date), "day": d, "c_ch": c[0], "c_ca": c[1], "c_an": c[2]})
        tiles.append(tex[..., :3])
    write_png(snakemake.output.strip, np.concatenate(tiles, axis=1), exposure=2.0)
    rows = ["day,chlorophyll,carotene,anthocyanin"] + [
        f"{d},{s.chlorophyll[d]:.5f},{s.carotene[d]:.5f},{s.anthocyanin[d]:.5f}" for d in range(365)]
    write_text(snakemake.output.csv, "\n".join(rows) + "\n")


run(snakemake, main)
