"""The smoke workflow (config/smoke.yaml) end to end, in a temporary copy of the repository:
it completes, every product exists and is readable, a second run has nothing to do, ``--forcerun volume``
redoes exactly the volume and what depends on it, and editing a library module of the volume stage makes
Snakemake want to rerun it (the code fingerprint)."""
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
SNAKEMAKE = [sys.executable, "-m", "snakemake"]


def _snake(repo: Path, workdir: Path, *args, check=True, configfile: Path | None = None, env: dict | None = None):
    env = dict(env if env is not None else os.environ, PYTHONPATH=str(repo / "src"), PYTHONUNBUFFERED="1")
    cmd = SNAKEMAKE + ["-s", str(repo / "Snakefile"), "--configfile", str(configfile or repo / "config" / "smoke.yaml"),
                       "--directory", str(workdir), "--cores", "2", *args]
    proc = subprocess.run(cmd, env=env, capture_output=True, text=True)
    if check and proc.returncode != 0:
        raise AssertionError(f"snakemake {' '.join(args)} failed:\n{proc.stdout[-4000:]}\n{proc.stderr[-6000:]}")
    return proc


def _job_counts(output: str) -> dict:
    """Rule -> job count from a dry run's "Job stats" table."""
    if "Job stats" not in output:
        return {}
    table = output.split("Job stats", 1)[1]
    counts = {}
    for line in table.splitlines():
        m = re.match(r"^([A-Za-z_][\w]*)\s+(\d+)\s*$", line.strip())
        if m and m.group(1) != "total":
            counts[m.group(1)] = int(m.group(2))
        if line.strip().startswith("total"):
            break
    return counts


def _descendants(rulegraph_dot: str, rule: str) -> set:
    """Rules downstream of ``rule`` in Snakemake's --rulegraph DOT output."""
    names = dict(re.findall(r'(\d+)\[label = "([^"]+)"', rulegraph_dot))
    edges = re.findall(r"(\d+) -> (\d+)", rulegraph_dot)
    start = [i for i, n in names.items() if n == rule]
    seen, todo = set(start), list(start)
    while todo:
        cur = todo.pop()
        for a, b in edges:
            if a == cur and b not in seen:
                seen.add(b)
                todo.append(b)
    return {names[i] for i in seen}


@pytest.fixture(scope="module")
def smoke(tmp_path_factory):
    base = tmp_path_factory.mktemp("smoke")
    repo = base / "repo"
    repo.mkdir()
    for item in ("Snakefile", "profiles", "workflow", "scripts", "src", "config", "resources"):
        src = ROOT / item
        (shutil.copytree if src.is_dir() else shutil.copy2)(src, repo / item)
    workdir = base / "run"
    proc = _snake(repo, workdir)
    return repo, workdir, proc


def test_smoke_workflow_completes_with_readable_outputs(smoke):
    repo, workdir, proc = smoke
    results = workdir / "results"
    for name in ("density.vol", "preview.exr", "preview.png", "meta.yaml"):
        assert (results / "volumes" / "tiny" / name).stat().st_size > 0
    from natscene.io import read_exr
    exrs = [p for p in results.rglob("*.exr")]
    assert exrs
    for p in exrs:
        img = read_exr(p)
        assert np.isfinite(img.pixels).all(), p
        assert img.attrs.get("version"), p
    # nothing half-written is left behind by the atomic writers
    assert not [p for p in results.rglob(".*") if p.is_file() and not p.name.startswith(".snakemake")]


def test_second_run_has_nothing_to_do(smoke):
    repo, workdir, _ = smoke
    out = _snake(repo, workdir, "-n").stdout
    assert "Nothing to be done" in out or _job_counts(out) == {}, out[-2000:]


def test_forcerun_volume_redoes_only_its_dependents(smoke):
    repo, workdir, _ = smoke
    dot = _snake(repo, workdir, "--rulegraph").stdout
    downstream = _descendants(dot, "volume")
    counts = _job_counts(_snake(repo, workdir, "-n", "--forcerun", "volume").stdout)
    assert counts.get("volume", 0) >= 1
    assert set(counts) <= downstream | {"all"}, (counts, downstream)
    if "sky" in counts or "tileset" in counts:
        pytest.fail(f"stages independent of the volume were scheduled: {counts}")


def test_editing_a_volume_module_reruns_the_volume(smoke):
    repo, workdir, _ = smoke
    module = repo / "src" / "natscene" / "volume" / "procedural.py"
    original = module.read_text()
    try:
        module.write_text(original + "\n_AN_EDIT = 1\n")
        counts = _job_counts(_snake(repo, workdir, "-n").stdout)
        assert counts.get("volume", 0) >= 1, counts
        assert "sky" not in counts
    finally:
        module.write_text(original)
    assert _job_counts(_snake(repo, workdir, "-n").stdout) == {}


def test_comment_and_docstring_edits_plan_nothing(smoke):
    """Fingerprints follow the code's meaning: a comment and a docstring added to natscene/io.py (imported by
    nearly every script) plan no job."""
    repo, workdir, _ = smoke
    module = repo / "src" / "natscene" / "io.py"
    original = module.read_text()
    try:
        module.write_text(original.replace('"""', '"""An edited docstring. ', 1) + "\n# a comment\n")
        assert module.read_text() != original
        assert _job_counts(_snake(repo, workdir, "-n").stdout) == {}
    finally:
        module.write_text(original)


def _reversed(node):
    """The same mapping with every level's keys in reverse order."""
    if isinstance(node, dict):
        return {k: _reversed(node[k]) for k in reversed(list(node))}
    if isinstance(node, list):
        return [_reversed(v) for v in node]
    return node


def test_equivalent_configs_plan_nothing(smoke, tmp_path):
    """Params in a canonical form: the smoke config with every mapping's keys reversed, defaults written out
    (precompute.skylight, fit.population) and a whole number for a float (a view's sun elevation 35 -> 35.0,
    precompute.skylight.turbidity 3.0 -> 3) plans no job."""
    import yaml
    repo, workdir, _ = smoke
    cfg = yaml.safe_load((repo / "config" / "smoke.yaml").read_text())
    cfg["precompute"].setdefault("skylight", {}).update(model="preetham", turbidity=3)
    cfg["fit"].setdefault("population", 20)
    cfg["views"]["tiny"]["sun"]["elevation"] = float(cfg["views"]["tiny"]["sun"]["elevation"])
    f = tmp_path / "equivalent.yaml"
    f.write_text(yaml.safe_dump(_reversed(cfg), sort_keys=False))
    counts = _job_counts(_snake(repo, workdir, "-n", configfile=f).stdout)
    assert counts == {}, counts


def test_a_forced_rerun_that_writes_the_same_bytes_does_not_cascade(smoke):
    """--forcerun sky --until sky rewrites the same bytes; the next run plans nothing, because the workflow
    profile (profiles/default) compares files by content up to a size above the main job's largest sky product.
    With Snakemake's files compared by time alone (a threshold below their size) the same rewrite cascades."""
    import OpenImageIO as oiio
    import yaml
    repo, workdir, _ = smoke
    _snake(repo, workdir, "--forcerun", "sky", "--until", "sky")
    assert _job_counts(_snake(repo, workdir, "-n").stdout) == {}
    assert _job_counts(_snake(repo, workdir, "-n", "--max-checksum-file-size", "10").stdout) != {}
    limit = yaml.safe_load((ROOT / "profiles" / "default" / "config.yaml").read_text())["max-checksum-file-size"]
    main = yaml.safe_load((ROOT / "config" / "config.yaml").read_text())
    for photo in main["photos"].values():
        inp = oiio.ImageInput.open(str(ROOT / photo["path"]))
        w, h = inp.spec().width, inp.spec().height
        inp.close()
        assert limit > w * h * 3 * 4 * 2, (photo["path"], w, h)      # float32 RGB EXR, uncompressed, twice over


def test_cache_needs_its_folder_and_says_so_in_one_line(smoke, tmp_path):
    """--cache precompute without $SNAKEMAKE_OUTPUT_CACHE fails with one line naming the variable (no traceback);
    with it, the cached rule is planned from the cache folder."""
    repo, workdir, _ = smoke
    env = {k: v for k, v in os.environ.items() if k != "SNAKEMAKE_OUTPUT_CACHE"}
    proc = _snake(repo, workdir, "-n", "--cache", "precompute", check=False, env=env)
    out = proc.stdout + proc.stderr
    assert proc.returncode != 0 and "SNAKEMAKE_OUTPUT_CACHE" in out, out[-2000:]
    assert "Traceback" not in out, out[-3000:]
    env["SNAKEMAKE_OUTPUT_CACHE"] = str(tmp_path)
    proc = _snake(repo, workdir, "-n", "--cache", "precompute", env=env)
    assert proc.returncode == 0


def _edited(repo: Path, tmp_path: Path, edit) -> Path:
    import yaml
    cfg = yaml.safe_load((repo / "config" / "smoke.yaml").read_text())
    edit(cfg)
    f = tmp_path / "edited.yaml"
    f.write_text(yaml.safe_dump(cfg, sort_keys=False))
    return f


def _set_deep(path, value):
    def edit(cfg):
        node = cfg
        for k in path[:-1]:
            node = node.setdefault(k, {})
        node[path[-1]] = value
    return edit


@pytest.mark.parametrize("path, value, expected, absent", [
    # a per-entry setting reruns its entry's job alone
    (["leaves", "cases", "warm_autumn", "delta_T"], 5.0, {"leaf_season": 1}, ()),
    (["mie", "demo", "silver_lining", "distance"], 41000.0, {"mie_render": 1}, ()),
    # a setting the pigment maps never read reruns the colour, not the reaction-diffusion maps
    (["patterns", "tiny_spot", "concentration"], 1.5, {"pattern_color": 1}, ("pigment_maps",)),
    # adding a composite frame renders that frame alone
    (["composite", "garden", "frames"], [0, 1, 2], {"composite": 1}, ()),
    # one more tile size builds that texture from the existing tile set
    (["tiles", "grass", "sizes"], [[256, 192], [96, 96]], {"tile_texture": 1}, ("tileset",)),
    # a preview-only setting redraws the previews, renders no frame
    (["shots", "tiny", "exposure"], 1.234, {"frame_preview": 3, "animation": 1}, ("render_frame", "interpolate")),
], ids=["leaf case", "mie demo render", "pattern concentration", "composite frame", "tile size", "shot exposure"])
def test_a_setting_reruns_only_the_jobs_that_read_it(smoke, tmp_path, path, value, expected, absent):
    repo, workdir, _ = smoke
    counts = _job_counts(_snake(repo, workdir, "-n", configfile=_edited(repo, tmp_path, _set_deep(path, value))).stdout)
    for rule, n in expected.items():
        assert counts.get(rule) == n, counts
    assert not set(absent) & set(counts), counts


def _rule_scripts(repo: Path) -> dict:
    out = {}
    for smk in (repo / "workflow" / "rules").glob("*.smk"):
        for block in re.split(r"(?m)^(?=rule )", smk.read_text())[1:]:
            script = re.search(r'script_path\("([^"]+)"\)', block)
            if script:
                out[re.match(r"rule (\w+):", block).group(1)] = repo / "scripts" / script.group(1)
    return out


@pytest.fixture(scope="module")
def smoke_dag(smoke):
    """(rules with jobs in the smoke DAG, the rule graph) of the finished smoke run."""
    repo, workdir, _ = smoke
    in_dag = set(_job_counts(_snake(repo, workdir, "-n", "--forceall").stdout)) - {"all"}
    return in_dag, _snake(repo, workdir, "--rulegraph").stdout


@pytest.mark.parametrize("module", ["color", "geometry"])
def test_editing_a_library_module_reruns_exactly_its_importers(smoke, smoke_dag, module):
    """Fingerprints from the code: editing natscene/<module>.py reruns exactly the rules whose scripts import it
    (transitively, lazy imports included; the importers found by the standard library's modulefinder).

    Snakemake schedules the rules downstream of a rerun job too (their input will change), so each side is checked
    with the other side's rules switched off (--allowed-rules): the importers alone are all scheduled, the other
    rules alone have nothing to do."""
    import modulefinder
    repo, workdir, _ = smoke
    in_dag, dot = smoke_dag
    importers = set()
    for rule, script in _rule_scripts(repo).items():
        mf = modulefinder.ModuleFinder(path=[str(repo / "src")])
        mf.run_script(str(script))
        if f"natscene.{module}" in mf.modules:
            importers.add(rule)
    expected = importers & in_dag
    others = in_dag - expected
    assert expected and (module == "color" or others)
    f = repo / "src" / "natscene" / f"{module}.py"
    original = f.read_text()
    try:
        f.write_text(original + "\n_AN_EDIT = 1\n")
        only_importers = _job_counts(_snake(repo, workdir, "-n", "--allowed-rules", "all", *sorted(expected)).stdout)
        only_others = _job_counts(_snake(repo, workdir, "-n", "--allowed-rules", "all", *sorted(others)).stdout) \
            if others else {}
        everything = _job_counts(_snake(repo, workdir, "-n").stdout)
    finally:
        f.write_text(original)
    assert set(only_importers) - {"all"} == expected, set(only_importers) ^ expected
    assert set(only_others) - {"all"} == set(), only_others
    downstream = set().union(*(_descendants(dot, r) for r in expected))
    assert expected <= set(everything) <= downstream | {"all"}


def _snapshot(results: Path) -> dict:
    """Every product's bytes by its path under ``results`` (logs and benchmark timings left out)."""
    return {p.relative_to(results).as_posix(): p.read_bytes() for p in results.rglob("*")
            if p.is_file() and p.relative_to(results).parts[0] not in ("logs", "benchmarks")}


def test_forced_rerun_is_byte_identical_and_clears_stale_temp_files(smoke):
    """Deterministic stages: a forced rerun of the whole smoke workflow writes the same bytes (no wall-clock time
    in any cached output, no DateTime in EXR headers); temp files of a killed earlier run are removed."""
    repo, workdir, _ = smoke
    results = workdir / "results"

    def snapshot():
        return _snapshot(results)

    before = snapshot()
    stale = [results / "volumes/tiny/.density.k1ll3d_x.vol", results / "sky/kite/.sun.abcd1234.yaml",
             results / "precompute/tiny/tiny/.single.zz9_zz9z.exr"]
    for s in stale:
        s.write_bytes(b"half-written by a killed job")
    _snake(repo, workdir, "--forceall")
    assert not [s for s in stale if s.exists()]
    after = snapshot()
    assert set(after) == set(before)
    changed = sorted(k for k in after if after[k] != before[k])
    assert not changed, f"outputs whose bytes changed on a forced rerun: {changed}"


def test_a_killed_run_is_recovered_by_one_command(smoke):
    """kill -9 a forced rerun of the sky mid-job: it leaves a lock and an incomplete job; natscene.recover clears
    the lock (no Snakemake process holds it) and one run with --rerun-incomplete completes, every output of the
    workflow byte-identical to the finished run's."""
    import signal
    import time
    from natscene.recover import clear_stale_locks, stale_locks
    repo, workdir, _ = smoke
    results = workdir / "results"

    def snapshot():
        return _snapshot(results)

    before = snapshot()
    env = dict(os.environ, PYTHONPATH=str(repo / "src"), PYTHONUNBUFFERED="1")
    cmd = SNAKEMAKE + ["-s", str(repo / "Snakefile"), "--configfile", str(repo / "config" / "smoke.yaml"),
                       "--directory", str(workdir), "--cores", "2", "--forcerun", "sky"]
    proc = subprocess.Popen(cmd, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                            start_new_session=True)
    incomplete = workdir / ".snakemake" / "incomplete"
    while not (incomplete.is_dir() and any(incomplete.iterdir())):
        assert proc.poll() is None, "the forced rerun ended before it started a job"
        time.sleep(0.2)
    os.killpg(proc.pid, signal.SIGKILL)
    proc.wait()
    assert stale_locks(workdir)
    removed, live = clear_stale_locks(workdir)
    assert removed and not live
    _snake(repo, workdir, "--rerun-incomplete")
    assert _job_counts(_snake(repo, workdir, "-n").stdout) == {}
    after = snapshot()
    assert after.keys() == before.keys()
    assert [k for k in before if before[k] != after[k]] == []


def test_a_live_run_keeps_its_lock(tmp_path):
    """A lock held by a live Snakemake process (here a stand-in whose command line names snakemake, working in the
    directory) is left alone; once it is gone the lock is cleared."""
    from natscene.recover import clear_stale_locks, snakemake_processes
    locks = tmp_path / ".snakemake" / "locks"
    locks.mkdir(parents=True)
    (locks / "0.input.lock").write_text("x")
    import time
    holder = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)", "snakemake"], cwd=tmp_path)
    try:
        t0 = time.time()
        while not snakemake_processes(tmp_path) and time.time() - t0 < 10:   # until the child has exec'd
            time.sleep(0.05)
        assert snakemake_processes(tmp_path) == [holder.pid]
        assert clear_stale_locks(tmp_path) == ([], [holder.pid])
        assert (locks / "0.input.lock").exists()
    finally:
        holder.kill()
        holder.wait()
    removed, live = clear_stale_locks(tmp_path)
    assert removed == [locks / "0.input.lock"] and not live and not (locks / "0.input.lock").exists()
