"""
Keyframes of a shot
===================

Defines a shot: keyframes on a frame axis and the parameter set of every frame (Dobashi et al. 2012, §5.2, §6):

-   :func:`validate_shot`, :func:`sorted_keyframes`, :func:`resolve_keyframe`: a shot's keyframes from the config.
-   :func:`keyframe_params`: a keyframe's full parameter set (:data:`PARAMS`, :data:`COLOURS`).
-   :func:`bracket`, :func:`camera_neighbours`: the keyframes a frame depends on.
-   :func:`frame_t`, :func:`frame_sun`, :func:`frame_state`, :func:`frame_camera`: a frame's position, sun,
    state and camera.
-   :func:`quantised_sun`, :func:`sun_key`: the sun rounded for rule ``point_scatter`` and its wildcard.

Each keyframe names a fitted parameter set (``fit: <config keyframe>``, the chosen set of
``results/fit/<keyframe>/params.yaml``) and/or explicit parameters (which override the fitted ones), a sun
direction and a camera (both default to those of the fit's view). A frame between two keyframes depends on
those two only (and, with the Catmull-Rom camera path, on the cameras of their neighbours), which is what
lets the workflow rerun only the frames a keyframe edit affects. Frames before the first / after the last
keyframe hold that keyframe.

References
----------
-   Dobashi, Y., Iwasaki, W., Ono, A., Yamamoto, T., Yue, Y., & Nishita, T. (2012). An inverse problem approach
    for automatically adjusting the parameters for rendering clouds using photographs. ACM Transactions on
    Graphics, 31(6).
"""
from __future__ import annotations

import bisect

import numpy as np

from natscene.errors import InputError
from natscene.geometry import sun_direction
from natscene.keyframes.interpolate import (catmull_rom, direction_to_sun_angles, ease, lerp, segment_t,
                                            slerp)

__all__ = ["PARAMS", "COLOURS", "validate_shot", "sorted_keyframes", "resolve_keyframe", "bracket",
           "camera_neighbours", "keyframe_params", "frame_t", "frame_sun", "quantised_sun", "sun_key", "frame_state",
           "frame_camera"]

PARAMS = ("L_in", "g", "extinction", "beta", "L_amb")  # scalars, interpolated linearly (L_amb: dobashi transport, 0 if absent)
COLOURS = ("c_in", "kappa_a")  # RGB triples, interpolated linearly per channel


def _key(shot: str, i: int | None = None) -> str:
    return f"shots.{shot}" + (f".keyframes[{i}]" if i is not None else "")


def validate_shot(name: str, shot: dict, config: dict) -> None:
    """Config-level checks of one shot (raises InputError naming the key)."""
    if shot["volume"] not in config.get("volumes", {}):
        raise InputError(f"config key '{_key(name)}.volume': {shot['volume']!r} is not in 'volumes'")
    ats = [kf["at"] for kf in shot["keyframes"]]
    if len(set(ats)) != len(ats):
        raise InputError(f"config key '{_key(name)}.keyframes': two keyframes share a frame index ({sorted(ats)})")
    if shot.get("phase", "hg") == "mie_blend":
        table = shot.get("mie_table")
        if table is not None and table not in (config.get("mie", {}).get("droplets") or {}):
            raise InputError(f"config key '{_key(name)}.mie_table': {table!r} is not in 'mie.droplets' "
                             f"(known: {sorted((config.get('mie', {}).get('droplets') or {}))}); use one of them or "
                             f"null for the default table")
    elif shot.get("mie_table") is not None:
        raise InputError(f"config key '{_key(name)}.mie_table': only used with 'phase: mie_blend' (phase is "
                         f"{shot.get('phase', 'hg')!r})")
    for i, kf in enumerate(shot["keyframes"]):
        if kf["at"] >= shot["frames"]:
            raise InputError(f"config key '{_key(name, i)}.at': frame {kf['at']} is past the shot's last frame "
                             f"{shot['frames'] - 1}; lower it or raise '{_key(name)}.frames'")
        resolve_keyframe(name, i, kf, config)


def sorted_keyframes(shot: dict) -> list[tuple[int, dict]]:
    """(config index, keyframe) pairs in frame order."""
    return sorted(enumerate(shot["keyframes"]), key=lambda p: p[1]["at"])


def resolve_keyframe(shot_name: str, index: int, kf: dict, config: dict) -> dict:
    """A keyframe of the validated config (its camera's up and fov the schema's where not given) with its sun and
    camera filled in from the fit's view where not given."""
    fit = kf.get("fit")
    view = None
    if fit is not None:
        if fit not in config.get("keyframes", {}):
            raise InputError(f"config key '{_key(shot_name, index)}.fit': {fit!r} is not in 'keyframes'")
        view = config.get("views", {}).get(config["keyframes"][fit]["view"])
    out = {"index": index, "at": int(kf["at"]), "fit": fit, "params": dict(kf.get("params") or {})}
    for part in ("sun", "camera"):
        if kf.get(part) is not None:
            out[part] = dict(kf[part])
        elif view is not None:
            out[part] = dict(view[part])
        else:
            raise InputError(f"config key '{_key(shot_name, index)}.{part}': needed when the keyframe has no "
                             f"'fit' whose view would give it")
    if fit is None:
        missing = [p for p in PARAMS + COLOURS if p not in out["params"] and p != "L_amb"]
        if missing:
            raise InputError(f"config key '{_key(shot_name, index)}.params': {missing} missing; give them or "
                             f"name a fitted keyframe with 'fit'")
    return out


def bracket(shot: dict, frame: int) -> list[int]:
    """Config indices of the keyframes frame ``frame`` depends on: the one at it, or the two around it
    (the nearest one before the first / after the last keyframe)."""
    keys = sorted_keyframes(shot)
    ats = [kf["at"] for _, kf in keys]
    j = bisect.bisect_left(ats, frame)
    if j < len(ats) and ats[j] == frame:
        return [keys[j][0]]
    if j == 0:
        return [keys[0][0]]
    if j == len(ats):
        return [keys[-1][0]]
    return [keys[j - 1][0], keys[j][0]]


def camera_neighbours(shot: dict, frame: int) -> list[int]:
    """Config indices of the keyframes a Catmull-Rom camera at ``frame`` uses (the bracket and one either side)."""
    keys = sorted_keyframes(shot)
    br = bracket(shot, frame)
    order = [i for i, _ in keys]
    lo = max(order.index(br[0]) - 1, 0)
    hi = min(order.index(br[-1]) + 1, len(order) - 1)
    return order[lo:hi + 1]


def keyframe_params(resolved: dict, fitted: dict | None, source: str = "") -> dict:
    """The full parameter set of a keyframe: the fit's chosen set overridden by the explicit ``params``."""
    out = {}
    if fitted is not None:
        chosen = fitted.get("chosen")
        if not isinstance(chosen, dict):
            raise InputError(f"{source}: no 'chosen' parameter set; rerun the fit rule")
        out.update({k: chosen[k] for k in PARAMS + COLOURS if k in chosen})
    out.update(resolved.get("params", {}))
    out.setdefault("L_amb", 0.0)
    missing = [p for p in PARAMS + COLOURS if p not in out]
    if missing:
        raise InputError(f"{source or 'keyframe'}: parameters {missing} missing (neither fitted nor given)")
    full = {p: float(out[p]) for p in PARAMS}
    for c in COLOURS:
        v = np.asarray(out[c], np.float64).reshape(-1)
        if v.size == 1:
            v = np.repeat(v, 3)
        if v.size != 3:
            raise InputError(f"{source or 'keyframe'}: '{c}' must be a number or [r, g, b], got {out[c]!r}")
        full[c] = [float(x) for x in v]
    return full


def _camera_vec(cam: dict) -> np.ndarray:
    return np.concatenate([cam["position"], cam["look_at"], cam["up"], [cam["fov"]]])


def _camera_dict(v: np.ndarray) -> dict:
    up = v[6:9] / np.linalg.norm(v[6:9])
    return {"position": v[0:3].tolist(), "look_at": v[3:6].tolist(), "up": up.tolist(), "fov": float(v[9])}


def frame_t(frame: int, keys: list[dict], easing: str = "linear") -> float:
    """The eased position t in [0, 1] of ``frame`` between its one or two keyframes (0 with one)."""
    if not 1 <= len(keys) <= 2:
        raise ValueError("frame_t: one or two keyframes")
    a, b = keys[0], keys[-1]
    return float(ease(segment_t(frame, a["at"], b["at"]), easing)) if len(keys) == 2 else 0.0


def frame_sun(keys: list[dict], t: float) -> tuple[np.ndarray, float, float]:
    """(unit direction toward the sun, azimuth, elevation) at eased position ``t`` between the keyframes' suns:
    slerp of the directions, the keyframes' own angles exactly at t = 0 and t = 1. Needs only the keyframes'
    ``sun`` entries (config), so the workflow knows every frame's sun before any job runs."""
    a, b = keys[0], keys[-1]
    d0 = sun_direction(a["sun"]["azimuth"], a["sun"]["elevation"])
    d1 = sun_direction(b["sun"]["azimuth"], b["sun"]["elevation"])
    if t == 0:
        return d0, float(a["sun"]["azimuth"]), float(a["sun"]["elevation"])
    if t == 1:
        return d1, float(b["sun"]["azimuth"]), float(b["sun"]["elevation"])
    d = slerp(d0, d1, t)
    az, el = direction_to_sun_angles(d)
    return d, az, el


def quantised_sun(azimuth: float, elevation: float, step: float = 0.5) -> tuple[float, float]:
    """The sun's angles rounded to multiples of ``step`` degrees (azimuth in [0, 360)): frames whose suns
    round alike share one point-to-point Mie solution (rule ``point_scatter``)."""
    if not step > 0:
        raise ValueError(f"quantised_sun: step must be > 0, got {step}")
    az = (round((float(azimuth) % 360.0) / step) * step) % 360.0 + 0.0
    el = min(90.0, max(-90.0, round(float(elevation) / step) * step)) + 0.0
    return float(f"{az:.6g}"), float(f"{el:.6g}")


def sun_key(azimuth: float, elevation: float) -> str:
    """The ``{sun}`` wildcard of rule ``point_scatter``: 'az130_el35', 'az112.5_el-2'."""
    return f"az{azimuth:g}_el{elevation:g}"


def frame_state(frame: int, keys: list[dict], easing: str = "linear", camera_path: str = "linear",
                path_keys: list[dict] | None = None) -> dict:
    """Everything a frame needs, from its one or two keyframes (``keys``: resolved keyframes in frame order,
    each with its full ``params`` from :func:`keyframe_params`).

    Returns {frame, t (eased), keyframes: [at...], params (scalars + c_in, kappa_a), sun: {direction,
    azimuth, elevation}, camera: {position, look_at, up, fov}}. ``path_keys`` (Catmull-Rom only): the
    resolved keyframes around the segment, in frame order, with their cameras.
    """
    if not 1 <= len(keys) <= 2:
        raise ValueError("frame_state: one or two keyframes")
    a, b = keys[0], keys[-1]
    t = frame_t(frame, keys, easing)
    params = {}
    for p in PARAMS:
        params[p] = float(lerp(a["params"][p], b["params"][p], t))
    for c in COLOURS:
        params[c] = lerp(a["params"][c], b["params"][c], t).tolist()
    d, az, el = frame_sun(keys, t)
    if camera_path == "catmull_rom" and len(keys) == 2 and path_keys and len(path_keys) > 2:
        x = a["at"] + t * (b["at"] - a["at"])
        cam = _camera_dict(catmull_rom([_camera_vec(k["camera"]) for k in path_keys],
                                       [k["at"] for k in path_keys], x))
    elif camera_path in ("linear", "catmull_rom"):
        cam = _camera_dict(lerp(_camera_vec(a["camera"]), _camera_vec(b["camera"]), t))
    else:
        raise ValueError(f"unknown camera path {camera_path!r} (linear or catmull_rom)")
    return {"frame": int(frame), "t": t, "keyframes": [int(k["at"]) for k in keys], "params": params,
            "sun": {"direction": np.asarray(d, float).tolist(), "azimuth": az, "elevation": el}, "camera": cam}


def frame_camera(camera: dict, resolution) -> "Camera":
    """The pinhole camera of a frame state's ``camera`` at ``resolution`` [w, h]. ``fov`` is the VERTICAL field
    of view: any resolution sees the same vertical extent of the scene (a wider aspect ratio sees more to the
    sides, never a cropped or stretched picture), so a cloud covers the same fraction of the frame's height at
    640x480 and at 1920x1080."""
    from natscene.geometry import Camera

    w, h = (int(v) for v in resolution)
    if w < 1 or h < 1:
        raise InputError(f"frame resolution must be positive, got {list(resolution)}")
    return Camera(tuple(float(c) for c in camera["position"]), tuple(float(c) for c in camera["look_at"]),
                  tuple(float(c) for c in camera["up"]), float(camera["fov"]), w, h)
