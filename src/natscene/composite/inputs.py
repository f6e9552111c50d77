"""Turn a validated ``composite.<name>`` config entry into a :class:`natscene.composite.scene.SetSpec`:
image sources (results products such as the shot's cloud frames, the tile texture and pattern colour maps;
bundled files; flat colours, gradients, checkers), the background plate resampled to the render resolution,
the sky dome read from the plate, and the sun's spectrum (Dong §2.5: D65, or matched to the fitted c_in).
"""
from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np

from natscene.composite.scene import FilmObject, Leaf, SetSpec, sun_spectrum_from_rgb
from natscene.geometry import Camera, sun_direction
from natscene.io import InputError, read_photo, read_yaml
from natscene.spectral.grid import WavelengthGrid


def image_files(source: dict, frame: int, results: str, root: str) -> list[str]:
    """The file(s) an image source reads (empty for synthetic sources)."""
    if "product" in source:
        return [str(Path(results) / source["product"].format(frame=frame))]
    if "path" in source:
        p = Path(source["path"].format(frame=frame))
        return [str(p if p.is_absolute() else Path(root) / p)]
    return []


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
        idx = (np.indices((n, n)).sum(0) % 2)
        return cols[idx]
    raise InputError(f"config {key}: image source needs one of product, path, color, gradient, checker")


def build_set(entry: dict, frame: int, results: str, root: str, sun_c_in=None) -> SetSpec:
    W, H = entry["resolution"]
    cam_cfg = entry["camera"]
    cam = Camera(tuple(cam_cfg["position"]), tuple(cam_cfg["look_at"]), tuple(cam_cfg.get("up", (0, 1, 0))),
                 float(cam_cfg.get("fov", 40)), int(W), int(H))
    bg = load_image(entry["background"], frame, results, root, (H, W), "background")[..., :3]
    if bg.shape[:2] != (H, W):
        bg = cv2.resize(bg.astype(np.float32), (W, H), interpolation=cv2.INTER_AREA).astype(np.float64)
    sky = entry.get("sky", {}) or {}
    zen = np.asarray(sky.get("zenith", bg[: max(1, H // 10)].reshape(-1, 3).mean(0)), np.float64)
    hor = np.asarray(sky.get("horizon", bg[H // 2: H // 2 + max(1, H // 10)].reshape(-1, 3).mean(0)), np.float64)
    g = entry["ground"]
    ground = load_image(g["texture"], frame, results, root, (64, 64), "ground.texture")[..., :3]
    leaves = []
    for i, lf in enumerate(entry.get("leaves", [])):
        tex = load_image(lf["texture"], frame, results, root, (32, 64), f"leaves[{i}].texture")
        leaves.append(Leaf(tex, tuple(lf["center"]), tuple(lf.get("size", (0.4, 0.25))), float(lf.get("yaw", 0)),
                           float(lf.get("tilt", 10))))
    objects = [FilmObject(tuple(o["center"]), float(o["radius"]),
                          [(l["material"], float(l["thickness_nm"])) for l in o.get("layers", [])],
                          o.get("substrate", "Cu"), float(o.get("gloss", 200)), tuple(o.get("highlight_rgb", (0.04,) * 3)))
               for o in entry.get("objects", [])]
    wl = entry.get("wavelengths", {})
    grid = WavelengthGrid(float(wl.get("start", 380)), float(wl.get("stop", 780)), float(wl.get("step", 5)))
    sun = {**entry["sun"], **sun_from_shot(entry, frame, results)}
    if sun_c_in is not None:
        sun["c_in"] = sun_c_in
    c_in = np.asarray(sun.get("c_in", sun.get("color", (1, 1, 1))), np.float64)
    return SetSpec(cam, bg, ground, float(g["size"]), float(g["repeat"]), leaves, objects,
                   sun_direction(sun["azimuth"], sun["elevation"]),
                   sun_spectrum_from_rgb(c_in, float(sun["intensity"]), grid, sun.get("spd", "d65")),
                   sky_zenith=zen, sky_horizon=hor, spp=int(entry["spp"]), grid=grid,
                   upsampling=entry["upsampling"], angle_step_deg=float(entry["angle_step_deg"]))


def sun_files(entry: dict, frame: int, results: str) -> list[str]:
    """Result files the sun of a composite frame reads: a sky product's sun.yaml and/or a shot frame's state."""
    sun = entry["sun"]
    return [str(Path(results) / sun[k].format(frame=frame)) for k in ("sky_product", "shot_state") if sun.get(k)]


def sun_c_in_from_product(entry: dict, results: str):
    """c_in from a sky product's sun.yaml when ``sun.sky_product`` is set, else None."""
    p = entry["sun"].get("sky_product")
    if not p:
        return None
    data = read_yaml(Path(results) / p)
    if not isinstance(data, dict) or "c_in" not in data:
        raise InputError(f"{Path(results) / p}: no c_in key (expected the sky stage's sun.yaml)")
    return data["c_in"]


def sun_from_shot(entry: dict, frame: int, results: str) -> dict:
    """Sun of a shot frame when ``sun.shot_state`` names the frame's interpolated state
    (``shots/<shot>/params/{frame:04d}.yaml``): ``{azimuth, elevation, c_in}`` so the set is lit like the
    clouds behind it; {} otherwise."""
    p = entry["sun"].get("shot_state")
    if not p:
        return {}
    path = Path(results) / p.format(frame=frame)
    data = read_yaml(path)
    try:
        return {"azimuth": float(data["sun"]["azimuth"]), "elevation": float(data["sun"]["elevation"]),
                "c_in": [float(c) for c in data["params"]["c_in"]]}
    except (TypeError, KeyError, ValueError) as e:
        raise InputError(f"{path} (config composite sun.shot_state): expected keys sun.azimuth, sun.elevation and "
                         f"params.c_in (the interpolate stage's frame state); {e!r}") from None
