"""`make cluster-smoke`: the smoke workflow (config/smoke.yaml) through the SLURM profile on a one-node
local SLURM, checked against a local run of the same workflow.

1. starts the local cluster (tools/slurm-local.sh start; left running if it already ran);
2. in fresh directories ``<out>/local`` and ``<out>/slurm``, runs the smoke workflow locally
   (``--cores T``) and through tools/slurm_run.py (``--max-threads T``) at the same time;
3. checks that both complete, that the SLURM run made every file the local run made (and nothing else),
   that a dry run of the SLURM directory has nothing left to do, and that the deterministic outputs
   (volumes, sky, precompute tables, fit parameters) are byte-identical to the local run's; a file whose
   bytes differ is diagnosed (pixels or only header attributes; which YAML keys);
4. prints ``sacct`` for the SLURM run's jobs; stops the cluster if it started it.

T = min(2, CPUs of the node): the smoke config's ``threads``; Dr.Jit renders the same bytes only at the
same thread count (docs/architecture.md, "Mitsuba facts"). Exit status 0 when every check holds.
"""
from __future__ import annotations

import argparse
import filecmp
import os
import re
import shutil
import subprocess
import sys
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SMOKE = ROOT / "config" / "smoke.yaml"
LOCAL_CLUSTER = ROOT / "tools" / "slurm-local.sh"
#: outputs that must repeat byte for byte (relative to results/): the stages the issue names
DETERMINISTIC = ("volumes/", "sky/", "precompute/", "fit/*/params.yaml")


def say(msg: str) -> None:
    print(f"cluster-smoke: {msg}", flush=True)


def deterministic(rel: str) -> bool:
    for pat in DETERMINISTIC:
        if pat.endswith("/") and rel.startswith(pat):
            return True
        if "*" in pat and Path(rel).match(pat):
            return True
    return False


def products(results: Path) -> set[str]:
    """Relative paths of every file a run made under results/, logs left out (they hold timings)."""
    return {p.relative_to(results).as_posix() for p in results.rglob("*")
            if p.is_file() and not p.relative_to(results).as_posix().startswith("logs/")}


def explain_difference(a: Path, b: Path) -> str:
    """Why two files with different bytes differ: pixels, header attributes, YAML keys."""
    if a.suffix == ".exr":
        import numpy as np
        import OpenImageIO as oiio

        def load(p):
            inp = oiio.ImageInput.open(str(p))
            spec = inp.spec()
            px = inp.read_image(0, 0, 0, spec.nchannels, "float")
            attrs = {x.name: spec.getattribute(x.name) for x in spec.extra_attribs}
            inp.close()
            return np.asarray(px), list(spec.channelnames), attrs
        pa, ca, aa = load(a)
        pb, cb, ab = load(b)
        if ca != cb or pa.shape != pb.shape:
            return f"channels/shape differ ({ca} {pa.shape} vs {cb} {pb.shape})"
        heads = sorted(k for k in set(aa) | set(ab) if aa.get(k) != ab.get(k))
        if not np.array_equal(pa, pb, equal_nan=True):
            n = int((pa != pb).sum())
            return (f"PIXELS differ ({n} of {pa.size} values, max |diff| {float(np.nanmax(np.abs(pa - pb))):.3g})"
                    + (f"; header attributes differ: {', '.join(heads)}" if heads else ""))
        return f"pixels identical; only header attributes differ: {', '.join(heads) or '(encoding)'}"
    if a.suffix in (".yaml", ".yml"):
        import yaml

        def walk(x, y, path=""):
            if isinstance(x, dict) and isinstance(y, dict):
                for k in sorted(set(x) | set(y), key=str):
                    yield from walk(x.get(k), y.get(k), f"{path}.{k}" if path else str(k))
            elif isinstance(x, list) and isinstance(y, list) and len(x) == len(y):
                for i, (u, v) in enumerate(zip(x, y)):
                    yield from walk(u, v, f"{path}[{i}]")
            elif x != y:
                yield path
        keys = list(walk(yaml.safe_load(a.read_text()), yaml.safe_load(b.read_text())))
        return f"YAML values differ at: {', '.join(keys[:12])}{' ...' if len(keys) > 12 else ''}"
    return "bytes differ"


def run_logged(cmd: list[str], log: Path, echo: bool, env: dict) -> subprocess.Popen:
    """Start ``cmd`` with its output in ``log`` (and on the terminal if ``echo``)."""
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, bufsize=1,
                            env=env, cwd=ROOT)

    def pump():
        with open(log, "w") as f:
            for line in proc.stdout:
                f.write(line)
                f.flush()
                if echo:
                    sys.stdout.write("  [slurm] " + line)
                    sys.stdout.flush()
    t = threading.Thread(target=pump, daemon=True)
    t.start()
    proc.pump = t  # type: ignore[attr-defined]
    return proc


def node_cpus() -> int:
    out = subprocess.run(["sinfo", "-h", "-N", "-o", "%c"], capture_output=True, text=True).stdout.split()
    return min(int(c) for c in out) if out else 1


def sacct_table(run_id: str) -> str:
    fmt = "JobID,Comment%44,State,ExitCode,Elapsed,AllocCPUS,ReqMem,MaxRSS"
    proc = subprocess.run(["sacct", "--name", run_id, "-S", "now-1days", "-o", fmt], capture_output=True, text=True)
    return proc.stdout + proc.stderr


def check(out: Path, threads: int | None) -> list[str]:
    """Run both workflows and return the list of failed checks (empty: all hold)."""
    failures: list[str] = []
    local, slurm = out / "local", out / "slurm"
    for d in (local, slurm):
        shutil.rmtree(d, ignore_errors=True)
        d.mkdir(parents=True)
    t = threads or min(2, node_cpus())
    env = dict(os.environ, PYTHONUNBUFFERED="1")
    py = sys.executable
    local_cmd = [py, "-m", "snakemake", "-s", str(ROOT / "Snakefile"), "--configfile", str(SMOKE),
                 "--directory", str(local), "--cores", str(t)]
    # status checks every few seconds instead of the plugin's 40 s: smoke jobs last seconds
    slurm_cmd = [py, str(ROOT / "tools" / "slurm_run.py"), "--max-threads", str(t), "--",
                 "--configfile", str(SMOKE), "--directory", str(slurm),
                 "--slurm-init-seconds-before-status-checks", "2", "--seconds-between-status-checks", "2"]
    say(f"local run  -> {local} ({t} cores; log {out / 'local.log'})")
    say(f"SLURM run  -> {slurm} (at most {t} threads per job; log {out / 'slurm.log'})")
    t0 = time.perf_counter()
    p_local = run_logged(local_cmd, out / "local.log", echo=False, env=env)
    p_slurm = run_logged(slurm_cmd, out / "slurm.log", echo=True, env=env)
    rc_slurm, rc_local = p_slurm.wait(), p_local.wait()
    p_slurm.pump.join()
    p_local.pump.join()
    say(f"both runs done in {time.perf_counter() - t0:.0f} s (local exit {rc_local}, SLURM exit {rc_slurm})")
    if rc_local:
        failures.append(f"the local run failed (see {out / 'local.log'})")
    if rc_slurm:
        failures.append(f"the SLURM run failed (see {out / 'slurm.log'})")
    slurm_log = (out / "slurm.log").read_text()
    m = re.search(r"SLURM run ID: (\S+)", slurm_log)
    if m:
        say(f"sacct for SLURM run {m.group(1)}:")
        print(sacct_table(m.group(1)), flush=True)
        n_jobs = len(re.findall(r"has been submitted with SLURM jobid", slurm_log))
        say(f"{n_jobs} jobs went through sbatch")
        if n_jobs == 0:
            failures.append("no job went through SLURM")
    if rc_local or rc_slurm:
        return failures

    have_l, have_s = products(local / "results"), products(slurm / "results")
    if have_l - have_s:
        failures.append(f"missing from the SLURM run: {sorted(have_l - have_s)}")
    if have_s - have_l:
        failures.append(f"only in the SLURM run: {sorted(have_s - have_l)}")
    empty = sorted(p for p in have_s if (slurm / "results" / p).stat().st_size == 0)
    if empty:
        failures.append(f"empty outputs: {empty}")
    say(f"{len(have_s)} output files in the SLURM run, {len(have_l)} in the local run")

    dry = subprocess.run([py, "-m", "snakemake", "-s", str(ROOT / "Snakefile"), "--configfile", str(SMOKE),
                          "--directory", str(slurm), "-n", "--cores", "1"],
                         capture_output=True, text=True, env=env, cwd=ROOT)
    if dry.returncode != 0 or "Nothing to be done" not in dry.stdout + dry.stderr:
        failures.append("a dry run of the SLURM directory still has jobs to do:\n" + dry.stdout[-2000:])
    else:
        say("dry run of the SLURM directory: nothing to be done")

    same, differ = [], []
    for rel in sorted(have_l & have_s):
        (same if filecmp.cmp(local / "results" / rel, slurm / "results" / rel, shallow=False) else differ).append(rel)
    det = [r for r in sorted(have_l & have_s) if deterministic(r)]
    det_differ = [r for r in differ if deterministic(r)]
    say(f"deterministic outputs (volumes, sky, precompute, fit params): {len(det) - len(det_differ)} of "
        f"{len(det)} byte-identical to the local run")
    for rel in det_differ:
        why = explain_difference(local / "results" / rel, slurm / "results" / rel)
        say(f"  NOT byte-identical: {rel}: {why}")
        failures.append(f"{rel} differs from the local run: {why}")
    other = [r for r in differ if not deterministic(r)]
    say(f"other outputs: {len(same) - (len(det) - len(det_differ))} byte-identical, {len(other)} differ"
        + (":" if other else ""))
    for rel in other:
        say(f"  (not required) {rel}: {explain_difference(local / 'results' / rel, slurm / 'results' / rel)}")
    return failures


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", type=Path, default=ROOT / "results" / "cluster-smoke",
                    help="where the two runs go (emptied first; default results/cluster-smoke)")
    ap.add_argument("--threads", type=int, default=None, help="threads on both sides (default min(2, node CPUs))")
    ap.add_argument("--keep-cluster", action="store_true", help="leave the local cluster running afterwards")
    args = ap.parse_args(argv)
    out = args.out.resolve()
    out.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    was_running = subprocess.run(["bash", str(LOCAL_CLUSTER), "status"], capture_output=True).returncode == 0
    if subprocess.run(["bash", str(LOCAL_CLUSTER), "start"]).returncode != 0:
        say("FAILED: the local SLURM cluster did not start (see above)")
        return 1
    try:
        failures = check(out, args.threads)
    finally:
        if not was_running and not args.keep_cluster:
            subprocess.run(["bash", str(LOCAL_CLUSTER), "stop"])
        elif was_running:
            say("the local cluster was already running before: left running (tools/slurm-local.sh stop)")
    took = time.perf_counter() - t0
    if failures:
        say(f"FAILED after {took:.0f} s:\n  - " + "\n  - ".join(failures))
        return 1
    say(f"PASSED in {took:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
