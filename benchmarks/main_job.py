"""The main job's time per rule, from Snakemake's own ``benchmark:`` files -> results/benchmarks/main_job.json.

Every rule of the workflow declares ``benchmark: results/benchmarks/rules/<rule>/...tsv``: Snakemake writes the
job's wall-clock seconds, peak resident memory and CPU time there. After a run of the main job (``make run``),

    .venv/bin/python benchmarks/main_job.py [--results results]

sums them per rule (jobs, total and longest wall-clock seconds, peak memory) and reads the run's own wall-clock
span from the newest Snakemake log (its first and last timestamps). The ``precompute`` rule is eligible for
Snakemake's between-workflow cache, which rules out a ``benchmark:`` directive (a cached result has no time to
report): its seconds come from its own log ("precompute done in ... s", results/logs/precompute/). The per-rule sums add up to more than the
span where jobs ran side by side (2 cores). Without benchmark files (no run yet) it says so and writes nothing.
"""
from __future__ import annotations

import argparse
import csv
import json
import re
import time
from datetime import datetime
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
STAMP = re.compile(r"^\[(\w{3} \w{3} +\d+ \d\d:\d\d:\d\d \d{4})\]")


def rule_times(bench_dir: Path) -> dict:
    """{rule: {jobs, total_s, max_s, max_rss_mb, cpu_s}} over the TSV files under ``bench_dir``/<rule>/."""
    out = {}
    for tsv in sorted(bench_dir.glob("*/**/*.tsv")):
        rule = tsv.relative_to(bench_dir).parts[0]
        with open(tsv, newline="") as f:
            rows = list(csv.DictReader(f, delimiter="\t"))
        if not rows:
            continue
        r = rows[-1]
        s, rss = float(r["s"]), float(r.get("max_rss") or 0.0)
        cpu = float(r.get("cpu_time") or 0.0)
        e = out.setdefault(rule, {"jobs": 0, "total_s": 0.0, "max_s": 0.0, "max_rss_mb": 0.0, "cpu_s": 0.0})
        e["jobs"] += 1
        e["total_s"] += s
        e["max_s"] = max(e["max_s"], s)
        e["max_rss_mb"] = max(e["max_rss_mb"], rss)
        e["cpu_s"] += cpu
    return {k: {kk: round(vv, 1) if isinstance(vv, float) else vv for kk, vv in v.items()} for k, v in out.items()}


def precompute_times(log_dir: Path) -> dict | None:
    """The precompute rule's seconds from its logs (it may not carry a ``benchmark:``, see the docstring)."""
    secs = []
    for log in sorted(log_dir.glob("**/*.log")):
        m = re.findall(r"precompute done in ([0-9.]+) s", log.read_text(errors="replace"))
        if m:
            secs.append(float(m[-1]))
    if not secs:
        return None
    return {"jobs": len(secs), "total_s": round(sum(secs), 1), "max_s": round(max(secs), 1), "from": "log"}


def run_span(log_dir: Path) -> dict | None:
    """The newest Snakemake log's first and last timestamps and the seconds between them."""
    logs = sorted(log_dir.glob("*.snakemake.log"))
    if not logs:
        return None
    stamps = [datetime.strptime(" ".join(m.group(1).split()), "%a %b %d %H:%M:%S %Y")
              for line in logs[-1].read_text().splitlines() if (m := STAMP.match(line))]
    if len(stamps) < 2:
        return None
    return {"log": logs[-1].name, "start": stamps[0].isoformat(), "end": stamps[-1].isoformat(),
            "wall_s": (stamps[-1] - stamps[0]).total_seconds()}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--results", default=str(ROOT / "results"), help="the run's results folder")
    ap.add_argument("--snakemake-dir", default=str(ROOT / ".snakemake"),
                    help="the run's .snakemake folder (its logs give the run's span)")
    ap.add_argument("--out", default=None, help="the JSON written (default <results>/benchmarks/main_job.json)")
    a = ap.parse_args()
    results = Path(a.results)
    rules = rule_times(results / "benchmarks" / "rules")
    if not rules:
        print(f"no rule benchmarks under {results / 'benchmarks' / 'rules'}: run the main job first (make run)")
        return 0
    pre = precompute_times(results / "logs" / "precompute")
    if pre:
        rules["precompute"] = pre
    span = run_span(Path(a.snakemake_dir) / "log")
    total = sum(v["total_s"] for v in rules.values())
    out = {"measured": time.strftime("%Y-%m-%d"), "results": str(results), "run": span,
           "jobs": sum(v["jobs"] for v in rules.values()), "sum_of_jobs_s": round(total, 1),
           "rules": dict(sorted(rules.items(), key=lambda kv: -kv[1]["total_s"]))}
    path = Path(a.out) if a.out else results / "benchmarks" / "main_job.json"
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(out, indent=2) + "\n")
    for rule, v in out["rules"].items():
        print(f"{rule:22s} {v['jobs']:4d} jobs {v['total_s']:8.1f} s (longest {v['max_s']:.1f} s"
              + (f", {v['max_rss_mb']:.0f} MB)" if "max_rss_mb" in v else ", from its log)"))
    if span:
        print(f"run: {span['wall_s']:.0f} s wall clock ({span['start']} to {span['end']})")
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
