"""The smoke workflow (config/smoke.yaml) end to end, in a temporary copy of the repository (the session fixture
``smoke_run``): it completes, every product exists and is readable, and a forced rerun of everything writes the
same bytes. What reruns after a change is tests/test_reruns.py."""
import numpy as np

from smoke import snake, snapshot


def test_smoke_workflow_completes_with_readable_outputs(smoke_run):
    repo, workdir, proc = smoke_run
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


def test_forced_rerun_is_byte_identical_and_clears_stale_temp_files(smoke_run):
    """Deterministic stages: a forced rerun of the whole smoke workflow writes the same bytes (no wall-clock time
    in any cached output, no DateTime in EXR headers); temp files of a killed earlier run are removed."""
    repo, workdir, _ = smoke_run
    results = workdir / "results"

    before = snapshot(results)
    stale = [results / "volumes/tiny/.density.k1ll3d_x.vol", results / "sky/kite/.sun.abcd1234.yaml",
             results / "precompute/tiny/tiny/.single.zz9_zz9z.exr"]
    for s in stale:
        s.write_bytes(b"half-written by a killed job")
    snake(repo, workdir, "--forceall")
    assert not [s for s in stale if s.exists()]
    after = snapshot(results)
    assert set(after) == set(before)
    changed = sorted(k for k in after if after[k] != before[k])
    assert not changed, f"outputs whose bytes changed on a forced rerun: {changed}"
