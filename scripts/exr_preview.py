"""Rules `frame_preview` and `composite_preview`: an EXR's RGB as a PNG at a fixed exposure (a shot's `exposure`;
"auto" maps the 99.5th percentile of luminance to 1), in rules of their own so that a new exposure redraws the
previews without rendering again."""
from natscene import io
from natscene.runner import run


def main(snakemake, log):
    image = io.read_exr(snakemake.input.exr)
    io.write_png(snakemake.output.png, image.channel("R", "G", "B"), exposure=snakemake.params.exposure)
    log.info(f"{snakemake.input.exr} -> {snakemake.output.png} (exposure {snakemake.params.exposure})")


run(snakemake, main)
