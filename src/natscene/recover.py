"""Recovery after a killed run: a stale Snakemake lock is cleared when no Snakemake process holds it.
==================================================================================================

(The title stays on the docstring's first line: ``python -m natscene.recover --help`` shows it.)

-   :func:`clear_stale_locks`: remove the lock files when no Snakemake process works in a directory.
-   :func:`stale_locks`, :func:`snakemake_processes`: the lock files, and the live Snakemake processes.
-   :func:`main`: the command line, ``python -m natscene.recover [--directory DIR]``.

A run killed by a signal, a power cut or a lost terminal leaves ``.snakemake/locks/*.lock`` behind, and the next
``snakemake`` stops with a ``LockException`` until ``--unlock``. ``make run`` (and ``make smoke``) first run
``python -m natscene.recover [--directory DIR]``, which removes those lock files when no live Snakemake process
works in that directory (Linux: ``/proc``), then Snakemake with ``--rerun-incomplete``, so one command picks a
killed run up where it stopped. A lock held by a live run is left alone, and Snakemake then refuses to start as
usual.
"""
from __future__ import annotations

import argparse
import os
from pathlib import Path

__all__ = ["snakemake_processes", "stale_locks", "clear_stale_locks", "main"]


def _cmdline(pid: str) -> list[str]:
    try:
        return Path(f"/proc/{pid}/cmdline").read_bytes().decode(errors="replace").split("\0")
    except OSError:
        return []


def _working_dir(pid: str, args: list[str]) -> Path | None:
    """The directory a Snakemake process works in: its ``--directory``/``-d`` argument, else its cwd."""
    for i, a in enumerate(args[:-1]):
        if a in ("--directory", "-d"):
            try:
                return Path(os.readlink(f"/proc/{pid}/cwd"), args[i + 1]).resolve()
            except OSError:
                return Path(args[i + 1]).resolve()
    try:
        return Path(os.readlink(f"/proc/{pid}/cwd")).resolve()
    except OSError:
        return None


def snakemake_processes(directory: str | Path) -> list[int]:
    """PIDs of live processes whose command line runs Snakemake in ``directory`` (empty where /proc is absent)."""
    directory = Path(directory).resolve()
    proc = Path("/proc")
    if not proc.is_dir():
        return []
    out = []
    for entry in proc.iterdir():
        if not entry.name.isdigit() or int(entry.name) == os.getpid():
            continue
        args = _cmdline(entry.name)
        if not any(Path(a).name == "snakemake" or a == "snakemake" for a in args if a):
            continue
        if _working_dir(entry.name, args) == directory:
            out.append(int(entry.name))
    return sorted(out)


def stale_locks(directory: str | Path) -> list[Path]:
    """Snakemake's lock files in ``directory`` (whether held or not)."""
    return sorted(Path(directory, ".snakemake", "locks").glob("*.lock"))


def clear_stale_locks(directory: str | Path) -> tuple[list[Path], list[int]]:
    """Remove the lock files when no Snakemake process works in ``directory``; return (removed, live PIDs)."""
    locks = stale_locks(directory)
    if not locks:
        return [], []
    live = snakemake_processes(directory)
    if live:
        return [], live
    for f in locks:
        f.unlink(missing_ok=True)
    return locks, []


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--directory", default=".", help="the workflow's working directory (Snakemake's --directory)")
    a = ap.parse_args(argv)
    removed, live = clear_stale_locks(a.directory)
    if removed:
        print(f"natscene: cleared the lock a killed run left in {Path(a.directory).resolve()} (no Snakemake process "
              f"holds it); incomplete jobs are rerun")
    elif live:
        print(f"natscene: Snakemake is running in {Path(a.directory).resolve()} (pid {', '.join(map(str, live))}); "
              f"its lock stays")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
