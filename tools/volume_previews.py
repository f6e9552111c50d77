"""Docs figure: the rendered previews of the main job's volumes (cumulus, cumulonimbus, the Mie stratocumulus deck)
and a cumulus field at the paper's 402x66x402 box at half size, beside the previous smooth generator's cumulus and
cumulonimbus rendered the same way. Writes docs/img/volume_kinds.png.

    .venv/bin/python tools/volume_previews.py [config/config.yaml] [out.png]
"""
import sys
from pathlib import Path

import numpy as np
import yaml
from PIL import Image, ImageDraw

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))

from natscene.io import to_srgb8  # noqa: E402
from natscene.volume.build import build_volume  # noqa: E402
from natscene.volume.grid import Volume, mean_optical_depth, placement  # noqa: E402
from natscene.volume.metaballs import generate_smooth  # noqa: E402
from natscene.volume.preview import optical_depth_projections, preview_sheet, rendered_look  # noqa: E402


def sheet(vol: Volume) -> Image.Image:
    front, top = optical_depth_projections(vol.density, float(vol.voxel_size[0]), vol.extinction_scale)
    img = preview_sheet(rendered_look(vol), front, top)
    return Image.fromarray((np.clip(img, 0, 1) * 255 + 0.5).astype(np.uint8))


def old_look(kind: str, res, seed: int, size: float) -> Image.Image:
    d = generate_smooth(kind, res, seed=seed)
    lo, hi = placement(res, size)
    scale = 60.0 / mean_optical_depth(d, float((hi - lo)[2] / d.shape[0]), axis=0)
    look = rendered_look(Volume(d, lo, hi, scale))
    return Image.fromarray(to_srgb8(look, "auto"))


def label(im: Image.Image, text: str) -> Image.Image:
    out = Image.new("RGB", (im.width, im.height + 14), "white")
    out.paste(im, (0, 14))
    ImageDraw.Draw(out).text((2, 1), text, fill=(0, 0, 0))
    return out


def scaled(im: Image.Image, k: float) -> Image.Image:
    return im.resize((int(im.width * k), int(im.height * k)), Image.LANCZOS)


def main(config="config/config.yaml", out="docs/img/volume_kinds.png"):
    vols = yaml.safe_load((ROOT / config).read_text())["volumes"]
    field = {"kind": "cumulus_field", "resolution": [201, 33, 201], "seed": 1}
    rows = []
    for name in ("cumulus", "cumulonimbus"):
        spec = vols[name]
        vol, _ = build_volume(spec, name, threads=2)
        new = label(scaled(sheet(vol), 2.0), f"{name} {spec['resolution']} seed {spec['seed']}: rendered | tau front | tau top")
        old = label(scaled(old_look(name, spec["resolution"], spec["seed"], vol.bbox_max[0] - vol.bbox_min[0]), 2.0),
                    "previous generator")
        rows.append([new, old])
    flat = []
    for name, spec in (("stratocumulus deck (Mie)", vols["deck"]), ("cumulus_field", field)):
        vol, _ = build_volume(spec, name, threads=2)
        flat.append(label(scaled(sheet(vol), 2.0), f"{name} {spec['resolution']}"))
    rows.append(flat)
    gap = 10
    width = max(sum(im.width for im in r) + gap * (len(r) - 1) for r in rows)
    height = sum(max(im.height for im in r) for r in rows) + gap * (len(rows) - 1)
    canvas = Image.new("RGB", (width, height), "white")
    y = 0
    for r in rows:
        x = 0
        for im in r:
            canvas.paste(im, (x, y))
            x += im.width + gap
        y += max(im.height for im in r) + gap
    k = min(1.0, 1600 / canvas.width)
    scaled(canvas, k).save(ROOT / out, optimize=True)
    print(f"wrote {out} {canvas.width}x{canvas.height} (scaled {k:.2f})")


if __name__ == "__main__":
    main(*sys.argv[1:])
