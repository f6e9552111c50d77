"""
Rule script harness
===================

Defines the thin-script harness: logging to the rule's log file and the terminal, clean error reporting:

-   :func:`run`: call a script's ``main(snakemake, logger)``; bad input is reported in one line.

Every ``scripts/*.py`` ends with ``run(snakemake, main)``. Before ``main`` runs, the temporary files that an
earlier, killed run of the same job left beside its outputs are removed (:func:`natscene.io.remove_stale_temps`).
A :class:`natscene.errors.InputError` or :class:`natscene.errors.ConfigError` (bad input, named by file or key) is
reported as one line without a traceback and the job fails; anything else is a bug and keeps its traceback
(on the terminal and in the rule's log file).
"""
from __future__ import annotations

import logging
import sys
import time
from pathlib import Path

from natscene.errors import ConfigError, InputError
from natscene.io import remove_stale_temps

__all__ = ["run"]


def setup_logging(log_path: str | None, name: str = "natscene") -> logging.Logger:
    """A logger writing to stderr and (if given) the rule's log file, with elapsed-time stamps."""
    logger = logging.getLogger(name)
    logger.setLevel(logging.INFO)
    logger.handlers.clear()
    start = time.perf_counter()

    class _Elapsed(logging.Formatter):
        def format(self, record):
            record.elapsed = f"{time.perf_counter() - start:7.1f}s"
            return super().format(record)

    fmt = _Elapsed("[%(elapsed)s] %(levelname)s %(message)s")
    handlers = [logging.StreamHandler(sys.stderr)]
    if log_path:
        Path(log_path).parent.mkdir(parents=True, exist_ok=True)
        handlers.append(logging.FileHandler(log_path, mode="w"))
    for h in handlers:
        h.setFormatter(fmt)
        logger.addHandler(h)
    logger.propagate = False
    return logger


def peak_rss_mb() -> float:
    """Peak resident memory (MB) of this process (the kernel's high-water mark VmHWM) and of its largest
    finished child (getrusage). Not getrusage(RUSAGE_SELF): it survives execve, so a script started by a
    forked Snakemake would report at least Snakemake's own peak."""
    import resource

    own = 0.0
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("VmHWM:"):
                own = float(line.split()[1])  # kB
    except OSError:
        own = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return max(own, resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss) / 1024.0


def _log_peak_memory(snakemake, logger) -> None:
    """One line 'peak memory X MB of mem_mb Y' in the rule's log (the data behind natscene.resources)."""
    declared = getattr(getattr(snakemake, "resources", None), "mem_mb", None)
    peak = peak_rss_mb()
    wc = getattr(snakemake, "wildcards", None)
    wildcards = ", ".join(f"{k}={v}" for k, v in (wc.items() if hasattr(wc, "items") else []))
    logger.info(f"peak memory {peak:.0f} MB" + (f" of mem_mb {declared}" if declared else "")
                + f" (rule {snakemake.rule}{', ' + wildcards if wildcards else ''})")
    if declared and peak > float(declared):
        logger.warning(f"rule {snakemake.rule} used {peak:.0f} MB, more than its declared mem_mb {declared}: the "
                       f"estimate of natscene.resources is low for this input; please report it")


def run(snakemake, main) -> None:
    """Call ``main(snakemake, logger)``; report bad input in one line and exit non-zero."""
    log_path = snakemake.log[0] if len(snakemake.log) else None
    logger = setup_logging(log_path)
    for out in snakemake.output:
        for f in remove_stale_temps(out):
            logger.info(f"removed {f}, left by an earlier interrupted run of this job")
    try:
        main(snakemake, logger)
        _log_peak_memory(snakemake, logger)
    except (InputError, ConfigError) as e:
        logger.error(f"rule {snakemake.rule}: {e}")
        sys.exit(1)
    except Exception:
        # a bug: keep the traceback, in the rule's log file too (Snakemake points the user there)
        if log_path:
            file_handlers = [h for h in logger.handlers if isinstance(h, logging.FileHandler)]
            for h in file_handlers:
                h.handle(logger.makeRecord(logger.name, logging.ERROR, __file__, 0,
                                           f"rule {snakemake.rule} failed:", None, sys.exc_info()))
        raise
