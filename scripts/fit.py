"""Rule `fit`: GA fit of the cloud rendering parameters of one keyframe (photo + volume + view) to its photo."""
from pathlib import Path

import numpy as np

from natscene import io
from natscene.fit.keyframe import fit_keyframe
from natscene.fit.report import convergence_csv, convergence_plot
from natscene.fit.settings import fit_settings
from natscene.runner import run
from natscene.scatter.tables import load_tables


def main(snakemake, log):
    inp, out, par = snakemake.input, snakemake.output, snakemake.params
    kf, settings = par.keyframe, fit_settings(par.settings)
    tables = load_tables(Path(inp.meta).parent)
    photo = io.read_exr(inp.photo).channel("R", "G", "B")
    label = io.read_exr(inp.mask).channel("label")
    sky = io.read_exr(inp.sky).channel("R", "G", "B")
    sun = io.read_yaml(inp.sun) or {}
    if "c_in" not in sun or np.asarray(sun["c_in"]).size != 3:
        raise io.InputError(f"{inp.sun}: needs 'c_in: [r, g, b]'; rerun the sky rule")
    fit = fit_keyframe(tables, photo, np.rint(label) == 1, sky, sun["c_in"], settings, seed=kf.get("seed", 0),
                       rank=kf.get("rank", 1), method=kf.get("method"), log=log.info)
    res, params, images = fit["result"], fit["params"], fit["images"]
    names = fit["problem"].names
    params = {"keyframe": par.name, "photo": kf["photo"], "volume": kf["volume"], "view": kf["view"], **params,
              "warnings": [f"sky ({inp.sun}): {w}" for w in sun.get("warnings") or []]}
    for w in params["warnings"]:
        log.warning(w)
    io.write_yaml(out.params, params)
    chans = [f"rank{i + 1}.{c}" for i in range(len(images)) for c in "RGB"]
    h, w = images.shape[1:3]
    io.write_exr(out.ranked, np.moveaxis(images, 0, 2).reshape(h, w, -1), chans,
                 attrs={"keyframe": par.name, "objective": [c.objective for c in res.ranked],
                        "params": [[c.values[p] for p in names] for c in res.ranked],
                        "param_names": list(names)}, stage="fit")
    io.write_text(out.csv, convergence_csv(res.best_history, res.mean_history))
    convergence_plot(out.plot, res.best_history, res.mean_history,
                     title=f"{par.name}: {params['method']} ({res.reason})", epsilon_o=settings.epsilon_o)
    log.info(f"chosen rank {kf.get('rank', 1)}: " + ", ".join(f"{p}={params['chosen'][p]:.4g}" for p in names)
             + f", kappa_a={params['chosen']['kappa_a']}")


run(snakemake, main)
