"""Rule `texture_features`: the feature maps of one example photo (Dong 2007 §6.3-6.5): scale, type, colour."""
import numpy as np

from natscene import io
from natscene.color import linear_to_srgb
from natscene.errors import InputError
from natscene.features.colour import region_colours
from natscene.features.entry import analyse, working_image
from natscene.features.scale import scale_preview
from natscene.features.type_map import type_preview
from natscene.runner import run


def main(snakemake, log):
    entry, name = snakemake.params.entry, snakemake.wildcards.name
    key = f"textures.{name}"
    size = entry["working_size"]
    photo = io.read_photo(snakemake.input.photo)[..., :3]
    srgb = linear_to_srgb(working_image(photo, size))
    if srgb.shape[-1] == 1:
        srgb = np.repeat(srgb, 3, -1)

    def same_size(img, what):  # before both are resized to working_size
        if img.shape[:2] != photo.shape[:2]:
            raise InputError(f"config key '{key}.{what}': {img.shape[1]}x{img.shape[0]}, but the photo "
                             f"{snakemake.input.photo} is {photo.shape[1]}x{photo.shape[0]}")
        return img

    mask = labels = None
    if snakemake.input.get("mask"):
        raw = same_size(io.read_mask(snakemake.input.mask), "scale.mask")
        mask = working_image(raw, size, nearest=True) > 0.5
    if snakemake.input.get("labels"):
        raw = same_size(io.read_image_u8(snakemake.input.labels), "types.labels")
        grey = raw.shape[-1] < 3 or np.ptp(raw[..., :3].astype(int), axis=-1).max() == 0
        labels = working_image(raw[..., 0] if grey else raw[..., :3], size, nearest=True)
    maps = analyse(srgb, entry, mask, labels, key)
    h, w = srgb.shape[:2]
    chans, names = [np.asarray(srgb, np.float32)], ["sR", "sG", "sB"]
    if maps["scale"] is not None:
        chans.append(maps["scale"][..., None])
        names.append("scale")
    if maps["types"] is not None:
        chans.append(maps["types"][..., None].astype(np.float32))
        names.append("type")
    if maps["colour"] is not None:
        chans.append(maps["colour"][..., None].astype(np.float32))
        names.append("colour")
    io.write_exr(snakemake.output.exr, np.concatenate(chans, -1), names,
                 attrs={"texture": name, "encoding": "sR, sG, sB: display-encoded sRGB in [0, 1]"},
                 stage="texture_features")
    io.write_yaml(snakemake.output.colour, {"regions": maps["colour_stats"]})
    tiles = [srgb]
    if maps["scale"] is not None:
        tiles.append(np.repeat(scale_preview(maps["scale"])[..., None], 3, -1))
        log.info(f"scale map: {maps['scale'].min():.3f} .. {maps['scale'].max():.3f}")
    if maps["types"] is not None:
        tiles.append(np.repeat(type_preview(maps["types"])[..., None], 3, -1))
        log.info(f"type map: types {sorted(np.unique(maps['types']).tolist())}")
    if maps["colour"] is not None:
        tiles.append(linear_to_srgb(region_colours(maps["colour"], maps["colour_stats"])))
        log.info(f"colour map: {int(maps['colour'].max()) + 1} regions")
    gap = np.ones((h, 4, 3))
    sheet = np.concatenate([x for t in tiles for x in (t, gap)][:-1], 1)
    io.write_png(snakemake.output.preview, sheet, encoded=True)
    log.info(f"{name}: {w}x{h}, features {names[3:] or 'none'} -> {snakemake.output.exr}")


run(snakemake, main)
