"""Rule `filmstrip`: a strip of a shot's frame PNGs (`shots.<shot>.filmstrip`: which frames the rule's input
picks, how tall), in a rule of its own so that its layout redraws the strip alone."""
from natscene import io
from natscene.keyframes.animation import filmstrip
from natscene.runner import run


def main(snakemake, log):
    frames = [io.read_image_u8(p)[..., :3] for p in snakemake.input]
    height = snakemake.params.height
    io.write_png(snakemake.output.filmstrip, filmstrip(frames, height=height), encoded=True)
    log.info(f"{len(frames)} frames, {height} px high -> {snakemake.output.filmstrip}")


run(snakemake, main)
