"""Rule `sky`: sky extraction from one photo (Dobashi 2012 §4.1). Thin: read, call natscene.sky, write."""
from pathlib import Path

import numpy as np

from natscene import io
from natscene.config import relative_to_root, settings_from_section
from natscene.runner import run
from natscene.sky.extract import SkySettings, extract_sky
from natscene.sky.extract import preview_panels
from natscene.sky.segmentation import decode_hand_mask


def main(snakemake, log):
    name = snakemake.params.name
    settings = settings_from_section(SkySettings, snakemake.params.settings, "sky")
    photo_path = snakemake.input.photo
    photo = io.read_photo(photo_path)
    log.info(f"photo {name}: {photo_path} ({photo.shape[1]}x{photo.shape[0]})")
    hand = None
    if len(snakemake.input.mask):
        mpath = snakemake.input.mask[0]
        raw = io.read_exr(mpath).pixels  # no colour decoding: painted values as stored, in [0, 1]
        hand = decode_hand_mask(raw, photo.shape[:2], name=f"{mpath} (photos.{name}.mask)")
        log.info(f"hand-painted mask {mpath}")
    res = extract_sky(photo, settings, hand, name=f"{photo_path} (photos.{name})", key=f"photos.{name}")
    summary = res.summary()
    for w in res.warnings:
        log.warning(f"{name}: {w}")
    px = summary["pixels"]
    log.info(f"{name}: s_ab threshold {summary['thresholds']['saturation']:.4f} "
             f"({summary['thresholds']['saturation_source']}), cloud {px['cloud']} px, sky {px['sky']} px, "
             f"neither {px['neither']} px, Laplace unknowns {px['solved']}; c_in = "
             f"[{', '.join(f'{c:.4f}' for c in res.sun.c_in)}]")
    attrs = {"photo": relative_to_root(photo_path, Path(snakemake.scriptdir).parent), "name": name, "c_in": res.sun.c_in, "settings": summary["settings"]}
    io.write_exr(snakemake.output.photo, res.photo, ["R", "G", "B"], attrs=attrs, stage="sky")
    io.write_exr(snakemake.output.mask, np.stack([res.labels.astype(np.float32), res.alpha], -1),
                 ["label", "alpha"], attrs={**attrs, "labels": "0 sky, 1 cloud, 2 neither"}, stage="sky")
    io.write_exr(snakemake.output.sky, res.sky, ["R", "G", "B"], attrs=attrs, stage="sky")
    io.write_yaml(snakemake.output.sun, summary)
    exposure = io.auto_exposure(res.photo) if float(res.photo.max()) > 1.0 else 1.0
    io.write_png(snakemake.output.preview, preview_panels(res), exposure=exposure)


run(snakemake, main)
