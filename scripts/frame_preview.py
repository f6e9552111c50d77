"""Rule `frame_preview`: a shot frame's PNG at the shot's fixed exposure, in a rule of its own so that a new
exposure redraws the previews (and the animation made of them) without rendering a frame again."""
from natscene import io
from natscene.runner import run


def main(snakemake, log):
    frame = io.read_exr(snakemake.input.exr)
    io.write_png(snakemake.output.png, frame.channel("R", "G", "B"), exposure=snakemake.params.exposure)
    log.info(f"{snakemake.input.exr} -> {snakemake.output.png} (exposure {snakemake.params.exposure})")


run(snakemake, main)
