"""Run the natscene workflow on a SLURM cluster through the profile workflow/profiles/slurm.

    .venv/bin/python tools/slurm_run.py [--account A] [--partition P] [--max-threads N] [-- SNAKEMAKE ARGS]

What the profile cannot know is filled in here, from the command line, else the environment, else the cluster:

- partition: ``--partition``, ``$NATSCENE_SLURM_PARTITION``, ``$SBATCH_PARTITION``, else the cluster's default
  partition (the one ``sinfo`` marks with ``*``); a partition that does not exist stops here, before
  anything is submitted, with the list of those that do;
- account: ``--account``, ``$NATSCENE_SLURM_ACCOUNT``, ``$SBATCH_ACCOUNT``, else your default account
  (``sacctmgr show user``), else none (clusters without accounts);
- ``--max-threads``: the CPUs of the smallest node of that partition (or ``--max-threads N`` if smaller), so
  that the profile's thread counts never ask more CPUs than a node has.

Every other argument goes to Snakemake unchanged (``--configfile``, targets, ``-n``, ``--directory``...).
When the run fails, the failed SLURM jobs of this run are listed from ``sacct`` with what happened
(out of memory, time limit, node failure, a job's own error), where their logs are and how to resume.
Exit status: Snakemake's, or 2 when the run could not start (no SLURM, unknown partition or account).
"""
from __future__ import annotations

import argparse
import getpass
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PROFILE = ROOT / "workflow" / "profiles" / "slurm"
#: MB added to every job's mem_mb (natscene.resources.job_overhead_mb): under SLURM's cgroup memory limit a job
#: holds Snakemake's batch step (~200 MB) and the Snakemake that runs the rule in the job step (~190 MB) too
SLURM_JOB_OVERHEAD_MB = 400


class SetupError(RuntimeError):
    """The run cannot start: the message says why and what to do."""


def _slurm(*cmd: str) -> str:
    """stdout of a SLURM client command; SetupError with its stderr if it fails."""
    try:
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    except FileNotFoundError:
        raise SetupError(f"'{cmd[0]}' is not on the PATH") from None
    except subprocess.TimeoutExpired:
        raise SetupError(f"'{' '.join(cmd)}' did not answer within 120 s: is the SLURM controller up?") from None
    if proc.returncode != 0:
        raise SetupError(f"'{' '.join(cmd)}' failed: {proc.stderr.strip() or proc.stdout.strip()}")
    return proc.stdout


def check_slurm() -> None:
    """SLURM's clients are installed and the controller answers."""
    missing = [c for c in ("sbatch", "sinfo", "sacct", "squeue") if shutil.which(c) is None]
    if missing:
        raise SetupError(
            f"no SLURM here: {', '.join(missing)} not on the PATH. Run this on a SLURM login node, or start a "
            f"one-node SLURM on this machine with `tools/slurm-local.sh start` (root; `make cluster-smoke` "
            f"does it). Nothing was submitted.")
    try:
        _slurm("sinfo", "-h", "-o", "%P")
    except SetupError as e:
        raise SetupError(f"SLURM is installed but its controller does not answer ({e}). Check `sinfo`; on this "
                         f"machine `tools/slurm-local.sh status`. Nothing was submitted.") from None
    try:
        import snakemake_executor_plugin_slurm  # noqa: F401
    except ImportError:
        raise SetupError(
            "the Snakemake SLURM executor is not installed in this environment: run `make cluster-setup` "
            "(or `.venv/bin/pip install -e '.[cluster]'`). Nothing was submitted.") from None


def partitions() -> dict[str, bool]:
    """Partition name -> is the default partition."""
    out = {}
    for name in _slurm("sinfo", "-h", "-o", "%P").split():
        out[name.rstrip("*")] = name.endswith("*")
    return out


def pick_partition(requested: str | None) -> str:
    parts = partitions()
    if requested:
        if requested not in parts:
            raise SetupError(f"partition '{requested}' does not exist on this cluster; partitions: "
                             f"{', '.join(parts) or '(none)'}. Nothing was submitted.")
        return requested
    default = [p for p, d in parts.items() if d]
    if not default:
        raise SetupError(f"no partition given and the cluster has no default partition: pass --partition "
                         f"(one of {', '.join(parts) or '(none)'}) or set NATSCENE_SLURM_PARTITION.")
    return default[0]


def pick_account(requested: str | None) -> str | None:
    """The account to charge; None when the cluster has no accounts for this user."""
    user = getpass.getuser()
    try:
        assoc = _slurm("sacctmgr", "-n", "-P", "show", "assoc", f"user={user}", "format=account")
        accounts = sorted({a.strip() for a in assoc.split() if a.strip()})
        default = _slurm("sacctmgr", "-n", "-P", "show", "user", user, "format=defaultaccount").strip() or None
    except SetupError:  # no accounting database: sbatch decides
        return requested
    if requested:
        if accounts and requested not in accounts:
            raise SetupError(f"account '{requested}' is not one of yours on this cluster ({user}: "
                             f"{', '.join(accounts)}). Nothing was submitted.")
        return requested
    return default


def node_size(partition: str) -> tuple[int, int]:
    """(CPUs, memory in MB) of the smallest node of ``partition``."""
    rows = [line.split() for line in _slurm("sinfo", "-h", "-N", "-p", partition, "-o", "%c %m").splitlines()]
    rows = [(int(c), int(m.rstrip("+"))) for c, m in (r for r in rows if len(r) == 2) if c.isdigit()]
    if not rows:
        raise SetupError(f"partition '{partition}' has no nodes")
    return min(c for c, _ in rows), min(m for _, m in rows)


def build_command(partition: str, account: str | None, max_threads: int, extra: list[str]) -> list[str]:
    # --default-resources on the command line replaces the profile's whole `default-resources`: repeat those
    import yaml
    profile = yaml.safe_load((PROFILE / "config.yaml").read_text()) or {}
    resources = [f"{k}={v}" for k, v in (profile.get("default-resources") or {}).items()]
    resources += [f"slurm_partition={partition}"] + ([f"slurm_account={account}"] if account else [])
    cmd = [sys.executable, "-m", "snakemake", "--workflow-profile", str(PROFILE),
           "--max-threads", str(max_threads), "--default-resources", *resources]
    if not account:
        cmd.append("--slurm-no-account")
    if "-s" not in extra and "--snakefile" not in extra:
        cmd += ["--snakefile", str(ROOT / "Snakefile")]
    return cmd + extra


ADVICE = {
    "OUT_OF_MEMORY": "killed by the node for using more memory than it asked for ({reqmem}): give the rule more "
                     "with `--set-resources {rule}:mem_mb=<MB>` (or under set-resources in workflow/profiles/slurm/config.yaml)",
    "TIMEOUT": "ran past its time limit ({timelimit}): raise it with `--set-resources {rule}:runtime=<minutes>`",
    "NODE_FAIL": "its node failed: resubmitting it is usually enough",
    "BOOT_FAIL": "its node failed to boot: resubmitting it is usually enough",
    "CANCELLED": "cancelled (by you, an administrator, or preemption)",
    "PREEMPTED": "preempted by a higher-priority job",
    "DEADLINE": "missed its deadline",
    "FAILED": "the job itself failed: read its log",
}


def failed_jobs(run_id: str) -> list[dict]:
    """This run's SLURM jobs that did not complete (from sacct; empty if sacct does not answer).

    A job whose step was killed for its memory ends FAILED while the step says OUT_OF_MEMORY (the kernel
    killed the rule's process, the job's Snakemake saw it die): such a job is reported as OUT_OF_MEMORY.
    """
    fields = ["JobID", "Comment", "State", "ExitCode", "ReqMem", "Timelimit", "Elapsed", "NodeList"]
    try:
        out = _slurm("sacct", "-n", "-P", "--name", run_id, "-S", "now-7days",
                     "-o", ",".join(f + "%200" for f in fields))
    except SetupError:
        return []
    jobs: dict[str, dict] = {}
    step_states: dict[str, set] = {}
    for line in out.splitlines():
        row = dict(zip(fields, line.split("|")))
        state = row.get("State", "").split()[0] if row.get("State") else ""
        job_id, _, step = row.get("JobID", "").partition(".")
        if not job_id:
            continue
        if step:
            step_states.setdefault(job_id, set()).add(state)
        else:
            row["State"] = state
            jobs[job_id] = row
    failed = []
    for job_id, row in jobs.items():
        if "OUT_OF_MEMORY" in step_states.get(job_id, set()):
            row["State"] = "OUT_OF_MEMORY"
        if row["State"] not in ("COMPLETED", "RUNNING", "PENDING", ""):
            failed.append(row)
    return failed


def _killed_for_memory(log: Path) -> bool:
    """slurmstepd's words in a job's log for a memory kill (cgroup OOM killer or the accounting poller)."""
    try:
        text = log.read_text(errors="replace")
    except OSError:
        return False
    return "oom-kill event" in text or "exceeded memory limit" in text or "Exceeded job memory limit" in text


def explain_failure(output: str, workdir: Path) -> str:
    """What went wrong, per failed SLURM job of this run, and how to resume."""
    lines = []
    m = re.search(r"SLURM run ID: (\S+)", output)
    if not m:  # Snakemake stopped before its executor started: its own message above says why
        return "Snakemake stopped before submitting anything (see its message above); nothing was submitted."
    if "SLURM sbatch failed" in output or "sbatch: error" in output:
        lines.append("SLURM refused a submission (see 'sbatch: error' above): fix the request (partition, "
                     "account, memory or CPUs larger than any node) and rerun.")
    failed = failed_jobs(m.group(1))
    if failed:
        lines.append("SLURM jobs of this run that did not complete:")
    for job in failed:
        cm = re.match(r"rule_(\w+?)(?:_wildcards_(.*))?$", job.get("Comment", ""))
        rule = cm.group(1) if cm else "?"
        pattern = f"rule_{rule}/**/{job['JobID']}.log" if cm else f"**/{job['JobID']}.log"
        logs = sorted((workdir / ".snakemake" / "slurm_logs").glob(pattern))
        if job["State"] in ("FAILED", "CANCELLED") and logs and _killed_for_memory(logs[0]):
            job["State"] = "OUT_OF_MEMORY"  # killed by SLURM's memory poller (no cgroup limits on that cluster)
        where = f" Log: {logs[0]}" if logs else ""
        what = ADVICE.get(job["State"], "see its log").format(rule=rule, reqmem=job.get("ReqMem", "?"),
                                                              timelimit=job.get("Timelimit", "?"))
        wild = f" ({cm.group(2)})" if cm and cm.group(2) else ""
        lines.append(f"  job {job['JobID']}, rule {rule}{wild}: {job['State']} - {what}.{where}")
    lines.append(
        "Nothing a failed job started is counted as done: Snakemake removed its outputs (natscene writes every "
        "output atomically, so no half-written file exists). Resume with the same command: finished outputs "
        "are kept, only the missing ones are made (the profile sets --rerun-incomplete, which also redoes "
        "jobs cut off when Snakemake itself was stopped). Rule logs: results/logs/<rule>/; SLURM logs: "
        ".snakemake/slurm_logs/rule_<rule>/<wildcards>/<jobid>.log (kept for failed jobs).")
    return "\n".join(lines)


def _workdir(extra: list[str]) -> Path:
    """The workflow's working directory from Snakemake's arguments (--directory / -d), else the current one."""
    workdir = Path.cwd()
    for i, a in enumerate(extra):
        if a in ("-d", "--directory") and i + 1 < len(extra):
            workdir = Path(extra[i + 1])
        elif a.startswith("--directory="):
            workdir = Path(a.split("=", 1)[1])
    return workdir


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0], allow_abbrev=False,
                                 formatter_class=argparse.RawDescriptionHelpFormatter,
                                 epilog="Arguments after -- (or not recognised here) go to Snakemake.")
    ap.add_argument("--account", default=os.environ.get("NATSCENE_SLURM_ACCOUNT") or os.environ.get("SBATCH_ACCOUNT"),
                    help="SLURM account (default: $NATSCENE_SLURM_ACCOUNT, $SBATCH_ACCOUNT, your default account)")
    ap.add_argument("--partition",
                    default=os.environ.get("NATSCENE_SLURM_PARTITION") or os.environ.get("SBATCH_PARTITION"),
                    help="SLURM partition (default: $NATSCENE_SLURM_PARTITION, $SBATCH_PARTITION, the cluster's "
                         "default partition)")
    ap.add_argument("--max-threads", type=int, default=None,
                    help="cap on any job's threads (default and upper bound: the CPUs of the partition's "
                         "smallest node)")
    args, extra = ap.parse_known_args(argv)
    if extra[:1] == ["--"]:
        extra = extra[1:]
    try:
        check_slurm()
        partition = pick_partition(args.partition)
        account = pick_account(args.account)
        cpus, mem_mb = node_size(partition)
    except SetupError as e:
        print(f"slurm_run: {e}", file=sys.stderr)
        return 2
    max_threads = min(cpus, args.max_threads) if args.max_threads else cpus
    cmd = build_command(partition, account, max_threads, extra)
    print(f"slurm_run: partition {partition}, account {account or '(none)'}, at most {max_threads} threads "
          f"per job (smallest node: {cpus} CPUs, {mem_mb} MB)", file=sys.stderr, flush=True)
    print("slurm_run: " + " ".join(cmd), file=sys.stderr, flush=True)
    # Snakemake's output goes to the terminal as it comes; a copy is kept to find the run's SLURM jobs.
    # the memory one job can have: a node's, not this login host's (natscene.resources refuses bigger jobs)
    env = dict(os.environ, NATSCENE_MEMORY_MB=os.environ.get("NATSCENE_MEMORY_MB", str(mem_mb)),
               # a job's --mem also covers Snakemake's batch step and the Snakemake of its job step
               NATSCENE_JOB_OVERHEAD_MB=os.environ.get("NATSCENE_JOB_OVERHEAD_MB", str(SLURM_JOB_OVERHEAD_MB)))
    # a killed earlier run's lock is cleared when no Snakemake process holds it; the profile's rerun-incomplete
    # then redoes the jobs it interrupted (natscene.recover, as `make run` does)
    from natscene.recover import main as recover
    recover(["--directory", str(_workdir(extra))])
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, bufsize=1, env=env)
    captured = []
    assert proc.stdout is not None
    for line in proc.stdout:
        sys.stdout.write(line)
        sys.stdout.flush()
        captured.append(line)
    rc = proc.wait()
    if rc != 0 and "-n" not in extra and "--dry-run" not in extra:
        workdir = _workdir(extra)
        print("\nslurm_run: the run did not complete.\n" + explain_failure("".join(captured), workdir),
              file=sys.stderr)
    return rc


if __name__ == "__main__":
    sys.exit(main())
