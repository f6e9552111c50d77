"""
Inputs of the set
=================

Defines how a validated ``composite.<name>`` config entry becomes a :class:`natscene.composite.set_spec.SetSpec`:

-   :func:`build_set`: the set of one frame of a composite.
-   :func:`load_image`, :func:`cutout_texture`: image sources and cut-out textures.
-   :func:`frame_state`, :func:`reference_distance`, :func:`sun_c_in_from_product`: what the shot and the sky
    products give the set.

With ``shot``: frame k of the composite is frame k of that shot, so the set is seen by the frame's camera
(``shots/<shot>/params/<frame>.yaml``), at the shot's ``resolution``, in front of the frame's cloud plate
(``shots/<shot>/frames/<frame>.exr``, rendered from the same camera: the cloud sits at its real distance and
altitude), lit by the frame's sun (direction, c_in, L_in) and sky (the shot's ``sky`` settings), hazed with the
frame's κ_a over the camera-to-cloud distance of the shot's volume (its ``meta.yaml`` bounding box). Without
``shot``: an explicit camera, resolution, background image, sun and sky.

Image sources: results products, bundled files, flat colours, gradients, checkers. Petal textures are the
pattern maps ``patterns/<pattern>/color.exr`` (alpha = petal outline); leaf textures are season stages warped
onto the maple outline (:mod:`natscene.composite.maple`). Cut-out textures have their colours extended past
the outline before their mip levels are built, so that filtered edges keep the petal's colour.

References
----------
-   Dong, W. (2007). Rendering Algorithms for Natural Scenes. PhD thesis, Université Henri Poincaré - Nancy I.
"""
from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace

import cv2
import numpy as np

from natscene.composite.maple import MapleOutline, extend_colours, warp_season_map
from natscene.composite.meadow import build_meadow
from natscene.composite.files import image_files, pattern_product, shot_files
from natscene.composite.set_spec import Atmosphere, Film, Ground, SetSpec, sun_spectrum_from_rgb
from natscene.composite.sky_dome import gradient_sky, shot_sky
from natscene.composite.texture import MipTexture
from natscene.errors import InputError
from natscene.geometry import Camera, sun_direction
from natscene.io import read_photo, read_yaml
from natscene.spectral.grid import WavelengthGrid

__all__ = ["load_image", "cutout_texture",
           "frame_state", "reference_distance", "build_set", "sun_c_in_from_product"]


def load_image(source: dict, frame: int, results: str, root: str, shape=(64, 64), key: str = "image") -> np.ndarray:
    """Linear float (h, w, 3 or 4) for an image source; synthetic ones are made at ``shape`` (h, w)."""
    files = image_files(source, frame, results, root)
    if files:
        a = read_photo(files[0], keep_alpha=True)
        if a.shape[-1] == 1:
            a = np.repeat(a, 3, -1)
        if not np.all(np.isfinite(a)):
            raise InputError(f"{files[0]} (config {key}): image holds NaN/inf values; re-run the stage that made it")
        return a.astype(np.float64)
    h, w = shape
    if "color" in source:
        return np.broadcast_to(np.asarray(source["color"], np.float64), (h, w, 3)).copy()
    if "gradient" in source:
        t = np.linspace(0, 1, h)[:, None, None]
        top, bot = np.asarray(source["gradient"]["top"]), np.asarray(source["gradient"]["bottom"])
        return np.broadcast_to(top * (1 - t) + bot * t, (h, w, 3)).copy()
    if "checker" in source:
        c = source["checker"]
        n = int(c.get("squares", 8))
        cols = np.asarray(c["colors"], np.float64)
        return cols[np.indices((n, n)).sum(0) % 2]
    raise InputError(f"config {key}: image source needs one of product, path, color, gradient, checker")


def cutout_texture(rgba: np.ndarray) -> np.ndarray:
    """RGBA with the colours continued past alpha > 0.5 (straight, not premultiplied, alpha kept)."""
    a = np.asarray(rgba, np.float32)
    if a.shape[-1] < 4:
        return a
    return np.concatenate([extend_colours(a[..., :3], a[..., 3]), a[..., 3:4]], -1)


def frame_state(path: str) -> dict:
    """The interpolate stage's frame state: camera, sun, params (c_in, L_in, kappa_a)."""
    data = read_yaml(path)
    try:
        cam = data["camera"]
        return {"camera": {"position": [float(v) for v in cam["position"]],
                           "look_at": [float(v) for v in cam["look_at"]],
                           "up": [float(v) for v in cam["up"]], "fov": float(cam["fov"])},
                "azimuth": float(data["sun"]["azimuth"]), "elevation": float(data["sun"]["elevation"]),
                "c_in": [float(c) for c in data["params"]["c_in"]], "L_in": float(data["params"]["L_in"]),
                "kappa_a": np.broadcast_to(np.asarray(data["params"].get("kappa_a", 0.0), np.float64), (3,)).copy()}
    except (TypeError, KeyError, ValueError) as e:
        raise InputError(f"{path}: expected the interpolate stage's frame state (keys camera.position/look_at/fov, "
                         f"sun.azimuth/elevation, params.c_in/L_in/kappa_a); {e!r}") from None


def reference_distance(camera_position, volume_meta: str) -> float:
    """Camera-to-cloud distance that normalises t_c in the cloud frames (the shot volume's bbox centre)."""
    from natscene.scatter.tables import reference_distance as ref
    meta = read_yaml(volume_meta)
    try:
        vol = SimpleNamespace(bbox_min=np.asarray(meta["bbox_min"], np.float64),
                              bbox_max=np.asarray(meta["bbox_max"], np.float64))
    except (TypeError, KeyError) as e:
        raise InputError(f"{volume_meta}: no bbox_min/bbox_max (expected the volume stage's meta.yaml); "
                         f"{e!r}") from None
    return ref(SimpleNamespace(position=np.asarray(camera_position, np.float64)), vol)


def build_set(entry: dict, frame: int, results: str, root: str, shot_cfg: dict | None = None,
              sun_c_in=None) -> SetSpec:
    """The set of frame ``frame`` of a composite (``shot_cfg``: the validated ``shots.<shot>`` entry)."""
    origin = np.asarray(entry["origin"], np.float64)
    sun_cfg = dict(entry["sun"])
    atmosphere = None
    if entry.get("shot"):
        if shot_cfg is None:
            raise InputError(f"config composite: shot {entry['shot']!r} is not in 'shots'")
        f = shot_files(entry["shot"], shot_cfg["volume"], frame, results)
        st = frame_state(f["state"])
        W, H = shot_cfg["resolution"]
        c = st["camera"]
        cam = Camera(tuple(np.subtract(c["position"], origin)), tuple(np.subtract(c["look_at"], origin)),
                     tuple(c["up"]), c["fov"], int(W), int(H))
        plate = read_photo(f["plate"])[..., :3].astype(np.float64)
        if plate.shape[:2] != (H, W):
            raise InputError(f"{f['plate']}: {plate.shape[1]}x{plate.shape[0]}, but shots.{entry['shot']}.resolution "
                             f"is {W}x{H}; re-run render_frame")
        sun_cfg.update(azimuth=st["azimuth"], elevation=st["elevation"], c_in=st["c_in"])
        if sun_cfg.get("intensity") is None:
            sun_cfg["intensity"] = st["L_in"]
        sun_dir = sun_direction(sun_cfg["azimuth"], sun_cfg["elevation"])
        sky = shot_sky(shot_cfg.get("sky"), sun_dir)
        atmosphere = Atmosphere(st["kappa_a"], reference_distance(c["position"], f["volume"]))
    else:
        W, H = entry["resolution"]
        cc = entry["camera"]
        cam = Camera(tuple(np.subtract(cc["position"], origin)), tuple(np.subtract(cc["look_at"], origin)),
                     tuple(cc["up"]), float(cc["fov"]), int(W), int(H))
        plate = load_image(entry["background"], frame, results, root, (H, W), "background")[..., :3]
        if plate.shape[:2] != (H, W):
            plate = cv2.resize(plate.astype(np.float32), (W, H), interpolation=cv2.INTER_AREA).astype(np.float64)
        sk = entry.get("sky", {}) or {}
        zen = sk.get("zenith", plate[: max(1, H // 10)].reshape(-1, 3).mean(0))
        hor = sk.get("horizon", plate[H // 2: H // 2 + max(1, H // 10)].reshape(-1, 3).mean(0))
        sky = gradient_sky(zen, hor)
        sun_dir = sun_direction(sun_cfg["azimuth"], sun_cfg["elevation"])
        if sun_cfg.get("intensity") is None:
            sun_cfg["intensity"] = 3.0
    if sun_c_in is not None:
        sun_cfg["c_in"] = sun_c_in
    c_in = np.asarray(sun_cfg.get("c_in", sun_cfg.get("color", (1, 1, 1))), np.float64)
    wl = entry["wavelengths"]
    grid = WavelengthGrid(float(wl["start"]), float(wl["stop"]), float(wl["step"]))
    # ground
    g = entry["ground"]
    gt = load_image(g["texture"], frame, results, root, (64, 64), "ground.texture")[..., :3]
    if g.get("albedo") is not None:  # a photo texture is exposure-relative: scale its mean luminance to an albedo
        y = float((gt.reshape(-1, 3) @ np.array([0.2126, 0.7152, 0.0722])).mean())
        gt = gt * (float(g["albedo"]) / max(y, 1e-9))
    ground = Ground(MipTexture(np.clip(gt, 0, 1), wrap=True), tuple(g.get("extent", (2.0, 2.0))),
                    tuple(g.get("offset", (0.0, 0.0))))
    # meadow
    meadow = entry.get("meadow") or {}
    petals = {}
    for i, fl in enumerate(meadow.get("flowers", [])):
        if fl["pattern"] not in petals:
            tex = load_image(pattern_product(fl["pattern"]), frame, results, root, key=f"meadow.flowers[{i}]")
            if tex.shape[-1] < 4:
                raise InputError(f"{image_files(pattern_product(fl['pattern']), frame, results, root)[0]} (config "
                                 f"meadow.flowers[{i}].pattern): the pattern map has no alpha (petal outline)")
            petals[fl["pattern"]] = cutout_texture(np.clip(tex, 0, 1))
    leaves = []
    lv = meadow.get("leaves") or {}
    outline = MapleOutline()
    for i, src in enumerate(lv.get("textures", [])):
        season = load_image(src, frame, results, root, key=f"meadow.leaves.textures[{i}]").astype(np.float32)
        size = int(lv.get("texture_size", 256))
        leaves.append(cutout_texture(warp_season_map(season, outline, size)))
    films = [Film(f"beetle{i}", [(l["material"], float(l["thickness_nm"]))
                                 for l in b.get("layers", [{"material": "Au", "thickness_nm": 500.0}])],
                  b.get("substrate", "Cu"), float(b.get("gloss", 200)), tuple(b.get("highlight_rgb", (0.04,) * 3)))
             for i, b in enumerate(meadow.get("beetles", []))]
    surfaces, films, shapes = build_meadow(meadow, petals, leaves, films, ground) if meadow else ([], films, [])
    return SetSpec(cam, plate, ground, surfaces, films, shapes, sun_dir,
                   sun_spectrum_from_rgb(c_in, float(sun_cfg["intensity"]), grid, sun_cfg.get("spd", "matched")),
                   sky=sky, atmosphere=atmosphere, spp=int(entry["spp"]), max_aniso=int(entry.get("max_aniso", 16)),
                   grid=grid, upsampling=entry["upsampling"], angle_step_deg=float(entry["angle_step_deg"]))


def sun_c_in_from_product(entry: dict, results: str):
    """c_in from a sky product's sun.yaml when ``sun.sky_product`` is set, else None."""
    p = entry["sun"].get("sky_product")
    if not p:
        return None
    data = read_yaml(Path(results) / p)
    if not isinstance(data, dict) or "c_in" not in data:
        raise InputError(f"{Path(results) / p}: no c_in key (expected the sky stage's sun.yaml)")
    return data["c_in"]
