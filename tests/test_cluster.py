"""Scale-out on a real SLURM (docs/cluster.md).

Without SLURM (no ``sbatch`` on the PATH, as on CI) only the launcher's refusal is tested: it must say that
there is no SLURM and submit nothing. With SLURM installed (``make cluster-setup``) and root (the local
cluster's daemons need it), the module starts the one-node cluster of tools/slurm-local.sh and checks:

- ``make cluster-smoke``'s check (tools/cluster_smoke.py): the smoke workflow through the profile completes,
  makes every output of a local run, and its volumes, sky, precompute tables and fit parameters are
  byte-identical to the local run's;
- a partition that does not exist is refused before anything is submitted, by the launcher and, used
  directly, by the profile (sbatch's own error), and nothing is counted as done;
- a job killed by the node for using more memory than it asked for (cgroup limit, SLURM state
  OUT_OF_MEMORY for the job or its step) ends the run with that state, the rule, its log and how to resume;
  its outputs do not exist and rerunning with enough memory completes the job.

CI (`make test`) deselects the `cluster` tests: together 10-20 min on 2 shared cores, more than the rest of
the suite, and they need root and system daemons; `make cluster-smoke` is the separate target.
"""
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
LOCAL_CLUSTER = ROOT / "tools" / "slurm-local.sh"
SLURM_RUN = ROOT / "tools" / "slurm_run.py"
SMOKE = ROOT / "config" / "smoke.yaml"


def _run(cmd, **kw):
    env = dict(os.environ, PYTHONUNBUFFERED="1", **kw.pop("env", {}))
    return subprocess.run(cmd, capture_output=True, text=True, env=env, cwd=ROOT, **kw)


def test_no_slurm_is_refused_with_a_clear_message(tmp_path):
    """No SLURM clients on the PATH: exit 2, a message naming what is missing and what to do, no submission."""
    bin_dir = tmp_path / "bin"
    bin_dir.mkdir()
    for tool in ("bash", "env", "python3"):  # a PATH with the basics but no SLURM clients
        if shutil.which(tool):
            (bin_dir / tool).symlink_to(shutil.which(tool))
    workdir = tmp_path / "run"
    proc = _run([sys.executable, str(SLURM_RUN), "--", "--configfile", str(SMOKE), "--directory", str(workdir)],
                env={"PATH": str(bin_dir)})
    assert proc.returncode == 2, proc.stdout + proc.stderr
    assert "no SLURM here" in proc.stderr and "sbatch" in proc.stderr, proc.stderr
    assert "tools/slurm-local.sh start" in proc.stderr and "Nothing was submitted" in proc.stderr
    assert not workdir.exists()


def test_memory_kill_without_cgroups_is_reported_as_out_of_memory(tmp_path, monkeypatch):
    """Clusters without cgroup limits kill a job over its --mem from the accounting poller: sacct says
    FAILED/CANCELLED, the job's log says why. The summary reports it as out of memory, with the rule and log."""
    sys.path.insert(0, str(ROOT / "tools"))
    import slurm_run

    log = tmp_path / ".snakemake" / "slurm_logs" / "rule_sky" / "kite" / "98.log"
    log.parent.mkdir(parents=True)
    # slurmstepd's words, as written by SLURM 22.05 with JobAcctGatherParams=OverMemoryKill
    log.write_text("slurmstepd-vm: error: StepId=98.batch exceeded memory limit (1588334592 > 209715200), "
                   "being killed\nslurmstepd-vm: error: Exceeded job memory limit\n")
    monkeypatch.setattr(slurm_run, "failed_jobs", lambda run_id: [
        {"JobID": "98", "Comment": "rule_sky_wildcards_kite", "State": "FAILED", "ReqMem": "200M"}])
    text = slurm_run.explain_failure("SLURM run ID: 0123-abcd\n", tmp_path)
    assert "job 98, rule sky (kite): OUT_OF_MEMORY" in text, text
    assert "--set-resources sky:mem_mb=" in text and str(log) in text
    assert "Resume with the same command" in text and "--rerun-incomplete" in text


needs_slurm = pytest.mark.skipif(
    shutil.which("sbatch") is None,
    reason="no SLURM on this machine (sbatch not on the PATH); `make cluster-setup` installs it, "
           "`make cluster-smoke` runs this check")
needs_root = pytest.mark.skipif(os.geteuid() != 0, reason="the local SLURM cluster's daemons need root")
cluster_mark = pytest.mark.cluster


@pytest.fixture(scope="module")
def cluster():
    """The local one-node cluster, started for this module (and stopped after it, if it was not running)."""
    was_running = _run(["bash", str(LOCAL_CLUSTER), "status"]).returncode == 0
    start = _run(["bash", str(LOCAL_CLUSTER), "start"])
    assert start.returncode == 0, start.stdout + start.stderr
    yield
    if not was_running:
        _run(["bash", str(LOCAL_CLUSTER), "stop"])


@cluster_mark
@needs_slurm
@needs_root
def test_cluster_smoke_matches_a_local_run(cluster, tmp_path):
    proc = _run([sys.executable, str(ROOT / "tools" / "cluster_smoke.py"), "--out", str(tmp_path)])
    out = proc.stdout + proc.stderr
    assert proc.returncode == 0, out[-6000:]
    assert "cluster-smoke: PASSED" in out
    assert "nothing to be done" in out
    # sacct answered for the run's jobs (the executor needs it to see jobs finish)
    assert "COMPLETED" in out


@cluster_mark
@needs_slurm
@needs_root
def test_unknown_partition_is_refused_before_submitting(cluster, tmp_path):
    workdir = tmp_path / "run"
    proc = _run([sys.executable, str(SLURM_RUN), "--partition", "no_such_partition", "--",
                 "--configfile", str(SMOKE), "--directory", str(workdir)])
    assert proc.returncode == 2, proc.stdout + proc.stderr
    assert "partition 'no_such_partition' does not exist" in proc.stderr
    assert "debug" in proc.stderr  # the partitions that do exist are listed
    assert not workdir.exists()


@cluster_mark
@needs_slurm
@needs_root
def test_unknown_partition_through_the_profile_directly(cluster, tmp_path):
    """Without the launcher sbatch itself refuses; Snakemake stops and no output is counted as done."""
    workdir = tmp_path / "run"
    cmd = [sys.executable, "-m", "snakemake", "-s", str(ROOT / "Snakefile"),
           "--workflow-profile", str(ROOT / "workflow" / "profiles" / "slurm"), "--max-threads", "2",
           "--default-resources", "slurm_partition=no_such_partition", "--slurm-no-account",
           "--configfile", str(SMOKE), "--directory", str(workdir), "results/volumes/tiny/meta.yaml"]
    proc = _run(cmd, timeout=600)
    out = proc.stdout + proc.stderr
    assert proc.returncode != 0, out[-4000:]
    assert "invalid partition" in out.lower(), out[-4000:]
    assert not (workdir / "results" / "volumes" / "tiny" / "meta.yaml").exists()


@cluster_mark
@needs_slurm
@needs_root
def test_out_of_memory_job_is_reported_and_resumable(cluster, tmp_path):
    """A job given 400 MB (cgroup-enforced --mem) is killed by the node; the run says so and resumes.

    400 MB holds the job's own Snakemake (about 200 MB) but not the rule's process too, so the kernel kills
    inside the job as it would for a rule that outgrows its mem_mb."""
    workdir = tmp_path / "run"
    target = "results/volumes/tiny/meta.yaml"
    base = [sys.executable, str(SLURM_RUN), "--max-threads", "2", "--", "--configfile", str(SMOKE),
            "--directory", str(workdir), "--slurm-init-seconds-before-status-checks", "2"]
    proc = _run(base + ["--set-resources", "volume:mem_mb=400", "--retries", "0", target], timeout=900)
    out = proc.stdout + proc.stderr
    assert proc.returncode != 0, out[-4000:]
    assert "OUT_OF_MEMORY" in out, out[-4000:]
    assert "rule volume" in out and "mem_mb" in out, out[-4000:]  # which rule, and how to give it more
    assert "Resume with the same command" in out and "--rerun-incomplete" in out
    outputs = [workdir / "results" / "volumes" / "tiny" / n for n in ("density.vol", "preview.exr", "meta.yaml")]
    assert not any(p.exists() for p in outputs), "a killed job's outputs must not be left as if done"
    # the SLURM log of the killed job is kept and says what the node did
    logs = list((workdir / ".snakemake" / "slurm_logs" / "rule_volume").rglob("*.log"))
    assert logs and any("oom" in p.read_text().lower() for p in logs), logs
    # resume: the same command with the rule's own memory completes, then nothing is left to do
    proc = _run(base + [target], timeout=900)
    assert proc.returncode == 0, (proc.stdout + proc.stderr)[-4000:]
    assert all(p.stat().st_size > 0 for p in outputs)
    dry = _run([sys.executable, "-m", "snakemake", "-s", str(ROOT / "Snakefile"), "--configfile", str(SMOKE),
                "--directory", str(workdir), "-n", "--cores", "1", target])
    assert "Nothing to be done" in dry.stdout + dry.stderr, dry.stdout[-2000:]
