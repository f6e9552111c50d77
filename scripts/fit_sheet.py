"""Rule `fit_sheet`: the contact sheet of one keyframe's fit (the photo, then the ranked renders labelled with their
objective), in a rule of its own so that its layout (`fit.contact_columns`) redraws the sheet and fits nothing."""
import numpy as np

from natscene import io
from natscene.fit.report import contact_sheet
from natscene.runner import run


def main(snakemake, log):
    photo = io.read_exr(snakemake.input.photo).channel("R", "G", "B")
    ranked = io.read_exr(snakemake.input.ranked)
    objectives = ranked.attrs["objective"]
    images = [ranked.channel(*(f"rank{i + 1}.{c}" for c in "RGB")) for i in range(len(objectives))]
    labels = [f"#{i + 1} O={o:.3f}" for i, o in enumerate(objectives)]
    sheet = contact_sheet(photo, images, labels, columns=snakemake.params.columns)
    io.write_png(snakemake.output.sheet, sheet, encoded=True)
    log.info(f"{len(images)} ranked renders -> {snakemake.output.sheet} ({sheet.shape[1]}x{sheet.shape[0]}, "
             f"{snakemake.params.columns} columns, objectives {np.round(objectives, 3).tolist()})")


run(snakemake, main)
