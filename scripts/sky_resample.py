"""Rule `sky_resample`: the sky products of one photo at a fit resolution {W}x{H} (area averaging)."""
import numpy as np

from natscene import io
from natscene.errors import InputError
from natscene.runner import run
from natscene.sky.resample import area_resample, crop_box, resample_labels


def main(snakemake, log):
    tw, th = int(snakemake.wildcards.W), int(snakemake.wildcards.H)
    if tw < 1 or th < 1:
        raise InputError(f"fit resolution {tw}x{th}: width and height must be >= 1")
    photo = io.read_exr(snakemake.input.photo)
    mask = io.read_exr(snakemake.input.mask)
    sky = io.read_exr(snakemake.input.sky)
    h, w = photo.pixels.shape[:2]
    box = crop_box(w, h, tw, th)
    if box[2] * box[3] < 0.95 * w * h:
        log.warning(f"fit resolution {tw}x{th} has another aspect than the photo ({w}x{h}): centre crop {box}")
    if tw > box[2] or th > box[3]:
        log.warning(f"fit resolution {tw}x{th} is larger than the photo crop: upsampled bilinearly")
    attrs = {k: v for k, v in photo.attrs.items() if k in ("photo", "name", "c_in", "settings")}
    attrs.update({"source_resolution": [w, h], "crop_box": list(box), "resample": "centre crop + area average"})
    io.write_exr(snakemake.output.photo, area_resample(photo.channel("R", "G", "B"), tw, th), ["R", "G", "B"],
                 attrs=attrs, stage="sky")
    labels = resample_labels(mask.channel("label"), tw, th)
    alpha = area_resample(mask.channel("alpha"), tw, th)
    io.write_exr(snakemake.output.mask, np.stack([labels, alpha], -1), ["label", "alpha"],
                 attrs={**attrs, "labels": "0 sky, 1 cloud, 2 neither (majority)"}, stage="sky")
    io.write_exr(snakemake.output.sky, area_resample(sky.channel("R", "G", "B"), tw, th), ["R", "G", "B"],
                 attrs=attrs, stage="sky")
    log.info(f"resampled {w}x{h} -> {tw}x{th} (crop {box})")


run(snakemake, main)
