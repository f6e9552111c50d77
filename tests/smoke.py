"""The smoke workflow (config/smoke.yaml) as the tests run it: a copy of the repository, Snakemake in a subprocess,
and what the tests read from its output (planned jobs by rule, the rule graph, the products' bytes). The run
itself is the session fixture ``smoke_run`` of conftest.py, shared by test_workflow.py and test_reruns.py."""
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tools"))
from rerun_table import job_counts  # noqa: E402,F401  (one parser of Snakemake's "Job stats" table)

SNAKEMAKE = [sys.executable, "-m", "snakemake"]
COPIED = ("Snakefile", "profiles", "workflow", "scripts", "src", "config", "resources")


def snake(repo: Path, workdir: Path, *args, check=True, configfile: Path | None = None, env: dict | None = None):
    """Snakemake on the repository copy ``repo`` in ``workdir`` (the smoke config unless ``configfile``)."""
    env = dict(env if env is not None else os.environ, PYTHONPATH=str(repo / "src"), PYTHONUNBUFFERED="1")
    cmd = SNAKEMAKE + ["-s", str(repo / "Snakefile"), "--configfile", str(configfile or repo / "config" / "smoke.yaml"),
                       "--directory", str(workdir), "--cores", "2", *args]
    proc = subprocess.run(cmd, env=env, capture_output=True, text=True)
    if check and proc.returncode != 0:
        raise AssertionError(f"snakemake {' '.join(args)} failed:\n{proc.stdout[-4000:]}\n{proc.stderr[-6000:]}")
    return proc


def start(base: Path):
    """(repo copy, workdir, the finished run's process) of a full smoke run under ``base``."""
    repo = base / "repo"
    repo.mkdir()
    for item in COPIED:
        src = ROOT / item
        (shutil.copytree if src.is_dir() else shutil.copy2)(src, repo / item)
    workdir = base / "run"
    return repo, workdir, snake(repo, workdir)


def descendants(rulegraph_dot: str, rule: str) -> set:
    """Rules downstream of ``rule`` (itself included) in Snakemake's --rulegraph DOT output."""
    names = dict(re.findall(r'(\d+)\[label = "([^"]+)"', rulegraph_dot))
    edges = re.findall(r"(\d+) -> (\d+)", rulegraph_dot)
    start_ = [i for i, n in names.items() if n == rule]
    seen, todo = set(start_), list(start_)
    while todo:
        cur = todo.pop()
        for a, b in edges:
            if a == cur and b not in seen:
                seen.add(b)
                todo.append(b)
    return {names[i] for i in seen}


def snapshot(results: Path) -> dict:
    """Every product's bytes by its path under ``results`` (logs and benchmark timings left out)."""
    return {p.relative_to(results).as_posix(): p.read_bytes() for p in results.rglob("*")
            if p.is_file() and p.relative_to(results).parts[0] not in ("logs", "benchmarks")}
