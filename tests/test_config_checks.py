"""Whole-config checks before any job starts (natscene.config_checks, natscene.resources): every dangling
cross-reference, missing input file, degenerate camera, sun below the horizon and job too big for the memory
is refused with the key's path."""
import copy
from pathlib import Path

import pytest

from natscene.config import load_yaml_config, validate_config
from natscene.config_checks import camera_problem, check_config, config_problems
from natscene.errors import ConfigError
from natscene.resources import MODEL, declared_mb, estimate_mem_mb, mem_mb, memory_problems

ROOT = Path(__file__).resolve().parents[1]
SCHEMA = ROOT / "workflow" / "schemas" / "config.schema.yaml"


@pytest.fixture(scope="module")
def smoke():
    return validate_config(load_yaml_config(ROOT / "config" / "smoke.yaml"), SCHEMA)


@pytest.mark.parametrize("name", ["config.yaml", "smoke.yaml"])
def test_bundled_configs_have_no_problems(name):
    cfg = validate_config(load_yaml_config(ROOT / "config" / name), SCHEMA)
    assert config_problems(cfg, ROOT) == []
    assert memory_problems(cfg, ROOT, {"mem_mb": 16000}) == []


def _set(path, value):
    def f(c):
        node = c
        for k in path[:-1]:
            node = node[k]
        node[path[-1]] = value
    return f


def _no_shot(**entry):
    """The smoke composite made a composite without a shot (its own camera, background and sun), with ``entry``."""
    def f(c):
        del c["composite"]["garden"]["shot"]
        c["composite"]["garden"].update(entry)
    return f


CASES = [
    # cross-references
    ("keyframe photo", _set(["keyframes", "tiny", "photo"], "nope"), "keyframes.tiny.photo", "'nope' is not in 'photos'"),
    ("keyframe volume", _set(["keyframes", "tiny", "volume"], "nope"), "keyframes.tiny.volume", "not in 'volumes'"),
    ("keyframe view", _set(["keyframes", "tiny", "view"], "nope"), "keyframes.tiny.view", "not in 'views'"),
    ("pair volume", _set(["precompute", "pairs"], [{"volume": "nope", "view": "tiny"}]), "precompute.pairs[0].volume",
     "not in 'volumes'"),
    ("pair view", _set(["precompute", "pairs"], [{"volume": "tiny", "view": "nope"}]), "precompute.pairs[0].view",
     "not in 'views'"),
    ("shot volume", _set(["shots", "tiny", "volume"], "nope"), "shots.tiny.volume", "not in 'volumes'"),
    ("shot fit", lambda c: c["shots"]["tiny"]["keyframes"][0].__setitem__("fit", "nope"), "shots.tiny.keyframes[0].fit",
     "not in 'keyframes'"),
    ("shot keyframe past end", lambda c: c["shots"]["tiny"]["keyframes"][1].__setitem__("at", 7),
     "shots.tiny.keyframes[1].at", "past the shot's last frame"),
    ("shot keyframe without fit or params", lambda c: c["shots"]["tiny"]["keyframes"][0].__setitem__("fit", None),
     "shots.tiny.keyframes[0].sun", "needed when the keyframe has no 'fit'"),
    ("mie demo volume", _set(["mie", "demo", "volume"], "nope"), "mie.demo.volume", "not in 'volumes'"),
    ("composite shot", _set(["composite", "garden", "shot"], "nope"), "composite.garden.shot", "'nope' is not in 'shots'"),
    ("composite frame past shot", _set(["composite", "garden", "frames"], [0, 5]), "composite.garden.frames",
     "frames [5] are past the last frame (2) of shot 'tiny'"),
    ("composite flower pattern", lambda c: c["composite"]["garden"]["meadow"]["flowers"][0].__setitem__("pattern", "nope"),
     "composite.garden.meadow.flowers[0].pattern", "'nope' is not in 'patterns'"),
    ("composite tiles product", lambda c: c["composite"]["garden"]["ground"].__setitem__(
        "texture", {"product": "tiles/nope/synth_256x192.exr"}), "composite.garden.ground.texture.product",
     "not in 'tiles'"),
    ("composite pattern product", lambda c: c["composite"]["garden"]["meadow"]["leaves"]["textures"].__setitem__(
        0, {"product": "patterns/nope/color.exr"}), "composite.garden.meadow.leaves.textures[0].product",
     "not in 'patterns'"),
    ("composite leaf date", lambda c: c["composite"]["garden"]["meadow"]["leaves"]["textures"].__setitem__(
        1, {"product": "leaves/maple/normal/12-31.exr"}), "composite.garden.meadow.leaves.textures[1].product",
     "not in 'leaves.dates'"),
    ("composite unknown product", lambda c: c["composite"]["garden"]["ground"].__setitem__(
        "texture", {"product": "renders/x.exr"}), "composite.garden.ground.texture.product", "not a product of any stage"),
    ("composite sky_product", lambda c: c["composite"]["garden"]["sun"].__setitem__("sky_product", "sky/nope/sun.yaml"),
     "composite.garden.sun.sky_product", "not in 'photos'"),
    ("composite beetle layer material", lambda c: c["composite"]["garden"]["meadow"]["beetles"][0].__setitem__(
        "layers", [{"material": "Unobtainium", "thickness_nm": 100}]),
     "composite.garden.meadow.beetles[0].layers[0].material", "no measured index data for material 'Unobtainium'"),
    ("composite beetle substrate", lambda c: c["composite"]["garden"]["meadow"]["beetles"][0].__setitem__(
        "substrate", "-1.5+0.2j"), "composite.garden.meadow.beetles[0].substrate", "need n > 0"),
    # a composite without a shot: its own background plate, camera and sun
    ("composite background shot product", _no_shot(background={"product": "shots/nope/frames/{frame:04d}.exr"}),
     "composite.garden.background.product", "not in 'shots'"),
    ("composite background frame past shot", _no_shot(background={"product": "shots/tiny/frames/{frame:04d}.exr"},
                                                      frames=[0, 5]),
     "composite.garden.background.product", "frames [5] are past the last frame (2) of shot 'tiny'"),
    ("mie demo deck", _set(["mie", "demo", "deck"], "nope"), "mie.demo.deck", "'nope' is not in 'volumes'"),
    ("mie demo deck missing", _set(["mie", "demo", "deck"], None), "mie.demo.deck",
     "names no volume, but the demo shots ['glory', 'fogbow'] look at the deck"),
    # input files
    ("volume file without path", _set(["volumes", "tiny"], {"kind": "file"}), "volumes.tiny.path", "needed with kind: file"),
    ("volume file missing", _set(["volumes", "tiny"], {"kind": "file", "path": "nope.npy"}), "volumes.tiny.path", "not found"),
    ("photo missing", _set(["photos", "kite", "path"], "resources/photos/nope.jpg"), "photos.kite.path", "not found"),
    ("mask missing", _set(["photos", "kite", "mask"], "nope_mask.png"), "photos.kite.mask", "not found"),
    ("tile example missing", lambda c: c["tiles"]["grass"].update(path="nope.png", product=None), "tiles.grass.path",
     "not found"),
    ("recolour photo missing", _set(["recolour", "tiny_flower", "photo"], "nope.jpg"), "recolour.tiny_flower.photo",
     "not found"),
    ("petal shape missing", _set(["patterns", "tiny_spot", "shape"], {"kind": "file", "path": "nope.png"}),
     "patterns.tiny_spot.shape.path", "not found"),
    ("composite image missing", lambda c: c["composite"]["garden"]["ground"].__setitem__("texture", {"path": "nope.png"}),
     "composite.garden.ground.texture.path", "not found"),
    ("composite background missing", _no_shot(background={"path": "nope_{frame}.png"}),
     "composite.garden.background.path", "nope_0.png not found"),
    # geometry
    ("view camera at look_at", lambda c: c["views"]["tiny"]["camera"].update(position=[0, 0.3, 0], look_at=[0, 0.3, 0]),
     "views.tiny.camera", "equals look_at"),
    ("view up parallel", lambda c: c["views"]["tiny"]["camera"].update(position=[0, 0, 0], look_at=[0, 5, 0]),
     "views.tiny.camera", "parallel to the view direction"),
    ("shot camera at look_at", lambda c: c["shots"]["tiny"]["keyframes"][1]["camera"].update(
        position=[1, 1, 1], look_at=[1, 1, 1]), "shots.tiny.keyframes[1].camera", "equals look_at"),
    ("composite camera up parallel", _no_shot(camera={"position": [0, 0, 0], "look_at": [0, -1, 0], "up": [0, 1, 0],
                                                      "fov": 40}), "composite.garden.camera", "parallel"),
    ("view does not see its volume", lambda c: c["views"]["tiny"]["camera"].update(look_at=[0.0, -2000.0, 0.0]),
     "views.tiny", "does not see volume 'tiny'"),
    ("view looks away from its volume", lambda c: c["views"]["tiny"]["camera"].update(look_at=[0.0, 1.7, -6000.0]),
     "views.tiny", "0 % of the frame"),
    ("view sun below horizon", lambda c: c["views"]["tiny"]["sun"].__setitem__("elevation", -5),
     "views.tiny.sun.elevation", "below the horizon"),
    ("shot sun below horizon", lambda c: c["shots"]["tiny"]["keyframes"][1]["sun"].__setitem__("elevation", -2),
     "shots.tiny.keyframes[1].sun.elevation", "below the horizon"),
    ("composite sun below horizon", _no_shot(sun={"azimuth": 10, "elevation": -10}),
     "composite.garden.sun.elevation", "below the horizon"),
    ("mie sun below horizon", _set(["mie", "demo", "sun"], {"azimuth": 10, "elevation": 0}), "mie.demo.sun.elevation",
     "below the horizon"),
    # value relations
    ("extinction not increasing", _set(["precompute", "extinction"], [0.0, 0.5, 0.3]), "precompute.extinction",
     "strictly increasing"),
    ("fit extinction not covered by the nodes", _set(["fit", "ranges"], {"extinction": [0.02, 0.5]}),
     "fit.ranges.extinction", "precompute.extinction"),
    ("fit extinction unphysical", _set(["fit", "ranges"], {"extinction": [0.00001, 0.3]}), "fit.ranges.extinction",
     "physical range"),
    ("fit extinction above 1 /m", _set(["fit", "ranges"], {"extinction": [0.02, 3.0]}), "fit.ranges.extinction",
     "physical range"),
    ("g not increasing", _set(["precompute", "g"], [0.5, 0.5]), "precompute.g", "strictly increasing"),
    # feature-aware textures (Dong Ch. 6)
    ("texture photo missing", _set(["textures", "meadow", "path"], "resources/nope.jpg"), "textures.meadow.path",
     "not found"),
    ("texture output smaller than a neighbourhood", _set(["textures", "meadow", "output", "size"], [12, 96]),
     "textures.meadow.output.size", "largest neighbourhood 16"),
    ("quilting cell larger than the example", lambda c: c["textures"]["meadow"].update(
        method="quilting") or c["textures"]["meadow"]["quilting"].update(cell=64), "textures.meadow.quilting.cell", "does not fit in the 96x76"),
    ("target scale without the example's", lambda c: c["textures"]["meadow"]["scale"].__setitem__("from", "none"),
     "textures.meadow.output.scale", "scale feature"),
    ("tiles example twice", _set(["tiles", "grass", "path"], "resources/textures/grass_meadow_128.png"), "tiles.grass",
     "exactly one"),
    ("tiles example of no stage", lambda c: c["tiles"]["grass"].update(path=None, product="textures/nope/synth.png"),
     "tiles.grass.product", "not in 'textures'"),
]


@pytest.mark.parametrize("label, mutate, key, words", CASES, ids=[c[0] for c in CASES])
def test_config_problem_names_the_key(smoke, label, mutate, key, words):
    cfg = copy.deepcopy(smoke)
    mutate(cfg)
    with pytest.raises(ConfigError) as e:
        check_config(cfg, ROOT, source="smoke.yaml")
    msg = str(e.value)
    assert f"config key '{key}'" in msg and words in msg and "smoke.yaml" in msg, msg


def test_a_shot_composite_is_not_refused_for_the_settings_the_shot_replaces(smoke):
    """With ``shot`` the frame's camera, sun and cloud plate replace the composite's camera, sun and background
    (schema: "camera, resolution, background and sky are then not used"): a degenerate camera, a sun below the
    horizon or a missing background file there refuse nothing; the same values without the shot are refused."""
    cfg = copy.deepcopy(smoke)
    cfg["composite"]["garden"].update(camera={"position": [0, 1, 0], "look_at": [0, 1, 0], "up": [0, 1, 0], "fov": 40},
                                      sun={"azimuth": 10, "elevation": -10}, background={"path": "nope.png"})
    assert config_problems(cfg, ROOT) == []
    del cfg["composite"]["garden"]["shot"]
    keys = sorted(p.split("'")[1] for p in config_problems(cfg, ROOT))
    assert keys == ["composite.garden.background.path", "composite.garden.camera", "composite.garden.sun.elevation"]


def test_all_problems_are_reported_at_once(smoke):
    cfg = copy.deepcopy(smoke)
    cfg["keyframes"]["tiny"]["photo"] = "nope"
    cfg["views"]["tiny"]["sun"]["elevation"] = -1
    assert len(config_problems(cfg, ROOT)) == 2


def test_box_coverage_counts_the_frame_that_meets_the_box():
    """The share of the frame whose rays meet a box: a box filling the view, half of it, none of it."""
    from natscene.geometry import Camera, box_coverage
    cam = Camera((0.0, 0.0, -10.0), (0.0, 0.0, 0.0), (0.0, 1.0, 0.0), fov=40, width=64, height=48)
    assert box_coverage(cam, (-100, -100, -1), (100, 100, 1)) == 1.0
    assert box_coverage(cam, (0, -100, -1), (100, 100, 1)) == pytest.approx(0.5, abs=0.02)
    assert box_coverage(cam, (-1, -1, -30), (1, 1, -20)) == 0.0          # behind the camera
    assert box_coverage(cam, (-1, 50, -1), (1, 60, 1)) == 0.0            # above the frame


def test_camera_problem_geometry():
    assert camera_problem({"position": [0, 0, -1], "look_at": [0, 0, 0], "up": [0, 1, 0]}) is None
    assert camera_problem({"position": [0, 0, 0], "look_at": [0, 0, 0], "up": [0, 1, 0]}) is not None
    assert camera_problem({"position": [0, 0, 0], "look_at": [0, 0, 1], "up": [0, 0, 2]}) is not None
    assert camera_problem({"position": [0, 0, 0], "look_at": [0, 0, 1], "up": [0, 0, 0]}) is not None
    # a nearly-but-not parallel up is fine (the basis is well defined)
    assert camera_problem({"position": [0, 0, 0], "look_at": [0, 0, 1], "up": [0, 0.01, 1]}) is None


# -------------------------------------------------------------------------------------------------- memory
def test_declared_memory_grows_with_the_inputs(smoke):
    small, _ = estimate_mem_mb("volume", smoke, {"volume": "tiny"}, ROOT)
    cfg = copy.deepcopy(smoke)
    cfg["volumes"]["tiny"]["resolution"] = [512, 512, 512]
    big, key = estimate_mem_mb("volume", cfg, {"volume": "tiny"}, ROOT)
    assert big > small and key == "volumes.tiny.resolution"
    p_small, _ = estimate_mem_mb("precompute", smoke, {"volume": "tiny", "view": "tiny"}, ROOT)
    cfg["views"]["tiny"]["resolution"] = [1920, 1080]
    p_big, _ = estimate_mem_mb("precompute", cfg, {"volume": "tiny", "view": "tiny"}, ROOT)
    assert p_big > p_small
    # the sky's order-1 shadow rays: their points a cell, in cells of fine_voxels
    assert smoke["precompute"]["transport"] == "all_orders"
    cfg["precompute"]["all_orders"]["sky_order1_points"] = 0
    p_none, _ = estimate_mem_mb("precompute", cfg, {"volume": "tiny", "view": "tiny"}, ROOT)
    cfg["precompute"]["all_orders"]["sky_order1_points"] = 256
    cfg["precompute"]["all_orders"]["fine_voxels"] = 1
    p_fine, _ = estimate_mem_mb("precompute", cfg, {"volume": "tiny", "view": "tiny"}, ROOT)
    assert p_fine > p_big > p_none


def test_job_too_big_is_refused_with_estimate_and_key(smoke, monkeypatch):
    cfg = copy.deepcopy(smoke)
    cfg["volumes"]["tiny"]["resolution"] = [1024, 1024, 1024]
    declared, _ = estimate_mem_mb("volume", cfg, {"volume": "tiny"}, ROOT)
    monkeypatch.setenv("NATSCENE_MEMORY_MB", str(declared - 100))
    problems = memory_problems(cfg, ROOT)
    assert any("rule volume" in p and "volumes.tiny.resolution" in p and "GB" in p for p in problems), problems
    with pytest.raises(ConfigError, match="volumes.tiny.resolution"):
        mem_mb("volume", cfg, {"volume": "tiny"}, ROOT)
    # snakemake --resources mem_mb takes precedence over the environment
    assert memory_problems(cfg, ROOT, {"mem_mb": 10 ** 7}) == []
    monkeypatch.setenv("NATSCENE_MEMORY_MB", str(declared + 100))
    assert not [p for p in memory_problems(cfg, ROOT) if "rule volume" in p]


def test_job_overhead_is_added_to_every_job(smoke, monkeypatch):
    """On SLURM a job's --mem also holds two Snakemake processes (docs/cluster.md): $NATSCENE_JOB_OVERHEAD_MB
    (set by tools/slurm_run.py) is added to each rule's mem_mb; a bad value names the variable."""
    monkeypatch.delenv("NATSCENE_JOB_OVERHEAD_MB", raising=False)
    local, _ = estimate_mem_mb("volume", smoke, {"volume": "tiny"}, ROOT)
    monkeypatch.setenv("NATSCENE_JOB_OVERHEAD_MB", "400")
    assert estimate_mem_mb("volume", smoke, {"volume": "tiny"}, ROOT)[0] == local + 400
    monkeypatch.setenv("NATSCENE_JOB_OVERHEAD_MB", "lots")
    with pytest.raises(ConfigError, match="NATSCENE_JOB_OVERHEAD_MB"):
        estimate_mem_mb("volume", smoke, {"volume": "tiny"}, ROOT)


def test_user_grid_size_is_read_from_its_header(smoke, tmp_path):
    import numpy as np
    from natscene.resources import grid_file_voxels
    a = np.lib.format.open_memmap(tmp_path / "g.npy", mode="w+", dtype=np.float32, shape=(512, 300, 512))
    del a  # a sparse file: the header says 512 x 300 x 512, nothing is read
    assert grid_file_voxels(tmp_path / "g.npy") == 512 * 300 * 512
    cfg = copy.deepcopy(smoke)
    cfg["volumes"]["tiny"] = {"kind": "file", "path": str(tmp_path / "g.npy")}
    _, key = estimate_mem_mb("volume", cfg, {"volume": "tiny"}, ROOT)
    assert key == "volumes.tiny.path"


def test_declared_memory_covers_every_measured_peak():
    """Every job measured by benchmarks/memory.py (peak RSS from the kernel, tests/data/memory_measured.json:
    smoke to 512^3 volumes, 640x480 frames, 4096^2 textures, 4.9 MP photos) fits in the mem_mb its rule
    declares for the same inputs, and no rule of the workflow lacks a model."""
    import json
    rows = json.loads((ROOT / "tests" / "data" / "memory_measured.json").read_text())
    short = [(r["case"], r["rule"], r["peak_mb"], declared_mb(r["model"], r["features"])) for r in rows
             if declared_mb(r["model"], r["features"]) < r["peak_mb"]]
    assert not short, short
    assert {r["model"] for r in rows} <= set(MODEL)
    import re
    rules = set()
    for smk in (ROOT / "workflow" / "rules").glob("*.smk"):
        rules |= set(re.findall(r'estimated_mem_mb\("(\w+)"\)', smk.read_text()))
    assert rules <= set(MODEL), rules - set(MODEL)


def test_mie_jobs_are_sized_by_the_volumes_they_read(smoke):
    """The Mie demo's deck is the volume `mie.demo.deck` names: its point_scatter job and the glory and fogbow
    renders (cloud: deck) grow with that volume's resolution, the silver lining (cloud: volume) with the demo
    volume's; a mie_blend shot plans the point_scatter job of its own volume."""
    from natscene.resources import job_features, planned_jobs
    cfg = copy.deepcopy(smoke)
    deck, demo = cfg["mie"]["demo"]["deck"], cfg["mie"]["demo"]["volume"]
    assert (deck, demo) == ("deck", "tiny")
    cfg["volumes"]["deck"]["resolution"] = [640, 40, 640]            # 16.4 M voxels, the tiny cumulus 51 200
    big = 640 * 40 * 640
    _, f, keys = job_features("point_scatter", cfg, {"volume": deck}, ROOT)
    assert f["voxels"] == big and keys["voxels"] == "volumes.deck.resolution"
    for shot, voxels in (("glory", big), ("fogbow", big), ("silver_lining", 40 * 32 * 40)):
        _, f, _ = job_features("mie_render", cfg, {"volume": demo, "shot": shot}, ROOT)
        assert f["voxels"] == voxels, shot
    declared, key = estimate_mem_mb("point_scatter", cfg, {"volume": deck}, ROOT)
    assert declared > estimate_mem_mb("point_scatter", smoke, {"volume": deck}, ROOT)[0]
    assert key == "volumes.deck.resolution"
    planned = {(r, tuple(sorted(wc.items()))) for r, wc, _ in planned_jobs(cfg)}
    assert {("point_scatter", (("volume", "deck"),)), ("point_scatter", (("volume", "tiny"),))} <= planned
    cfg["mie"]["demo"]["volume"] = None                              # no demo: the tiny_mie shot still needs it
    planned = [(r, wc, e) for r, wc, e in planned_jobs(cfg) if r == "point_scatter"]
    assert planned == [("point_scatter", {"volume": "tiny"}, "shots.tiny_mie.phase")]


def test_composite_memory_follows_its_shot_and_meadow(smoke):
    """A composite with a shot renders at the shot's resolution (the key to name is the shot's); its textures are
    the ground, each flower pattern map and each leaf texture (as read and as warped)."""
    from natscene.resources import job_features
    cfg = copy.deepcopy(smoke)
    entry = cfg["composite"]["garden"]
    _, f, keys = job_features("composite", cfg, {"name": "garden"}, ROOT)
    w, h = cfg["shots"]["tiny"]["resolution"]
    assert f["samples"] == w * h * entry["spp"] and keys["samples"] == "shots.tiny.resolution"
    ground = 256 * 192                                               # tiles/grass/synth_256x192.exr
    pattern = 64 * 64                                                # patterns.tiny_spot.size
    leaves = 2 * (48 * 48 + 64 * 64)                                 # leaves.size^2 + texture_size^2, two textures
    assert f["texture_pixels"] == ground + pattern + leaves
    cfg["shots"]["tiny"]["resolution"] = [1920, 1080]
    cfg["patterns"]["tiny_spot"]["size"] = [2048, 2048]
    _, g, _ = job_features("composite", cfg, {"name": "garden"}, ROOT)
    assert g["samples"] == 1920 * 1080 * entry["spp"]
    assert g["texture_pixels"] == ground + 2048 * 2048 + leaves
