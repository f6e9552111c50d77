"""Rule recolour: a flower photo recoloured with a pigment pattern in YIQ (Dong 2007 §3.5, Fig. 3.8)."""
import numpy as np

from natscene.io import write_exr, write_png
from natscene.patterns.recolour import recolour_photo
from natscene.runner import run


def main(snakemake, log):
    res = recolour_photo(snakemake.input.photo, snakemake.params.spec, snakemake.params.seed, logger=log)
    st = res["stats"]
    log.info(f"flower {res['mask'].mean():.0%} of the photo; simulation {st['sim'][0]}x{st['sim'][1]}: vein tree "
             f"{st['vein_cells']} cells, {st['vein_paths']} root-to-tip paths; reaction-diffusion {st['rd_steps']} "
             f"steps (converged {st['rd_converged']})")
    log.info(f"pigment map 0: vein mean {st['map0_vein']:.3f}, inter-vein mean {st['map0_intervein']:.3f}, "
             f"range {st['map0_range'][0]:.3f}..{st['map0_range'][1]:.3f}; hue {st['hue_photo_deg']:.0f} -> "
             f"{st['hue_result_deg']:.0f} deg (shift {st['hue_shift_deg']:.0f}), chroma {st['chroma_photo']:.1f} -> "
             f"{st['chroma_result']:.1f}")
    write_exr(snakemake.output.exr, res["result"],
              attrs={"rd": res["params"].to_dict(), "pigments": res["pigments"], "stats": st}, stage="recolour")
    write_png(snakemake.output.png, np.concatenate([res["photo"], res["result"]], axis=1), exposure=1.0)


run(snakemake, main)
