"""Rule `animation`: a shot's frame PNGs as an mp4 (gif without an encoder) at `shots.<shot>.fps`."""
from natscene import io
from natscene.keyframes.animation import write_animation
from natscene.runner import run


def main(snakemake, log):
    frames = [io.read_image_u8(p)[..., :3] for p in snakemake.input]
    write_animation(snakemake.output.animation, frames, fps=snakemake.params.fps)
    log.info(f"{len(frames)} frames at {snakemake.params.fps} fps -> {snakemake.output.animation}")


run(snakemake, main)
