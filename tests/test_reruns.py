"""Reruns that redo only what changed (issue: canonical params, per-rule config, code fingerprints, recovery), as
dry runs on the finished smoke run (the session fixture ``smoke_run``): a second run plans nothing; reordered keys
and written-out defaults plan nothing; each preview-only setting plans only its preview rule and each per-entry
setting only its entry's jobs; a comment-only edit plans nothing and a code change plans its import closure;
a rewrite with the same bytes does not cascade; a killed run is recovered by one command with byte-identical
outputs; and docs/reruns.md is what the workflow does."""
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from smoke import ROOT, SNAKEMAKE, descendants, job_counts, snake, snapshot


def test_second_run_has_nothing_to_do(smoke_run):
    repo, workdir, _ = smoke_run
    out = snake(repo, workdir, "-n").stdout
    assert "Nothing to be done" in out or job_counts(out) == {}, out[-2000:]


def test_forcerun_volume_redoes_only_its_dependents(smoke_run):
    repo, workdir, _ = smoke_run
    dot = snake(repo, workdir, "--rulegraph").stdout
    downstream = descendants(dot, "volume")
    counts = job_counts(snake(repo, workdir, "-n", "--forcerun", "volume").stdout)
    assert counts.get("volume", 0) >= 1
    assert set(counts) <= downstream | {"all"}, (counts, downstream)
    if "sky" in counts or "tileset" in counts:
        pytest.fail(f"stages independent of the volume were scheduled: {counts}")


def test_editing_a_volume_module_reruns_the_volume(smoke_run):
    repo, workdir, _ = smoke_run
    module = repo / "src" / "natscene" / "volume" / "procedural.py"
    original = module.read_text()
    try:
        module.write_text(original + "\n_AN_EDIT = 1\n")
        counts = job_counts(snake(repo, workdir, "-n").stdout)
        assert counts.get("volume", 0) >= 1, counts
        assert "sky" not in counts
    finally:
        module.write_text(original)
    assert job_counts(snake(repo, workdir, "-n").stdout) == {}


@pytest.mark.parametrize("path", ["src/natscene/io.py", "scripts/sky_resample.py"])
def test_comment_and_docstring_edits_plan_nothing(smoke_run, path):
    """Fingerprints follow the code's meaning: a comment and a docstring added to natscene/io.py (imported by
    nearly every script) or to a rule script plan no job; a change of the script's code plans its rule."""
    repo, workdir, _ = smoke_run
    module = repo / path
    original = module.read_text()
    try:
        module.write_text(original.replace('"""', '"""An edited docstring. ', 1) + "\n# a comment\n")
        assert module.read_text() != original
        assert job_counts(snake(repo, workdir, "-n").stdout) == {}
        if path.startswith("scripts/"):
            module.write_text(original + "\n_AN_EDIT = 1\n")
            assert "sky_resample" in job_counts(snake(repo, workdir, "-n").stdout)
    finally:
        module.write_text(original)


def _reversed(node):
    """The same mapping with every level's keys in reverse order."""
    if isinstance(node, dict):
        return {k: _reversed(node[k]) for k in reversed(list(node))}
    if isinstance(node, list):
        return [_reversed(v) for v in node]
    return node


def test_equivalent_configs_plan_nothing(smoke_run, tmp_path):
    """Params in a canonical form: the smoke config with every mapping's keys reversed, defaults written out
    (precompute.skylight, fit.population) and a whole number for a float (a view's sun elevation 35 -> 35.0,
    precompute.skylight.turbidity 3.0 -> 3) plans no job."""
    import yaml
    repo, workdir, _ = smoke_run
    cfg = yaml.safe_load((repo / "config" / "smoke.yaml").read_text())
    cfg["precompute"].setdefault("skylight", {}).update(model="preetham", turbidity=3)
    cfg["fit"].setdefault("population", 20)
    cfg["views"]["tiny"]["sun"]["elevation"] = float(cfg["views"]["tiny"]["sun"]["elevation"])
    f = tmp_path / "equivalent.yaml"
    f.write_text(yaml.safe_dump(_reversed(cfg), sort_keys=False))
    counts = job_counts(snake(repo, workdir, "-n", configfile=f).stdout)
    assert counts == {}, counts


def test_a_forced_rerun_that_writes_the_same_bytes_does_not_cascade(smoke_run):
    """--forcerun sky --until sky rewrites the same bytes; the next run plans nothing, because the workflow
    profile (profiles/default) compares files by content up to a size above the main job's largest sky product.
    With Snakemake's files compared by time alone (a threshold below their size) the same rewrite cascades."""
    import OpenImageIO as oiio
    import yaml
    repo, workdir, _ = smoke_run
    snake(repo, workdir, "--forcerun", "sky", "--until", "sky")
    assert job_counts(snake(repo, workdir, "-n").stdout) == {}
    assert job_counts(snake(repo, workdir, "-n", "--max-checksum-file-size", "10").stdout) != {}
    limit = yaml.safe_load((ROOT / "profiles" / "default" / "config.yaml").read_text())["max-checksum-file-size"]
    main = yaml.safe_load((ROOT / "config" / "config.yaml").read_text())
    for photo in main["photos"].values():
        inp = oiio.ImageInput.open(str(ROOT / photo["path"]))
        w, h = inp.spec().width, inp.spec().height
        inp.close()
        assert limit > w * h * 3 * 4 * 2, (photo["path"], w, h)      # float32 RGB EXR, uncompressed, twice over


def test_cache_needs_its_folder_and_says_so_in_one_line(smoke_run, tmp_path):
    """--cache precompute without $SNAKEMAKE_OUTPUT_CACHE fails with one line naming the variable (no traceback);
    with it, the cached rule is planned from the cache folder."""
    repo, workdir, _ = smoke_run
    env = {k: v for k, v in os.environ.items() if k != "SNAKEMAKE_OUTPUT_CACHE"}
    proc = snake(repo, workdir, "-n", "--cache", "precompute", check=False, env=env)
    out = proc.stdout + proc.stderr
    assert proc.returncode != 0 and "SNAKEMAKE_OUTPUT_CACHE" in out, out[-2000:]
    assert "Traceback" not in out, out[-3000:]
    env["SNAKEMAKE_OUTPUT_CACHE"] = str(tmp_path)
    proc = snake(repo, workdir, "-n", "--cache", "precompute", env=env)
    assert proc.returncode == 0


def _edited(repo: Path, tmp_path: Path, path: str, value) -> Path:
    """The smoke config with the key at ``path`` set to ``value``, in a file."""
    import yaml
    from rerun_table import changed
    f = tmp_path / "edited.yaml"
    f.write_text(yaml.safe_dump(changed(yaml.safe_load((repo / "config" / "smoke.yaml").read_text()), path, value),
                                sort_keys=False))
    return f


@pytest.mark.parametrize("path, value, expected", [
    # a per-entry setting reruns its entry's job alone
    ("leaves.cases.warm_autumn.delta_T", 5.0, {"leaf_season": 1}),
    ("mie.demo.silver_lining.distance", 41000.0, {"mie_render": 1}),
    # a setting the pigment maps never read reruns the colour and what uses it, not the reaction-diffusion maps
    ("patterns.tiny_spot.concentration", 1.5, {"pattern_color": 1, "pattern_sheet": 1, "composite": 2,
                                               "composite_reference": 2, "composite_preview": 2,
                                               "composite_compare": 2}),
    # adding a composite frame renders that frame alone
    ("composite.garden.frames", [0, 1, 2], {"composite": 1, "composite_reference": 1, "composite_preview": 1,
                                            "composite_compare": 1}),
    # one more tile size builds that texture from the existing tile set
    ("tiles.grass.sizes", [[256, 192], [96, 96]], {"tile_texture": 1}),
    # a preview-only setting redraws the previews, renders no frame
    ("shots.tiny.exposure", 1.234, {"frame_preview": 3, "animation": 1, "filmstrip": 1, "composite_preview": 2,
                                    "composite_compare": 2}),
    ("shots.tiny.fps", 24, {"animation": 1}),
    ("shots.tiny.filmstrip.height", 40, {"filmstrip": 1}),
    ("fit.contact_columns", 3, {"fit_sheet": 1}),
], ids=["leaf case", "mie demo render", "pattern concentration", "composite frame", "tile size", "shot exposure",
        "shot fps", "filmstrip height", "contact sheet columns"])
def test_a_setting_reruns_only_the_jobs_that_read_it(smoke_run, tmp_path, path, value, expected):
    repo, workdir, _ = smoke_run
    counts = job_counts(snake(repo, workdir, "-n", configfile=_edited(repo, tmp_path, path, value)).stdout)
    assert counts == expected, counts


def _rule_scripts(repo: Path) -> dict:
    out = {}
    for smk in (repo / "workflow" / "rules").glob("*.smk"):
        for block in re.split(r"(?m)^(?=rule )", smk.read_text())[1:]:
            script = re.search(r'script_path\("([^"]+)"\)', block)
            if script:
                out[re.match(r"rule (\w+):", block).group(1)] = repo / "scripts" / script.group(1)
    return out


@pytest.fixture(scope="module")
def smoke_dag(smoke_run):
    """(rules with jobs in the smoke DAG, the rule graph) of the finished smoke run."""
    repo, workdir, _ = smoke_run
    in_dag = set(job_counts(snake(repo, workdir, "-n", "--forceall").stdout)) - {"all"}
    return in_dag, snake(repo, workdir, "--rulegraph").stdout


@pytest.mark.parametrize("module", ["color", "geometry"])
def test_editing_a_library_module_reruns_exactly_its_importers(smoke_run, smoke_dag, module):
    """Fingerprints from the code: editing natscene/<module>.py reruns exactly the rules whose scripts import it
    (transitively, lazy imports included; the importers found by the standard library's modulefinder).

    Snakemake schedules the rules downstream of a rerun job too (their input will change); its summary
    (--summary) marks the outputs whose own params (the code fingerprint among them) changed: exactly the
    importers' outputs. The rules the dry run plans besides are downstream of them."""
    import modulefinder
    repo, workdir, _ = smoke_run
    in_dag, dot = smoke_dag
    importers = set()
    for rule, script in _rule_scripts(repo).items():
        mf = modulefinder.ModuleFinder(path=[str(repo / "src")])
        mf.run_script(str(script))
        if f"natscene.{module}" in mf.modules:
            importers.add(rule)
    expected = importers & in_dag
    assert expected and (module == "color" or in_dag - expected)
    f = repo / "src" / "natscene" / f"{module}.py"
    original = f.read_text()
    try:
        f.write_text(original + "\n_AN_EDIT = 1\n")
        summary = snake(repo, workdir, "--summary").stdout
        planned = job_counts(snake(repo, workdir, "-n").stdout)
    finally:
        f.write_text(original)
    rows = [line.split("\t") for line in summary.splitlines() if line.count("\t") == 5]
    assert {r[2] for r in rows if r[4] == "params changed"} == expected
    downstream = set().union(*(descendants(dot, r) for r in expected))
    assert expected <= set(planned) <= downstream


def test_a_killed_run_is_recovered_by_one_command(smoke_run):
    """kill -9 a forced rerun of the sky mid-job: it leaves a lock and an incomplete job; natscene.recover clears
    the lock (no Snakemake process holds it) and one run with --rerun-incomplete completes, every output of the
    workflow byte-identical to the finished run's. Those are the two commands of `make run`'s recipe."""
    import signal
    import time
    from natscene.recover import clear_stale_locks, stale_locks
    repo, workdir, _ = smoke_run
    recipe = (ROOT / "Makefile").read_text().split("\nrun:", 1)[1].split("\n\n", 1)[0]
    assert "-m natscene.recover" in recipe and "--rerun-incomplete" in recipe, recipe  # what make run does
    results = workdir / "results"
    before = snapshot(results)
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
    snake(repo, workdir, "--rerun-incomplete")
    assert job_counts(snake(repo, workdir, "-n").stdout) == {}
    after = snapshot(results)
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


def test_the_rerun_table_of_the_docs_is_what_the_workflow_does(smoke_run):
    """docs/reruns.md (tools/rerun_table.py) holds, per config key group, the jobs Snakemake plans after a change
    to it on this finished smoke run; every section of the smoke config has a row."""
    import yaml
    from rerun_table import CHANGES, DOC, HEADER, rows, table
    repo, workdir, _ = smoke_run
    sections = set(yaml.safe_load((repo / "config" / "smoke.yaml").read_text())) - {"results"}
    assert sections <= {path.split(".")[0] for path, _ in CHANGES}
    assert DOC.read_text() == HEADER + table(rows(repo, workdir)), "docs/reruns.md is stale: tools/rerun_table.py"
