"""
Memory of the jobs
==================

Defines honest memory: each rule's ``mem_mb`` computed from its inputs, and jobs that cannot fit refused up
front:

-   :func:`mem_mb`: the ``mem_mb`` of one job for its rule's ``resources``.
-   :func:`memory_problems`: the configured jobs whose estimate exceeds what one job may use
    (:func:`available_memory_mb`).
-   :func:`estimate_mem_mb`, :func:`declared_mb`, :func:`model_mb`: a job's estimate, from the model
    :data:`MODEL` with :data:`MARGIN` and :data:`SLACK_MB`.
-   :func:`job_features`, :func:`planned_jobs`, :func:`grid_file_voxels`: the features of a job, the size-dependent
    jobs of a config, the voxels of a user grid.

A job's peak resident memory is modelled as ``base + sum_f coef_f * feature_f`` with the features of
:func:`job_features` (voxels of the volume it reads or makes, pixels of its image, Monte Carlo samples,
table entries, ...). The coefficients in :data:`MODEL` are least-squares fits to peak RSS measured with
``getrusage`` (every job logs its peak, see :mod:`natscene.runner`) over several sizes per rule, by
``benchmarks/memory.py``, which writes ``results/benchmarks/memory.json`` and prints the coefficients
to paste here after a change to a stage's memory use.

The declared ``mem_mb`` is the model times :data:`MARGIN` plus :data:`SLACK_MB` (so Snakemake and a cluster
scheduler reserve what the job needs), rounded up to 100 MB. Before any job starts (:func:`memory_problems`,
called from the Snakefile) every configured product's jobs are estimated, and a job whose estimate exceeds
the memory available to one job (:func:`available_memory_mb`: ``--resources mem_mb=...`` if given, else
``$NATSCENE_MEMORY_MB``, else the machine's memory or its cgroup limit) is refused with the estimate and the
config key that sets its size.
"""
from __future__ import annotations

import math
import os
import struct
from pathlib import Path

import numpy as np

from natscene.config import resolve_path
from natscene.errors import ConfigError

__all__ = ["mem_mb", "memory_problems", "available_memory_mb", "estimate_mem_mb", "declared_mb", "model_mb",
           "MODEL", "MARGIN", "SLACK_MB", "job_features", "planned_jobs", "grid_file_voxels"]

MB = 1024.0 * 1024.0
MARGIN = 1.2  # declared = MARGIN * model + SLACK_MB
SLACK_MB = 200.0

#: rule -> {"base": MB, feature: MB per unit}. Fitted by benchmarks/memory.py (see the module docstring).
MODEL: dict[str, dict[str, float]] = {  # bytes per unit / MB; n = measured jobs, residual = largest misfit
    "animation": {"base": 182.7, "pixels": 35.93 / MB},  # n=2, max residual 0.0 MB
    "composite": {"base": 323.9, "samples": 0 / MB, "texture_pixels": 173 / MB},  # n=4, max residual 115.3 MB
    # the same script and images as frame_preview (one EXR read, its PNG)
    "composite_preview": {"base": 156.0, "pixels": 212 / MB},
    # measured by hand (two EXRs read, a strip three frames wide: 640x480 and 1920x1080)
    "composite_compare": {"base": 160.0, "pixels": 578 / MB},  # n=2 (338 and 1358 MB)
    "composite_reference": {"base": 373.6, "spectral_samples": 8.105 / MB, "texture_pixels": 0 / MB},  # n=3, max residual 0.5 MB
    # measured by hand (one frame read + its PNG: 221 MB at 640x480, 595 MB at 1920x1080 peak RSS)
    "frame_preview": {"base": 156.0, "pixels": 212 / MB},  # n=2
    # measured by hand (peak RSS of the script's reads and drawing: 320x240 and 640x480 views, 11 renders)
    "fit_sheet": {"base": 197.0, "pixels": 43 / MB},  # n=2
    # measured by hand (6 frames: 187 MB at 640x480, 221 MB at 1920x1080)
    "filmstrip": {"base": 181.0, "pixels": 3.3 / MB},  # n=2
    "fit": {"base": 298.3, "pixels": 2275 / MB, "table_values": 0 / MB},  # n=2, max residual 0.0 MB
    # all-orders tables (8 + 4x3 band images per node): one main-job run (kite, 320x240, 7 extinctions x 5 g,
    # 55.9 M table values): 1008 MB peak -> 9.7 bytes per value over base and pixels (the tables as read, their
    # pixel-compressed copy for the GA and the EXR reader's buffers)
    "fit_all_orders": {"base": 298.3, "pixels": 2275 / MB, "table_values": 9.72 / MB},  # n=1
    "interpolate": {"base": 162.0},  # n=8, max residual 0.0 MB
    "leaf_season": {"base": 266.5, "pixels": 223.5 / MB},  # n=5, max residual 0.0 MB
    "mie_render": {"base": 330.0, "pixels": 1068 / MB, "voxels": 64.25 / MB},  # n=6, max residual 2.3 MB
    "mie_table": {"base": 320.0},  # n=2, max residual 0.0 MB
    "mie_table_droplets": {"base": 319.0},  # n=2, max residual 0.0 MB
    "pattern_color": {"base": 265.1, "pixels": 249.4 / MB},  # n=4, max residual 0.3 MB
    "pattern_sheet": {"base": 192.0, "pixels": 256 / MB},  # n=2, max residual 0.0 MB
    "pigment_maps": {"base": 165.6, "pixels": 725.4 / MB},  # n=4, max residual 4.0 MB
    "point_scatter": {"base": 227.1, "voxels": 67.19 / MB},  # n=8, max residual 4.6 MB
    # all-orders transport: one main-job run (cumulus 160x112x160, 320x240, 7 extinctions x 5 g, 8 + 4x3 bands):
    # 1655 MB peak, 55.9 M table values -> 22.5 bytes per value over base and voxels. The sky's order-1 shadow
    # rays (natscene.scatter.sky_first.shadow_samples) hold 26.7 bytes a point for the whole run, in the cloud's
    # occupied cells only, which are not known before the volume is made: the feature is the bound (every fine
    # cell of the grid x sky_order1_points) and the coefficient 26.7 bytes x the main job's occupancy (43 k of
    # 358 k cells, 12 %). Main job (8 x 5 nodes, 82.3 M table values, 256 points a cell): 2444 MB modelled,
    # 2545 MB peak in a fresh-clone run
    "precompute_all_orders": {"base": 365.9, "table_values": 22.5 / MB, "voxels": 12.15 / MB,
                              "shadow_point_bound": 3.2 / MB},  # n=2
    "precompute": {"base": 365.9, "paths": 353.6 / MB, "pixels": 0 / MB, "table_values": 0 / MB, "voxels": 12.15 / MB},  # n=5, max residual 145.3 MB
    "recolour": {"base": 288.7, "pixels": 452.4 / MB},  # n=3, max residual 0.5 MB
    "render_frame": {"base": 467.5, "paths": 0 / MB, "pixels": 1323 / MB, "voxels": 44.89 / MB},  # n=8, max residual 85.4 MB
    # all-orders frames: the photons' wavefront grows with the collision budget, 4.7 bytes per collision (one
    # 640x480 main-job frame at 4 M and 37.5 M collisions: 1243 and 1401 MB); the base is raised so that the
    # main job's frames (31 M + 23 M collisions: 1387-1470 MB in an earlier run, 1251-1288 MB of the declared
    # 2100 in the fresh-clone run of 726a883) sit under the model
    "render_frame_all_orders": {"base": 708.0, "pixels": 1323 / MB, "voxels": 44.89 / MB,
                                "collisions": 4.7 / MB},  # n=26 + 2
    "sky": {"base": 204.5, "pixels": 684.8 / MB},  # n=3, max residual 8.9 MB
    "sky_resample": {"base": 184.7, "pixels": 62.58 / MB},  # n=2, max residual 0.0 MB
    # measured on the main job's three entries (64-82 k example pixels; peak RSS 227-240 MB, 1098-1219 MB with the
    # lambda-0 baseline, 1005 MB) and the smoke run's (7 k pixels: 241, 280, 268 MB): the example's neighbourhood
    # vectors of every size dominate
    "texture_features": {"base": 230.0, "pixels": 130 / MB},
    "feature_synthesis": {"base": 280.0, "pixels": 12000 / MB, "output_pixels": 0 / MB},
    "texture_completion": {"base": 270.0, "pixels": 10000 / MB},
    "tile_texture": {"base": 185.2, "pixels": 182 / MB},  # n=5, max residual 40.2 MB
    "tileset": {"base": 184.7, "pixels": 2390 / MB},  # n=4, max residual 0.0 MB
    "volume": {"base": 181.9, "voxels": 40.13 / MB},  # n=6, max residual 7.1 MB
    "volume_file": {"base": 167.1, "voxels": 29.74 / MB},  # n=3, max residual 0.0 MB
}


# -------------------------------------------------------------------------------------------- sizes
def image_size(path: str | os.PathLike) -> tuple[int, int] | None:
    """(width, height) of an image from its header (no decoding); None when it cannot be read."""
    import OpenImageIO as oiio

    inp = oiio.ImageInput.open(str(path))
    if inp is None:
        return None
    try:
        spec = inp.spec()
        return int(spec.width), int(spec.height)
    finally:
        inp.close()


def grid_file_voxels(path: str | os.PathLike) -> int | None:
    """Voxels of a user grid from its header: ``.npy`` (numpy header) or Mitsuba ``.vol``; None if unknown."""
    path = Path(path)
    try:
        with open(path, "rb") as f:
            if path.suffix.lower() == ".npy":
                version = np.lib.format.read_magic(f)
                read = np.lib.format.read_array_header_1_0 if version == (1, 0) else \
                    np.lib.format.read_array_header_2_0
                shape = read(f)[0]  # the header only, no data
                return int(np.prod(shape))
            head = f.read(24)
            if head[:3] == b"VOL" and len(head) == 24:
                _, nx, ny, nz, nc = struct.unpack("<iiiii", head[4:24])
                return int(nx) * int(ny) * int(nz) * int(nc)
    except (OSError, ValueError):
        return None
    return None


def volume_voxels(config: dict, name: str, root) -> tuple[int, str]:
    """(voxels, the config key that sets them) of volume ``name`` of ``volumes`` (the Mie demo's deck included:
    it is the volume ``mie.demo.deck`` names)."""
    v = config["volumes"][name]
    if v["kind"] == "file" and v.get("path"):
        n = grid_file_voxels(resolve_path(v["path"], root))
        if n is not None:
            return n, f"volumes.{name}.path"
    return int(np.prod(v["resolution"])), f"volumes.{name}.resolution"


def _paths_per_pass(pixels: int, spp: int, batch_spp=None) -> int:
    """Monte Carlo paths in flight in one Dr.Jit pass (natscene.scatter.multiple.trace_orders: about 2 million,
    at least one sample per pixel, unless batch_spp is given)."""
    if batch_spp:
        return pixels * int(batch_spp)
    return pixels * max(1, min(int(spp), 2_000_000 // max(pixels, 1)))


def _shadow_point_bound(config: dict, voxels: int) -> int:
    """The grid's fine cache cells (``voxels`` / ``precompute.all_orders.fine_voxels``³) x
    ``precompute.all_orders.sky_order1_points``: the most shadow-ray points the precompute can hold (it places
    them in the cloud's occupied cells only, :func:`natscene.scatter.sky_first.shadow_samples`)."""
    ao = config["precompute"]["all_orders"]
    return -(-int(voxels) // int(ao["fine_voxels"]) ** 3) * int(ao["sky_order1_points"])


def _pixels(res) -> int:
    return int(res[0]) * int(res[1])


def _table_values(config: dict, pixels: int) -> int:
    """Float values of the precompute tables: 4 single-scattering/geometry images per extinction node, plus per
    (g, extinction) the n_m - 1 orders (dobashi) or the sun's bands and the sky's bands x 4 channels (all_orders)."""
    pre = config["precompute"]
    n_s = len(pre["extinction"])
    n_g = len(pre["g"])
    per_node = _transport(pre["transport"]).values_per_node(pre)
    return pixels * n_s * (4 + n_g * per_node)


def _transport(name: str):
    from natscene.scatter.transport import get
    return get(name)


def _texture_pixels(config: dict, src: dict | None, root) -> int:
    """Pixels of a composite image source (tiles, leaves and pattern products by their name and config, files by
    their header)."""
    if not isinstance(src, dict):
        return 0
    if "product" in src:
        import re
        m = re.search(r"synth_(\d+)x(\d+)", src["product"])
        if m:
            return int(m.group(1)) * int(m.group(2))
        if src["product"].startswith("leaves/"):  # a season stage: leaves.size squared
            return int(config["leaves"]["size"]) ** 2
        parts = src["product"].split("/")
        if parts[0] == "patterns" and len(parts) > 2 and parts[1] == "recolour":  # a recoloured flower photo
            photo = config["recolour"][parts[2]]["photo"]
            size = image_size(resolve_path(photo, root)) if photo else None
            return _pixels(size) if size else 0
        if parts[0] == "patterns" and len(parts) > 1:  # a pattern map: patterns.<name>.size
            return _pixels(config["patterns"][parts[1]]["size"])
        return 0
    if "path" in src:
        size = image_size(resolve_path(src["path"], root))
        return _pixels(size) if size else 0
    return 0


def _composite_texture_pixels(config: dict, entry: dict, root) -> int:
    """Texture pixels a composite frame holds (natscene.composite.inputs.build_set): the ground texture, each
    distinct flower pattern map (``patterns.<pattern>.size``), each season leaf texture as read and as warped
    onto the maple outline (``meadow.leaves.texture_size`` squared)."""
    n = _texture_pixels(config, entry["ground"]["texture"], root)
    meadow = entry["meadow"]
    for pattern in {f["pattern"] for f in meadow["flowers"]}:
        n += _pixels(config["patterns"][pattern]["size"])
    leaves = meadow.get("leaves") or {}                     # optional, no default
    for src in leaves.get("textures") or []:
        n += _texture_pixels(config, src, root) + int(leaves["texture_size"]) ** 2
    return n


def job_features(rule: str, config: dict, wildcards: dict, root) -> tuple[str, dict, dict]:
    """(model name, features, feature -> config key that sets it) of one job of ``rule``."""
    wc = dict(wildcards)
    feats: dict[str, float] = {}
    keys: dict[str, str] = {}
    model = rule
    if rule == "volume":
        feats["voxels"], keys["voxels"] = volume_voxels(config, wc["volume"], root)
        if config["volumes"][wc["volume"]]["kind"] == "file":
            model = "volume_file"  # import: measured the same for float32 and float64 .npy files
    elif rule == "precompute":
        p = _pixels(config["views"][wc["view"]]["resolution"])
        feats["voxels"], keys["voxels"] = volume_voxels(config, wc["volume"], root)
        feats["pixels"], keys["pixels"] = p, f"views.{wc['view']}.resolution"
        feats["table_values"], keys["table_values"] = _table_values(config, p), f"views.{wc['view']}.resolution"
        pre = config["precompute"]
        model = _transport(pre["transport"]).memory_model(rule)
        if "shadow_point_bound" in MODEL[model]:
            feats["shadow_point_bound"] = _shadow_point_bound(config, feats["voxels"])
            keys["shadow_point_bound"] = "precompute.all_orders.sky_order1_points"
        if "paths" in MODEL[model]:
            feats["paths"] = _paths_per_pass(p, pre["spp"], pre["batch_spp"])
            keys["paths"] = "precompute.batch_spp"
    elif rule == "fit":
        kf = config["keyframes"][wc["keyframe"]]
        p = _pixels(config["views"][kf["view"]]["resolution"])
        feats["pixels"], keys["pixels"] = p, f"views.{kf['view']}.resolution"
        feats["table_values"], keys["table_values"] = _table_values(config, p), f"views.{kf['view']}.resolution"
        model = _transport(config["precompute"]["transport"]).memory_model(rule)
    elif rule in ("sky", "sky_resample"):
        ph = config["photos"][wc["photo"]]
        size = image_size(resolve_path(ph["path"], root))
        feats["pixels"], keys["pixels"] = (_pixels(size) if size else 0), f"photos.{wc['photo']}.path"
    elif rule == "render_frame":
        shot = config["shots"][wc["shot"]]
        feats["voxels"], keys["voxels"] = volume_voxels(config, shot["volume"], root)
        p = _pixels(shot["resolution"])
        feats["pixels"], keys["pixels"] = p, f"shots.{wc['shot']}.resolution"
        r = shot["render"]
        model = _transport(r["transport"]).memory_model(rule)
        if "collisions" in MODEL[model]:
            feats["collisions"] = int(r["sun_collisions"]) + int(r["sky_collisions"])
            keys["collisions"] = f"shots.{wc['shot']}.render.sun_collisions"
        if "paths" in MODEL[model]:
            feats["paths"] = _paths_per_pass(p, r["spp"])
            keys["paths"] = f"shots.{wc['shot']}.resolution"
    elif rule == "point_scatter":
        feats["voxels"], keys["voxels"] = volume_voxels(config, wc["volume"], root)
    elif rule == "mie_render":
        demo = config["mie"]["demo"]
        # the glory and fogbow (cloud: deck) look at the deck volume, the silver lining at the demo volume
        name = demo["deck"] if demo[wc["shot"]]["cloud"] == "deck" else wc["volume"]
        feats["voxels"], keys["voxels"] = volume_voxels(config, name, root)
        feats["pixels"], keys["pixels"] = _pixels(demo["resolution"]), "mie.demo.resolution"
    elif rule in ("composite", "composite_reference"):
        c = config["composite"][wc["name"]]
        if c.get("shot"):  # frame k of the shot: its camera and resolution
            p = _pixels(config["shots"][c["shot"]]["resolution"])
            key = f"shots.{c['shot']}.resolution"
        else:
            p = _pixels(c["resolution"])
            key = f"composite.{wc['name']}.resolution"
        spp = int(c["spp"])
        if rule == "composite":
            feats["samples"], keys["samples"] = p * spp, key
        else:
            wl = c["wavelengths"]
            n_wl = int(round((float(wl["stop"]) - float(wl["start"])) / float(wl["step"]))) + 1
            feats["spectral_samples"], keys["spectral_samples"] = p * spp * n_wl, key
        feats["texture_pixels"] = _composite_texture_pixels(config, c, root)
        keys["texture_pixels"] = f"composite.{wc['name']}.ground.texture"
    elif rule in ("composite_preview", "composite_compare"):
        c = config["composite"][wc["name"]]
        res = config["shots"][c["shot"]]["resolution"] if c.get("shot") else c["resolution"]
        feats["pixels"] = _pixels(res)
        keys["pixels"] = f"shots.{c['shot']}.resolution" if c.get("shot") else f"composite.{wc['name']}.resolution"
    elif rule == "tileset":
        t = config["tiles"][wc["texture"]]
        if t["path"]:
            size = image_size(resolve_path(t["path"], root))
            feats["pixels"], keys["pixels"] = (_pixels(size) if size else 0), f"tiles.{wc['texture']}.path"
        else:  # another stage's product: a feature-aware synthesis has its configured output size
            parts = str(t["product"]).split("/")
            tex = config["textures"].get(parts[1]) if parts[0] == "textures" and len(parts) > 1 else None
            size = tex["output"]["size"] if tex else None
            feats["pixels"], keys["pixels"] = (_pixels(size) if size else 0), f"tiles.{wc['texture']}.product"
    elif rule in ("texture_features", "texture_completion", "feature_synthesis"):
        t = config["textures"][wc["name"]]
        size = t["working_size"] or image_size(resolve_path(t["path"], root))
        feats["pixels"], keys["pixels"] = (_pixels(size) if size else 0), f"textures.{wc['name']}.working_size"
        if rule == "feature_synthesis":
            feats["output_pixels"] = _pixels(t["output"]["size"])
            keys["output_pixels"] = f"textures.{wc['name']}.output.size"
    elif rule == "tile_texture":
        feats["pixels"], keys["pixels"] = int(wc["w"]) * int(wc["h"]), f"tiles.{wc['texture']}.sizes"
    elif rule in ("pigment_maps", "pattern_color"):
        feats["pixels"], keys["pixels"] = _pixels(config["patterns"][wc["pattern"]]["size"]), \
            f"patterns.{wc['pattern']}.size"
    elif rule == "pattern_sheet":
        feats["pixels"] = sum(_pixels(p["size"]) for p in config["patterns"].values())
        keys["pixels"] = "patterns.<name>.size"
    elif rule == "recolour":
        r = config["recolour"][wc["photo"]]
        size = image_size(resolve_path(r["photo"], root))
        feats["pixels"], keys["pixels"] = (_pixels(size) if size else 0), f"recolour.{wc['photo']}.photo"
    elif rule == "leaf_season":
        lv = config["leaves"]
        feats["pixels"] = int(lv["size"]) ** 2 * len(lv["dates"])
        keys["pixels"] = "leaves.size"
    elif rule == "frame_preview":
        shot = config["shots"][wc["shot"]]
        feats["pixels"] = _pixels(shot["resolution"])
        keys["pixels"] = f"shots.{wc['shot']}.resolution"
    elif rule == "animation":
        shot = config["shots"][wc["shot"]]
        feats["pixels"] = _pixels(shot["resolution"]) * int(shot["frames"])
        keys["pixels"] = f"shots.{wc['shot']}.resolution"
    elif rule == "filmstrip":
        shot = config["shots"][wc["shot"]]
        count = min(int(shot["frames"]), int(shot["filmstrip"]["count"]))
        feats["pixels"] = _pixels(shot["resolution"]) * count
        keys["pixels"] = f"shots.{wc['shot']}.resolution"
    elif rule == "fit_sheet":  # the photo and the top_k ranked renders at the view's resolution
        kf = config["keyframes"][wc["keyframe"]]
        p = _pixels(config["views"][kf["view"]]["resolution"])
        feats["pixels"] = p * (1 + int(config["fit"]["top_k"]))
        keys["pixels"] = f"views.{kf['view']}.resolution"
    return model, feats, keys


def model_mb(model: str, feats: dict) -> float:
    """The modelled peak resident memory (MB) of a job."""
    coef = MODEL.get(model, {"base": 500.0})
    return coef.get("base", 0.0) + sum(coef.get(f, 0.0) * float(v) for f, v in feats.items())


def declared_mb(model: str, feats: dict) -> int:
    """The ``mem_mb`` declared for a modelled peak: MARGIN x model + SLACK_MB, rounded up to 100 MB."""
    return int(math.ceil((MARGIN * model_mb(model, feats) + SLACK_MB) / 100.0) * 100)


def estimate_mem_mb(rule: str, config: dict, wildcards: dict, root) -> tuple[int, str]:
    """(declared mem_mb, the config key of the input that dominates the estimate) of one job.

    The key is '' when the fixed part (libraries, renderer set-up) dominates: no config key makes it smaller.
    """
    model, feats, keys = job_features(rule, config, wildcards, root)
    coef = MODEL.get(model, {})
    parts = {f: coef.get(f, 0.0) * float(v) for f, v in feats.items()}
    top = max(parts, key=parts.get) if parts else None
    declared = declared_mb(model, feats) + job_overhead_mb()
    if top is None or parts[top] < coef.get("base", 0.0):
        return declared, ""
    return declared, keys.get(top, "")


def job_overhead_mb() -> int:
    """Memory a job needs besides its rule's own process (``$NATSCENE_JOB_OVERHEAD_MB``, default 0).

    On SLURM a job's memory limit covers Snakemake's batch step (about 200 MB) and the Snakemake process that
    runs the rule inside the job step (about 190 MB) as well; ``tools/slurm_run.py`` sets 400 there. Locally
    the rule runs inside the one Snakemake process that is not counted against any job, so 0."""
    env = os.environ.get("NATSCENE_JOB_OVERHEAD_MB")
    if not env:
        return 0
    try:
        v = int(float(env))
    except ValueError:
        raise ConfigError(f"$NATSCENE_JOB_OVERHEAD_MB={env!r} is not a number of megabytes") from None
    if v < 0:
        raise ConfigError(f"$NATSCENE_JOB_OVERHEAD_MB={env!r} must be >= 0")
    return v


# ------------------------------------------------------------------------------------------ machine
def machine_memory_mb() -> int:
    """Physical memory of this machine, or the cgroup (container) limit if lower, in MB."""
    total = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    for cg in ("/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory/memory.limit_in_bytes"):
        try:
            raw = Path(cg).read_text().strip()
        except OSError:
            continue
        if raw.isdigit():
            total = min(total, int(raw))
    return int(total / MB)


def available_memory_mb(global_resources: dict | None = None) -> tuple[int, str]:
    """(MB one job may use, where that number comes from)."""
    mem = (global_resources or {}).get("mem_mb")
    mem = getattr(mem, "value", mem)  # Snakemake 9 wraps parsed resources
    if isinstance(mem, (int, float)) and mem > 0 and mem < 1e12:
        return int(mem), "snakemake --resources mem_mb"
    env = os.environ.get("NATSCENE_MEMORY_MB")
    if env:
        try:
            return int(float(env)), "$NATSCENE_MEMORY_MB"
        except ValueError:
            raise ConfigError(f"$NATSCENE_MEMORY_MB={env!r} is not a number of megabytes") from None
    return machine_memory_mb(), "this machine's memory"


def planned_jobs(config: dict) -> list[tuple[str, dict, str]]:
    """(rule, wildcards, config entry) of the size-dependent jobs the configured products need."""
    jobs = []
    for v in config["volumes"]:
        jobs.append(("volume", {"volume": v}, f"volumes.{v}"))
    for p in config["precompute"]["pairs"]:
        jobs.append(("precompute", {"volume": p["volume"], "view": p["view"]}, "precompute.pairs"))
    for k, kf in config["keyframes"].items():
        jobs.append(("precompute", {"volume": kf["volume"], "view": kf["view"]}, f"keyframes.{k}"))
        jobs.append(("fit", {"keyframe": k}, f"keyframes.{k}"))
    for p in config["photos"]:
        jobs.append(("sky", {"photo": p}, f"photos.{p}"))
    for s in config["shots"]:
        jobs.append(("render_frame", {"shot": s}, f"shots.{s}"))
        jobs.append(("animation", {"shot": s}, f"shots.{s}"))
    demo = config["mie"]["demo"]
    if demo["volume"]:
        jobs.append(("point_scatter", {"volume": demo["volume"]}, "mie.demo.volume"))
        if demo["deck"]:
            jobs.append(("point_scatter", {"volume": demo["deck"]}, "mie.demo.deck"))
        for shot in ("glory", "fogbow", "silver_lining"):
            jobs.append(("mie_render", {"volume": demo["volume"], "shot": shot}, "mie.demo"))
    for s, shot in config["shots"].items():
        if shot["phase"] == "mie_blend":  # the point-to-point solutions of the shot volume, one per sun
            jobs.append(("point_scatter", {"volume": shot["volume"]}, f"shots.{s}.phase"))
    for c, entry in config["composite"].items():
        jobs.append(("composite", {"name": c}, f"composite.{c}"))
        if entry["reference"]:
            jobs.append(("composite_reference", {"name": c}, f"composite.{c}"))
    for t, spec in config["textures"].items():
        jobs.append(("texture_features", {"name": t}, f"textures.{t}"))
        jobs.append(("feature_synthesis", {"name": t}, f"textures.{t}"))
        if spec["complete"]:
            jobs.append(("texture_completion", {"name": t}, f"textures.{t}"))
    for t, spec in config["tiles"].items():
        jobs.append(("tileset", {"texture": t}, f"tiles.{t}"))
        for w, h in spec["sizes"]:
            jobs.append(("tile_texture", {"texture": t, "w": w, "h": h}, f"tiles.{t}.sizes"))
    for p in config["patterns"]:
        jobs.append(("pigment_maps", {"pattern": p}, f"patterns.{p}"))
    for r in config["recolour"]:
        jobs.append(("recolour", {"photo": r}, f"recolour.{r}"))
    if config["leaves"]:
        jobs.append(("leaf_season", {}, "leaves"))
    return jobs


def refusal(rule: str, wildcards: dict, declared: int, key: str, available: int, source: str) -> str:
    what = ", ".join(f"{k}={v}" for k, v in wildcards.items())
    todo = (f"reduce the size set by config key '{key}', or run it on a machine with more memory"
            if key else "most of it is the fixed cost of the rule's libraries: run it on a machine with more memory")
    return (f"rule {rule} ({what}) needs about {declared / 1024:.1f} GB of memory (natscene.resources estimate), "
            f"but one job may use {available / 1024:.1f} GB ({source}); {todo} (and set --resources mem_mb or "
            f"NATSCENE_MEMORY_MB there)")


def memory_problems(config: dict, root, global_resources: dict | None = None) -> list[str]:
    """A line per configured job whose memory estimate exceeds what one job may use (empty: all fit)."""
    available, source = available_memory_mb(global_resources)
    out, seen = [], set()
    for rule, wc, _entry in planned_jobs(config):
        ident = (rule, tuple(sorted(wc.items())))
        if ident in seen:
            continue
        seen.add(ident)
        try:
            declared, key = estimate_mem_mb(rule, config, wc, root)
        except (KeyError, TypeError):
            continue  # a dangling reference: reported by natscene.config_checks
        if declared > available:
            out.append(refusal(rule, wc, declared, key, available, source))
    return out


def mem_mb(rule: str, config: dict, wildcards: dict, root, global_resources: dict | None = None) -> int:
    """The ``mem_mb`` of one job for its rule's ``resources``; ConfigError when it cannot fit."""
    declared, key = estimate_mem_mb(rule, config, wildcards, root)
    available, source = available_memory_mb(global_resources)
    if declared > available:
        raise ConfigError(refusal(rule, dict(wildcards), declared, key, available, source))
    return declared
