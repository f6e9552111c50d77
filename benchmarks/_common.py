"""Benchmark helpers: best-of-N timing and JSON results under results/benchmarks/."""
from __future__ import annotations

import json
import os
import platform
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))


def best_of(fn, repeat: int = 3) -> float:
    """Minimum wall time of ``repeat`` calls (the least disturbed by other load)."""
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return min(times)


def write_result(name: str, data: dict) -> Path:
    out = ROOT / "results" / "benchmarks" / f"{name}.json"
    out.parent.mkdir(parents=True, exist_ok=True)
    data = {"benchmark": name, "machine": {"cpus": os.cpu_count(), "python": platform.python_version()}, **data}
    out.write_text(json.dumps(data, indent=2))
    print(json.dumps(data, indent=2))
    return out
