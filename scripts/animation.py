"""Rule `animation`: a shot's frame PNGs as an mp4 (gif without an encoder) and a filmstrip PNG."""
from natscene import io
from natscene.keyframes.animation import filmstrip, strip_indices, write_animation
from natscene.runner import run


def main(snakemake, log):
    frames = [io.read_image_u8(p)[..., :3] for p in snakemake.input]
    write_animation(snakemake.output.animation, frames, fps=snakemake.params.fps)
    fs = snakemake.params.filmstrip
    idx = strip_indices(len(frames), fs["count"])
    io.write_png(snakemake.output.filmstrip, filmstrip([frames[i] for i in idx], height=fs["height"]), encoded=True)
    log.info(f"{len(frames)} frames -> {snakemake.output.animation}; filmstrip of frames {idx}")


run(snakemake, main)
