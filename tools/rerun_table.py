"""docs/reruns.md: for each config key group, the jobs a change to it reruns, generated from the workflow.

On a finished run of ``config/smoke.yaml`` (the workflow's every rule on tiny inputs), each change of
:data:`CHANGES` is written into a copy of that config and Snakemake's own dry run says which jobs it plans, by
rule. The rows are what Snakemake does, not what the rule files mean to do; ``tests/test_reruns.py`` regenerates
them on the test suite's smoke run and compares them with the file.

    .venv/bin/python tools/rerun_table.py                      # smoke run in results/smoke (made if needed), rewrite
    .venv/bin/python tools/rerun_table.py --check --workdir D  # compare with the rows on the finished run in D
"""
from __future__ import annotations

import argparse
import copy
import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parents[1]
DOC = ROOT / "docs" / "reruns.md"
SMOKE = "config/smoke.yaml"

#: (config key path, the value tried). One row per key group a user changes: each section's expensive settings,
#: its per-entry settings and its preview-only settings. Integers in a path index a list.
CHANGES: list[tuple[str, object]] = [
    ("seed", 1),
    ("threads", 1),
    ("volumes.tiny.blobs", 21),
    ("volumes.deck.coverage", 0.9),
    ("views.tiny.sun.elevation", 36.0),
    ("photos.kite.threshold", 0.3),
    ("sky.fit_resolutions", [[64, 48], [32, 24]]),
    ("precompute.spp", 20),
    ("precompute.all_orders.sun_collisions", 500000),
    ("keyframes.tiny.seed", 1),
    ("fit.n_max", 12),
    ("fit.contact_columns", 3),
    ("mie.table.n_radii", 20),
    ("mie.droplets.stratocumulus", {"r_eff_um": 9.0, "v_eff": 0.02}),
    ("mie.solver.passes", 2),
    ("mie.render.L_amb", 0.3),
    ("mie.demo.silver_lining.distance", 4500.0),
    ("shots.tiny.render.sun_collisions", 500000),
    ("shots.tiny.keyframes.1.params.L_amb", 0.2),
    ("shots.tiny.easing", "smoothstep"),
    ("shots.tiny.frames", 4),
    ("shots.tiny.exposure", 1.25),
    ("shots.tiny.fps", 24),
    ("shots.tiny.filmstrip.height", 40),
    ("shots.tiny_mie.mie_sun_step", 1.0),
    ("composite.garden.spp", 2),
    ("composite.garden.frames", [0, 1, 2]),
    ("composite.garden.reference", False),
    ("textures.meadow.scale.slant", 40.0),
    ("textures.meadow.output.size", [80, 80]),
    ("textures.meadow.complete.hole", [30, 20, 24, 20]),
    ("tiles.grass.ga.n_g", 6),
    ("tiles.grass.sizes", [[256, 192], [96, 96]]),
    ("patterns.tiny_spot.rd", {"preset": "ring"}),
    ("patterns.tiny_spot.concentration", 1.5),
    ("recolour.tiny_flower.concentration", 1.5),
    ("leaves.size", 40),
    ("leaves.cases.warm_autumn.delta_T", 5.0),
]


def changed(cfg: dict, path: str, value) -> dict:
    """A deep copy of ``cfg`` with the key at ``path`` (dots; integers index lists) set to ``value``."""
    out = copy.deepcopy(cfg)
    node, keys = out, path.split(".")
    for k in keys[:-1]:
        node = node[int(k)] if isinstance(node, list) else node.setdefault(k, {})
    node[keys[-1]] = value
    return out


def job_counts(dry_run_output: str) -> dict[str, int]:
    """Rule -> job count from a dry run's "Job stats" table ({} when nothing is planned), without ``all``."""
    if "Job stats" not in dry_run_output:
        return {}
    counts = {}
    for line in dry_run_output.split("Job stats", 1)[1].splitlines():
        line = line.strip()
        if line.startswith("total"):
            break
        m = re.match(r"^([A-Za-z_]\w*)\s+(\d+)$", line)
        if m and m.group(1) != "all":
            counts[m.group(1)] = int(m.group(2))
    return counts


def snakemake(repo: Path, workdir: Path, configfile: Path, *args: str) -> str:
    env = dict(os.environ, PYTHONPATH=str(repo / "src"), PYTHONUNBUFFERED="1")
    cmd = [sys.executable, "-m", "snakemake", "-s", str(repo / "Snakefile"), "--configfile", str(configfile),
           "--directory", str(workdir), "--cores", "2", *args]
    proc = subprocess.run(cmd, env=env, capture_output=True, text=True)
    if proc.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} failed:\n{proc.stdout[-3000:]}\n{proc.stderr[-3000:]}")
    return proc.stdout


def rows(repo: Path, workdir: Path) -> list[tuple[str, str, dict[str, int]]]:
    """(key, value tried, rule -> planned jobs) per change, on the finished smoke run in ``workdir``."""
    base = yaml.safe_load((repo / SMOKE).read_text())
    if job_counts(snakemake(repo, workdir, repo / SMOKE, "-n")):
        raise RuntimeError(f"{workdir}: the smoke run is not complete; run it first (make smoke)")
    out = []
    with tempfile.TemporaryDirectory() as tmp:
        for path, value in CHANGES:
            f = Path(tmp) / "changed.yaml"
            f.write_text(yaml.safe_dump(changed(base, path, value), sort_keys=False))
            out.append((path, yaml.safe_dump(value, default_flow_style=True).strip().removesuffix("\n..."),
                        job_counts(snakemake(repo, workdir, f, "-n"))))
    return out


def table(rows_: list) -> str:
    lines = ["| config key | changed to | jobs it reruns (rule × jobs) |", "|---|---|---|"]
    for path, value, counts in rows_:
        jobs = ", ".join(f"`{r}` × {n}" for r, n in sorted(counts.items())) or "none"
        lines.append(f"| `{path}` | `{value}` | {jobs} |")
    return "\n".join(lines) + "\n"


HEADER = """# Which settings rerun which jobs

Snakemake reruns a job when its params, its code or its inputs change. Each rule's params hold only the config
keys its script reads, in a canonical form (sorted keys, the schema's defaults filled in, numbers as the schema
means them: `natscene.config.canonical`), its code fingerprint covers the meaning of its script and the modules it
imports (comments, docstrings and layout do not count: `natscene.fingerprint`), and files up to 4 GB are compared
by content (`profiles/default`), so an equivalent config, a comment or a rewrite with the same bytes reruns nothing.
Preview-only settings (the fit's contact sheet layout, a shot's exposure, filmstrip and fps) have rules of their
own; per-entry settings (a leaf case, a demo render, a composite frame, a tile size) rerun their entry alone.

The table below is what Snakemake plans after a finished run of `config/smoke.yaml` (every rule of the workflow
on tiny inputs) when one key is changed to the value shown: the jobs of the rules that read the key and of
everything downstream of them, whose inputs change. The main job has more entries (several volumes, views,
shots) but the same rules, so the same keys rerun the same rules there. Regenerate it after changing a rule's
params:

    .venv/bin/python tools/rerun_table.py     # runs the smoke workflow in results/smoke first if needed

`tests/test_reruns.py` checks that the table is what the workflow does.

"""


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--workdir", type=Path, default=ROOT / "results" / "smoke",
                    help="a finished run of config/smoke.yaml (default results/smoke; made when missing)")
    ap.add_argument("--repo", type=Path, default=ROOT, help="the checkout whose Snakefile runs (default: this one)")
    ap.add_argument("--check", action="store_true", help="exit 1 when docs/reruns.md differs from the workflow")
    a = ap.parse_args(argv)
    if not a.check:
        print(f"bringing the smoke run in {a.workdir} up to date", file=sys.stderr)
        snakemake(a.repo, a.workdir, a.repo / SMOKE, "--rerun-incomplete")
    text = HEADER + table(rows(a.repo, a.workdir))
    if a.check:
        if DOC.read_text() != text:
            print(f"{DOC} is out of date: run tools/rerun_table.py", file=sys.stderr)
            return 1
        return 0
    DOC.write_text(text)
    print(f"wrote {DOC}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
