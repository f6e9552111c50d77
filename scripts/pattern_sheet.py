"""Rule pattern_sheet: one preview sheet of all configured pigment patterns (Dong 2007 Fig. 3.3 layout): a row
per pattern with its name, pigment map 0 and map 1 (dark = more pigment, Dong's convention) and the colour."""
import numpy as np

from natscene.color import linear_to_srgb
from natscene.io import read_exr, write_png
from natscene.preview import label
from natscene.runner import run


def _caption(text: str, h: int, w: int = 150) -> np.ndarray:
    """A caption cell (h, w, 3) in [0, 1]: the pattern's name on black."""
    return label(np.zeros((h, w, 3), np.uint8), text.replace("_", " "), "caption").astype(np.float32) / 255.0


def main(snakemake, log):
    names = snakemake.params.names
    rows = []
    for k, name in enumerate(names):
        maps = [read_exr(f) for f in snakemake.input.maps[2 * k: 2 * k + 2]]
        mask = maps[0].channel("A")[..., None]
        col = read_exr(snakemake.input.colors[k])
        rgb = np.stack([col.channel(c) for c in "RGB"], -1)
        cells = [np.repeat((1.0 - m.channel("c"))[..., None], 3, -1) * mask for m in maps]
        cells.append(linear_to_srgb(np.clip(rgb, 0, 1)) * mask)
        pad = ((4, 4), (4, 4), (0, 0))
        rows.append(np.concatenate([np.pad(_caption(name, mask.shape[0]), pad)] + [np.pad(c, pad) for c in cells],
                                   axis=1))
        c0 = maps[0].channel("c")[mask[..., 0] > 0]
        log.info(f"{name}: map 0 c in [{c0.min():.3f}, {c0.max():.3f}]")
    width = max(r.shape[1] for r in rows)
    sheet = np.concatenate([np.pad(r, ((0, 0), (0, width - r.shape[1]), (0, 0))) for r in rows], axis=0)
    write_png(snakemake.output[0], sheet, encoded=True)


run(snakemake, main)
