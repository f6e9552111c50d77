"""The bad-input matrix: every stage refuses bad files and bad config keys through the real workflow.

Each case asserts a non-zero exit, a message naming the file or config key, and nothing left that a rerun
would take as complete (no output, no temporary file; a dry run schedules the job again).

- config cases: ``snakemake -n`` on a config with one mistake fails while loading the config, before any job,
  and creates no results directory;
- input cases: one ``snakemake --keep-going`` run over a config holding many bad inputs (damaged files,
  photos that are not cloud photos, volumes with NaNs, a texture too small for its tiles, ...): every job
  fails with its own message and leaves nothing behind. Positive controls in the same run: a photo accepted
  with ``accept_unusual`` is fitted with the warnings in sun.yaml and params.yaml; and the tile size the
  "choose at most N" message advises then runs.
"""
import copy
import os
import re
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import cv2
import numpy as np
import pytest
import yaml

from natscene import io

ROOT = Path(__file__).resolve().parents[1]
KITE = ROOT / "resources" / "photos" / "kite_cumulus_left.jpg"
GRASS = ROOT / "resources" / "textures" / "grass_meadow_128.png"


def _snake(workdir: Path, config: dict, *args, env=None):
    workdir.mkdir(parents=True, exist_ok=True)
    cfg = workdir / "config.yaml"
    cfg.write_text(yaml.safe_dump(config, sort_keys=False))
    e = dict(os.environ, PYTHONPATH=str(ROOT / "src"), PYTHONUNBUFFERED="1", **(env or {}))
    cmd = [sys.executable, "-m", "snakemake", "-s", str(ROOT / "Snakefile"), "--configfile", str(cfg),
           "--directory", str(workdir), "--cores", "2", *args]
    return subprocess.run(cmd, env=e, capture_output=True, text=True)


def _smoke():
    return yaml.safe_load((ROOT / "config" / "smoke.yaml").read_text())


# ----------------------------------------------------------------------------------------- config cases
def _mut(path, value):
    def f(c):
        node = c
        for k in path[:-1]:
            node = node[k]
        node[path[-1]] = value
    return f


CONFIG_CASES = {  # stage: (mutation, text that must be in the message, extra environment)
    "fit: keyframe names no photo": (_mut(["keyframes", "tiny", "photo"], "nope"), "keyframes.tiny.photo", None),
    "precompute: pair names no volume": (_mut(["precompute", "pairs"], [{"volume": "nope", "view": "tiny"}]),
                                         "precompute.pairs[0].volume", None),
    "precompute: extinction above 1 /m": (_mut(["precompute", "extinction"], [0.0, 1.0, 2.0]),
                                          "precompute.extinction[2]", None),
    "fit: extinction range beyond the nodes": (_mut(["fit", "ranges"], {"extinction": [0.02, 0.6]}),
                                               "fit.ranges.extinction", None),
    "volume: kind file without path": (_mut(["volumes", "tiny"], {"kind": "file"}), "volumes.tiny.path", None),
    "views: camera at its look-at": (lambda c: c["views"]["tiny"]["camera"].update(look_at=c["views"]["tiny"]["camera"]
                                                                                    ["position"]),
                                     "views.tiny.camera", None),
    "views: sun below the horizon": (lambda c: c["views"]["tiny"]["sun"].update(elevation=-3),
                                     "views.tiny.sun.elevation", None),
    "shots: unknown volume": (_mut(["shots", "tiny", "volume"], "nope"), "shots.tiny.volume", None),
    "composite: shot unknown": (_mut(["composite", "garden", "shot"], "nope"), "composite.garden.shot", None),
    "composite: product of no stage": (_mut(["composite", "garden", "ground", "texture"], {"product": "shots/nope/x.exr"}),
                                       "composite.garden.ground.texture.product", None),
    "composite: flower pattern unknown": (
        lambda c: c["composite"]["garden"]["meadow"]["flowers"][0].update(pattern="nope"),
        "composite.garden.meadow.flowers[0].pattern", None),
    "tiles: example missing": (lambda c: c["tiles"]["grass"].update(path="resources/textures/nope.png", product=None),
                               "tiles.grass.path", None),
    "textures: photo missing": (_mut(["textures", "meadow", "path"], "resources/textures/nope.jpg"),
                                "textures.meadow.path", None),
    "textures: slant of 90 deg": (_mut(["textures", "meadow", "scale", "slant"], 90), "textures.meadow.scale.slant",
                                  None),
    "patterns: petal shape missing": (_mut(["patterns", "tiny_spot", "shape"], {"kind": "file", "path": "no.png"}),
                                      "patterns.tiny_spot.shape.path", None),
    "recolour: photo missing": (_mut(["recolour", "tiny_flower", "photo"], "nope.jpg"), "recolour.tiny_flower.photo",
                                None),
    "mie: demo volume unknown": (_mut(["mie", "demo", "volume"], "nope"), "mie.demo.volume", None),
    "leaves: composite names a date not computed": (
        lambda c: c["composite"]["garden"]["meadow"]["leaves"]["textures"].__setitem__(
            1, {"product": "leaves/maple/normal/12-01.exr"}),
        "composite.garden.meadow.leaves.textures[1].product", None),
    "memory: a 1024^3 volume on a small machine": (_mut(["volumes", "tiny", "resolution"], [1024, 1024, 1024]),
                                                   "volumes.tiny.resolution", {"NATSCENE_MEMORY_MB": "8000"}),
}


@pytest.mark.parametrize("case", list(CONFIG_CASES), ids=list(CONFIG_CASES))
def test_config_mistake_stops_before_any_job(case, config_results):
    proc = config_results[case]
    _, words, _ = CONFIG_CASES[case]
    assert proc.returncode != 0, proc.stdout[-2000:]
    out = proc.stdout + proc.stderr
    assert f"'{words}'" in out and "ConfigError" in out, out[-3000:]


@pytest.fixture(scope="module")
def config_results(tmp_path_factory):
    base = tmp_path_factory.mktemp("config_cases")

    def one(item):
        i, case = item
        mutate, _, env = CONFIG_CASES[case]
        cfg = _smoke()
        mutate(cfg)
        work = base / f"c{i}"
        proc = _snake(work, cfg, "-n", env=env)
        assert not (work / "results").exists(), f"{case}: results created by a refused config"
        return case, proc

    with ThreadPoolExecutor(max_workers=2) as ex:
        return dict(ex.map(one, enumerate(CONFIG_CASES)))


# ------------------------------------------------------------------------------------------ input cases
def _write_inputs(d: Path) -> dict:
    """Bad input files made from the bundled ones (crops, colour transforms, truncation); name -> path."""
    d.mkdir(parents=True, exist_ok=True)
    kite = io.read_photo(KITE)
    flower = io.read_photo(ROOT / "resources" / "photos" / "freshflower.jpg")
    p = {}
    data = KITE.read_bytes()
    p["trunc2k"] = d / "kite_first_2k.jpg"
    p["trunc2k"].write_bytes(data[:2048])
    p["trunc60"] = d / "kite_60pct.jpg"
    p["trunc60"].write_bytes(data[: int(0.6 * len(data))])
    grass = io.read_photo(ROOT / "resources" / "textures" / "grass_meadow_256.png")
    g = cv2.GaussianBlur(np.tile(grass, (2, 3, 1))[:480, :640], (0, 0), 1.5)
    g[140:340, 220:420] = cv2.resize(flower[100:400, 150:450], (200, 200), interpolation=cv2.INTER_AREA)
    p["garden"] = d / "garden.png"
    io.write_png(p["garden"], g, exposure=1.0)
    y = kite @ np.array([0.2126, 0.7152, 0.0722], np.float32)
    p["overcast"] = d / "overcast.png"
    io.write_png(p["overcast"], np.clip(y[..., None] * 0.3 + 0.01, 0, 1) * np.array([0.96, 1.0, 1.06]), exposure=1.0)
    p["closeup"] = d / "cloud_closeup.png"
    io.write_png(p["closeup"], cv2.resize(np.ascontiguousarray(kite[220:400, 0:60]), (240, 720),
                                          interpolation=cv2.INTER_CUBIC), exposure=1.0)
    p["negative"] = d / "negative.exr"
    io.write_exr(p["negative"], kite - 0.05)
    nan = kite.copy()
    nan[5:9, 5:9] = np.nan
    p["nan"] = d / "nan.exr"
    io.write_exr(p["nan"], nan)
    p["grey"] = d / "grey.png"
    io.write_png(p["grey"], np.repeat(y[..., None], 3, -1), exposure=1.0)
    p["small_mask"] = d / "mask_small.png"
    io.write_png(p["small_mask"], np.ones((10, 10, 3), np.float32), encoded=True)
    tex = io.read_photo(GRASS)
    p["tex4"] = d / "grass_4x4.png"
    io.write_png(p["tex4"], tex[:4, :4], exposure=1.0)
    p["tex64"] = d / "grass_64.png"
    io.write_png(p["tex64"], tex[:64, :64], exposure=1.0)
    p["flat"] = d / "flat_grey.png"
    io.write_png(p["flat"], np.full((64, 64, 3), 0.5, np.float32), encoded=True)
    raw = GRASS.read_bytes()
    p["trunc_png"] = d / "grass_cut.png"
    p["trunc_png"].write_bytes(raw[: len(raw) // 3])
    vol = np.zeros((12, 10, 12), np.float32)
    vol[3:8, 2:7, 3:8] = 0.7
    bad = vol.copy()
    bad[5, 5, 5] = np.nan
    p["vol_nan"] = d / "vol_nan.npy"
    np.save(p["vol_nan"], bad)
    p["vol_zero"] = d / "vol_zero.npy"
    np.save(p["vol_zero"], np.zeros_like(vol))
    p["vol_2d"] = d / "vol_2d.npy"
    np.save(p["vol_2d"], vol[0])
    p["vol_corrupt"] = d / "vol_corrupt.vol"
    p["vol_corrupt"].write_bytes(b"VOL\x03" + bytes(20))
    return p


FAST_GA = {"pop_size": 6, "n_g": 2, "n_o": 1}


def _input_config(p: dict) -> dict:
    cfg = {
        "results": "results", "seed": 0, "threads": 1,
        "photos": {
            "trunc2k": {"path": str(p["trunc2k"])}, "trunc60": {"path": str(p["trunc60"])},
            "flower": {"path": "resources/photos/freshflower.jpg"}, "garden": {"path": str(p["garden"])},
            "overcast": {"path": str(p["overcast"])}, "closeup": {"path": str(p["closeup"])},
            "negative": {"path": str(p["negative"])}, "nan": {"path": str(p["nan"])}, "grey": {"path": str(p["grey"])},
            "badmask": {"path": str(KITE), "mask": str(p["small_mask"])},
            "flower_ok": {"path": "resources/photos/freshflower.jpg", "accept_unusual": True},
        },
        "sky": {"fit_resolutions": [[32, 24]]},
        "textures": {
            "small_labels": {"path": str(GRASS), "types": {"labels": str(p["small_mask"])},
                             "output": {"size": [64, 64]}},
            "no_edges": {"path": str(p["flat"]), "scale": {"from": "mask"}, "output": {"size": [64, 64]}},
        },
        "tiles": {
            "tiny4": {"path": str(p["tex4"]), "tile_size": 4, "set": "N1", "sizes": [[16, 16]], "ga": FAST_GA},
            "big_tile": {"path": str(p["tex64"]), "tile_size": 64, "set": "N1", "sizes": [[96, 96]], "ga": FAST_GA},
            "cut": {"path": str(p["trunc_png"]), "tile_size": 16, "set": "B", "sizes": [[32, 32]], "ga": FAST_GA},
        },
        "volumes": {
            "nan": {"kind": "file", "path": str(p["vol_nan"])}, "zero": {"kind": "file", "path": str(p["vol_zero"])},
            "flat": {"kind": "file", "path": str(p["vol_2d"])}, "corrupt": {"kind": "file", "path": str(p["vol_corrupt"])},
            "tiny": {"kind": "cumulus", "resolution": [24, 20, 24], "blobs": 10},
        },
        "views": {"tiny": {"camera": {"position": [0.0, 1.7, -3000.0], "look_at": [0.0, 2200.0, 0.0], "fov": 40},
                           "sun": {"azimuth": 130, "elevation": 35}, "resolution": [32, 24]}},
        "precompute": {"spp": 4, "extinction": [0.0, 0.002, 0.3], "g": [0.0, 0.8],
                       "all_orders": {"sun_collisions": 100000, "sky_collisions": 50000}},
        "keyframes": {"flower_ok": {"photo": "flower_ok", "volume": "tiny", "view": "tiny"}},
        "fit": {"n_max": 3, "population": 6, "top_k": 2},
        "patterns": {"cut_shape": {"size": [32, 32], "shape": {"kind": "file", "path": str(p["trunc_png"])}}},
        "recolour": {"cut_photo": {"photo": str(p["trunc60"]), "sim_width": 16}},
        "composite": {"cut_bg": {"frames": [0], "resolution": [32, 24], "spp": 1,
                                 "background": {"path": str(p["trunc_png"])},
                                 "ground": {"texture": {"color": [0.2, 0.4, 0.1]}}}},
    }
    return cfg


R = "results"
SKY_OUT = ["photo_linear.exr", "cloud_mask.exr", "sky.exr", "sun.yaml", "preview.png"]
INPUT_CASES = {  # name: (target, outputs that must not exist, log, text that must be in the log)
    "sky: truncated JPEG (2 KB)": ("sky/trunc2k/sun.yaml", [f"sky/trunc2k/{f}" for f in SKY_OUT],
                                   "logs/sky/trunc2k.log", "kite_first_2k.jpg: truncated JPEG"),
    "sky: truncated JPEG (60 %)": ("sky/trunc60/sun.yaml", [f"sky/trunc60/{f}" for f in SKY_OUT],
                                   "logs/sky/trunc60.log", "kite_60pct.jpg: truncated JPEG"),
    "sky: flower photo": ("sky/flower/sun.yaml", [f"sky/flower/{f}" for f in SKY_OUT], "logs/sky/flower.log",
                          "freshflower.jpg (photos.flower): this does not look like a daytime cloud photo"),
    "sky: garden photo": ("sky/garden/sun.yaml", [f"sky/garden/{f}" for f in SKY_OUT], "logs/sky/garden.log",
                          "garden.png (photos.garden)"),
    "sky: dark overcast": ("sky/overcast/sun.yaml", [f"sky/overcast/{f}" for f in SKY_OUT], "logs/sky/overcast.log",
                           "overcast.png (photos.overcast)"),
    "sky: cloud close-up without sky": ("sky/closeup/sun.yaml", [f"sky/closeup/{f}" for f in SKY_OUT],
                                        "logs/sky/closeup.log", "too little sky"),
    "sky: negative EXR values": ("sky/negative/sun.yaml", [f"sky/negative/{f}" for f in SKY_OUT],
                                 "logs/sky/negative.log", "negative.exr (photos.negative)"),
    "sky: NaN in an EXR photo": ("sky/nan/sun.yaml", [f"sky/nan/{f}" for f in SKY_OUT], "logs/sky/nan.log",
                                 "nan.exr (photos.nan): contains NaN"),
    "sky: greyscale photo": ("sky/grey/sun.yaml", [f"sky/grey/{f}" for f in SKY_OUT], "logs/sky/grey.log",
                             "grey.png (photos.grey): greyscale photo"),
    "sky: mask of the wrong size": ("sky/badmask/sun.yaml", [f"sky/badmask/{f}" for f in SKY_OUT],
                                    "logs/sky/badmask.log", "mask_small.png (photos.badmask.mask)"),
    "tiles: texture too small for any tile": ("tiles/tiny4/tileset.yaml", ["tiles/tiny4/tileset.exr",
                                              "tiles/tiny4/tileset.yaml", "tiles/tiny4/tileset.png"],
                                              "logs/tileset/tiny4.log", "'tiles.tiny4.path'"),
    "tiles: tile size too large": ("tiles/big_tile/tileset.yaml", ["tiles/big_tile/tileset.exr",
                                   "tiles/big_tile/tileset.yaml"], "logs/tileset/big_tile.log",
                                   "'tiles.big_tile.tile_size'"),
    "tiles: truncated example": ("tiles/cut/tileset.yaml", ["tiles/cut/tileset.exr", "tiles/cut/tileset.yaml"],
                                 "logs/tileset/cut.log", "grass_cut.png: truncated PNG"),
    "volume: NaN in a user grid": ("volumes/nan/meta.yaml", ["volumes/nan/density.vol", "volumes/nan/meta.yaml"],
                                   "logs/volume/nan.log", "vol_nan.npy"),
    "volume: all-zero user grid": ("volumes/zero/meta.yaml", ["volumes/zero/density.vol", "volumes/zero/meta.yaml"],
                                   "logs/volume/zero.log", "vol_zero.npy"),
    "volume: 2-D user grid": ("volumes/flat/meta.yaml", ["volumes/flat/density.vol", "volumes/flat/meta.yaml"],
                              "logs/volume/flat.log", "vol_2d.npy"),
    "volume: corrupt .vol": ("volumes/corrupt/meta.yaml", ["volumes/corrupt/density.vol",
                             "volumes/corrupt/meta.yaml"], "logs/volume/corrupt.log", "vol_corrupt.vol"),
    "patterns: truncated petal shape": ("patterns/cut_shape/maps.png", ["patterns/cut_shape/maps.png",
                                        "patterns/cut_shape/pigment_0.exr"], "logs/pigment_maps/cut_shape.log",
                                        "grass_cut.png: truncated PNG"),
    "recolour: truncated photo": ("patterns/recolour/cut_photo/recoloured.png",
                                  ["patterns/recolour/cut_photo/recoloured.exr",
                                   "patterns/recolour/cut_photo/recoloured.png"], "logs/recolour/cut_photo.log",
                                  "kite_60pct.jpg: truncated JPEG"),
    "textures: label image of another size": ("textures/small_labels/features.png",
                                              ["textures/small_labels/features.exr",
                                               "textures/small_labels/features.png"],
                                              "logs/texture_features/small_labels.log",
                                              "textures.small_labels.types.labels': 10x10"),
    "textures: empty feature mask": ("textures/no_edges/features.png", ["textures/no_edges/features.exr"],
                                     "logs/texture_features/no_edges.log", "the feature mask is empty"),
    "composite: truncated background image": ("composite/cut_bg/0000/final.png",
                                              ["composite/cut_bg/0000/final.png", "composite/cut_bg/0000/hybrid.exr"],
                                              "logs/composite/cut_bg.0000.log", "grass_cut.png: truncated PNG"),
}
CONTROL_TARGETS = ["fit/flower_ok/params.yaml"]


@pytest.fixture(scope="module")
def input_run(tmp_path_factory):
    base = tmp_path_factory.mktemp("input_cases")
    paths = _write_inputs(base / "inputs")
    config = _input_config(paths)
    work = base / "run"
    targets = [f"{R}/{t}" for t, *_ in INPUT_CASES.values()] + [f"{R}/{t}" for t in CONTROL_TARGETS]
    proc = _snake(work, config, "--keep-going", *targets)
    return work, config, proc


@pytest.mark.parametrize("case", list(INPUT_CASES), ids=list(INPUT_CASES))
def test_bad_input_fails_with_its_name_and_leaves_nothing(input_run, case):
    work, _, proc = input_run
    assert proc.returncode != 0
    target, outputs, log, words = INPUT_CASES[case]
    text = (work / R / log).read_text()
    assert words in text, text[-2000:]
    assert "Traceback" not in text, text[-3000:]  # a named refusal, not a crash
    for o in outputs:
        f = work / R / o
        assert not f.exists(), f
        stale = [x for x in f.parent.glob(f".{f.stem}.*")] if f.parent.exists() else []
        assert not stale, stale


def test_failed_jobs_are_scheduled_again(input_run):
    """Nothing a rerun would take as complete: a dry run wants every failed target again."""
    work, config, _ = input_run
    targets = [f"{R}/{t}" for t, *_ in INPUT_CASES.values()]
    proc = _snake(work, config, "-n", *targets)
    assert proc.returncode == 0, proc.stderr[-3000:]
    for t in targets:
        assert t in proc.stdout, t


def test_accepted_unusual_photo_warns_in_sun_yaml_and_fit(input_run):
    work, _, _ = input_run
    sun = yaml.safe_load((work / R / "sky/flower_ok/sun.yaml").read_text())
    unusual = [w for w in sun["warnings"] if "photos.flower_ok.accept_unusual" in w]
    assert len(unusual) == 3 and sun["plausibility"]["sun_cct_k"] < 2000
    params = yaml.safe_load((work / R / "fit/flower_ok/params.yaml").read_text())
    assert len([w for w in params["warnings"] if "accept_unusual" in w]) == 3


def test_advised_tile_size_runs(input_run, tmp_path):
    """The 'choose at most N' of the tiles stage is a value that then runs."""
    work, config, _ = input_run
    text = (work / R / "logs/tileset/big_tile.log").read_text()
    n = int(re.search(r"choose at most (\d+)", text).group(1))
    cfg = copy.deepcopy(config)
    cfg["tiles"] = {"advised": {**config["tiles"]["big_tile"], "tile_size": n}}
    for k in ("photos", "keyframes", "patterns", "recolour", "composite"):
        cfg[k] = {}
    cfg["volumes"] = {"tiny": config["volumes"]["tiny"]}
    proc = _snake(tmp_path / "advised", cfg, f"{R}/tiles/advised/synth_96x96.png")
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert (tmp_path / "advised" / R / "tiles/advised/synth_96x96.exr").is_file()
