"""Rule recolour: a flower photo recoloured with a pigment pattern in YIQ (Dong 2007 §3.5, Fig. 3.8)."""
import numpy as np
from skimage.transform import resize

from natscene.color import luminance
from natscene.io import read_photo, write_exr, write_png
from natscene.patterns.expression import express_rgb, precompute
from natscene.patterns.pigments import pigment
from natscene.patterns.presets import rd_params
from natscene.patterns.reaction_diffusion import normalise, simulate
from natscene.patterns.recolour import flower_mask, recolour
from natscene.patterns.venation import venation_from_photo
from natscene.runner import run


def main(snakemake, log):
    spec = snakemake.params.spec
    photo = read_photo(snakemake.input.photo)
    h, w = photo.shape[:2]
    mask = flower_mask(photo, spec["s_min"], spec["v_min"])
    sw = int(spec["sim_width"])
    sh = max(4, round(h * sw / w))
    small = resize(photo, (sh, sw, 3), anti_aliasing=True).astype(np.float32)
    msmall = (resize(mask, (sh, sw), order=0) > 0.5).astype(np.float32)
    ven = venation_from_photo(luminance(small), msmall, tuple(spec["root"]))
    log.info(f"photo {w}x{h}: flower {mask.mean():.0%} of pixels; simulation {sw}x{sh}, "
             f"{int(ven.vascular.sum())} vein pixels extracted")
    p = rd_params(spec["rd"], snakemake.params.seed, sh)
    r = simulate(msmall, ven, p, logger=log)
    maps = [normalise(r.a, msmall), normalise(r.b, msmall)]
    conc = np.stack([resize(c, (h, w), order=1) for c in maps], -1) * float(spec.get("concentration", 1.0))
    table = precompute([pigment(x) for x in spec["pigments"]])
    colour = express_rgb(table, conc)
    base = express_rgb(table, np.zeros(len(maps)))
    out = recolour(photo, colour, base, mask)
    write_exr(snakemake.output.exr, out, attrs={"rd": p.to_dict(), "pigments": table.names}, stage="recolour")
    write_png(snakemake.output.png, np.concatenate([photo, out], axis=1), exposure=1.0)


run(snakemake, main)
