"""
Config checks
=============

Defines the checks of a validated config (:func:`natscene.config.validate_config`: the schema's defaults filled in,
which the checks read as they are, with no default of their own) that a JSON schema cannot express, run before
any job starts:

-   :func:`check_config`: raise :class:`natscene.errors.ConfigError` listing every problem.
-   :func:`config_problems`: every problem of a config, each with its key path.
-   :func:`camera_problem`: why a camera is degenerate.

The schema checks each value on its own (types, ranges, allowed keys). This module checks the config as a
whole, so that no job starts on a config that would fail later with a raw exception naming no key:

- **cross-references**: every name one section gives for an entry of another (keyframes -> photos, volumes,
  views; precompute.pairs; shots -> volumes, keyframes; mie.demo.volume and mie.demo.deck -> volumes;
  composite.shot -> shots; composite meadow flower patterns -> patterns; composite image and sun products
  (ground texture, leaf textures, background, sky_product) -> shots, tiles, patterns, recolour, leaves, sky
  photos, fits, volumes) exists, and a product path is one that a stage writes;
- **input files**: every file the config names (photos, masks, textures, petal shapes, user volumes) exists;
- **materials**: the composite beetles' thin-film layer and substrate indices are numbers, "n+kj" strings or
  measured tables covering the composite's wavelength range;
- **geometry**: no degenerate camera (position at its look-at, up parallel to the view direction) in views,
  shot keyframes and composites without a shot; the sun above the horizon where a stage needs sunlight from
  above (views, i.e. precompute and fit; shot keyframes, whose Preetham sky is defined for a sun above the
  horizon; the sun of a composite without a shot; the Mie demo);
- **value relations**: grids strictly increasing, the fit's extinction range (1/m) physical and covered by the
  precompute's extinction nodes,
  keyframe frames inside their shot, a composite's frames inside its shot (or inside the shot whose frames a
  product background names).

Every problem is reported with the key's path (``keyframes.kite.photo``), and all problems at once.
"""
from __future__ import annotations

import os
import re
from pathlib import Path

import numpy as np

from natscene.config import resolve_path
from natscene.errors import ConfigError

__all__ = ["check_config", "config_problems", "camera_problem"]


class _Problems:
    def __init__(self):
        self.items: list[str] = []

    def add(self, key: str, msg: str) -> None:
        self.items.append(f"config key '{key}': {msg}")


def _names(section) -> str:
    return ", ".join(sorted(section)) if section else "(none)"


def _ref(p: _Problems, config: dict, key: str, value, section: str) -> bool:
    entries = config[section]
    if value not in entries:
        p.add(key, f"{value!r} is not in '{section}' (defined: {_names(entries)})")
        return False
    return True


def _file(p: _Problems, root, key: str, path, what: str) -> None:
    if not isinstance(path, str) or not path:
        p.add(key, f"{what} path missing")
        return
    full = Path(resolve_path(path, root))
    if not full.is_file():
        p.add(key, f"{what} {full} not found (paths are relative to the repository root {root})")
    elif not os.access(full, os.R_OK):
        p.add(key, f"{what} {full} is not readable; fix its permissions")


# --------------------------------------------------------------------------------------------- geometry
def camera_problem(cam: dict) -> str | None:
    """Why a validated camera {position, look_at, up, fov} is degenerate, or None."""
    pos = np.asarray(cam["position"], np.float64)
    at = np.asarray(cam["look_at"], np.float64)
    up = np.asarray(cam["up"], np.float64)
    fwd = at - pos
    dist = float(np.linalg.norm(fwd))
    scale = max(float(np.linalg.norm(pos)), float(np.linalg.norm(at)), 1.0)
    if dist <= 1e-9 * scale:
        return f"position {pos.tolist()} equals look_at {at.tolist()}: the view direction is undefined; move one"
    if float(np.linalg.norm(up)) == 0.0:
        return "up is the zero vector; use e.g. [0, 1, 0]"
    s = float(np.linalg.norm(np.cross(fwd / dist, up / np.linalg.norm(up))))
    if s < 1e-6:
        return (f"up {up.tolist()} is parallel to the view direction {np.round(fwd / dist, 6).tolist()}: the image's "
                f"right and up are undefined; choose an up that is not along the view direction")
    return None


def _camera(p: _Problems, key: str, cam: dict | None) -> None:
    if cam is None:
        return
    why = camera_problem(cam)
    if why:
        p.add(key, why)


def _sun_above(p: _Problems, key: str, sun: dict | None, needed_by: str) -> None:
    if sun is None or "elevation" not in sun:
        return
    el = float(sun["elevation"])
    if el <= 0.0:
        p.add(f"{key}.elevation", f"{el:g} deg puts the sun at or below the horizon, but {needed_by} needs "
                                  f"sunlight from above it; use an elevation > 0")


# ------------------------------------------------------------------------------------------- products
_FRAME_FIELD = re.compile(r"\{frame(:[^}]*)?\}")


def _product_problem(config: dict, product: str, frames: list[int]) -> str | None:
    """Why ``product`` (a path under the results directory, may contain {frame}) is not made by any stage."""
    parts = product.strip("/").split("/")
    head = parts[0]
    sec = lambda name: config[name]  # noqa: E731

    def need(section, name, what):
        if name not in sec(section):
            return f"names {what} {name!r}, which is not in '{section}' (defined: {_names(sec(section))})"
        return None

    if len(parts) < 2:
        return "is not a product of any stage (expected e.g. shots/<shot>/frames/{frame:04d}.exr)"
    name = parts[1]
    if head == "shots":
        why = need("shots", name, "shot")
        if why:
            return why
        n = sec("shots")[name]["frames"]
        if _FRAME_FIELD.search(product):
            bad = [f for f in frames if f >= n]
            if bad:
                return f"frames {bad} are past the last frame ({n - 1}) of shot {name!r}"
        return None
    if head == "tiles":
        return need("tiles", name, "texture")
    if head == "textures":
        return need("textures", name, "texture")
    if head == "patterns":
        if name == "recolour":
            return need("recolour", parts[2], "recoloured photo") if len(parts) > 2 else "names no recoloured photo"
        return need("patterns", name, "pattern")
    if head == "leaves":
        leaves = sec("leaves")
        if name != leaves["name"]:
            return f"names leaf {name!r}, but leaves.name is {leaves['name']!r}"
        if len(parts) >= 4:
            climate, date = parts[2], Path(parts[3]).stem
            if climate not in leaves["cases"]:
                return f"names climate case {climate!r}, which is not in 'leaves.cases' " \
                       f"(defined: {_names(leaves['cases'])})"
            if parts[3].endswith(".exr") and date not in leaves["dates"]:
                return f"names date {date!r}, which is not in 'leaves.dates' ({', '.join(leaves['dates'])})"
        return None
    if head == "sky":
        return need("photos", name, "photo")
    if head == "fit":
        return need("keyframes", name, "keyframe")
    if head == "volumes":
        return need("volumes", name, "volume")
    if head == "precompute":
        return need("volumes", name, "volume") or (need("views", parts[2], "view") if len(parts) > 2 else None)
    if head in ("mie", "composite"):
        return None
    return (f"is not a product of any stage (the first folder must be one of shots, tiles, textures, patterns, "
            f"leaves, sky, fit, volumes, precompute, mie)")


def _image_source(p: _Problems, config: dict, root, key: str, src: dict | None, frames: list[int]) -> None:
    if not isinstance(src, dict):
        return
    if "product" in src:
        why = _product_problem(config, str(src["product"]), frames)
        if why:
            p.add(f"{key}.product", f"{src['product']!r} {why}")
    elif "path" in src:
        for f in frames if _FRAME_FIELD.search(src["path"]) else [None]:
            path = src["path"] if f is None else src["path"].format(frame=f)
            _file(p, root, f"{key}.path", path, "image")


# ------------------------------------------------------------------------------------------- sections
def _check_volumes(p, config, root):
    for name, v in config["volumes"].items():
        if v["kind"] == "file":
            if not v.get("path"):
                p.add(f"volumes.{name}.path", "needed with kind: file (a .npy or Mitsuba .vol grid)")
            else:
                _file(p, root, f"volumes.{name}.path", v["path"], "volume file")


def _check_views(p, config):
    for name, view in config["views"].items():
        _camera(p, f"views.{name}.camera", view.get("camera"))
        _sun_above(p, f"views.{name}.sun", view.get("sun"),
                   "the precompute and fit of a view (sunlight on the cloud from above)")


def _check_photos(p, config, root):
    for name, ph in config["photos"].items():
        _file(p, root, f"photos.{name}.path", ph.get("path"), "photo")
        if ph.get("mask"):
            _file(p, root, f"photos.{name}.mask", ph["mask"], "mask")


def _increasing(p, key, values):
    v = np.asarray(values, np.float64)
    if v.size > 1 and not np.all(np.diff(v) > 0):
        p.add(key, f"{list(values)} must be strictly increasing")


def _check_precompute(p, config):
    pre = config["precompute"]
    for i, pair in enumerate(pre["pairs"]):
        _ref(p, config, f"precompute.pairs[{i}].volume", pair.get("volume"), "volumes")
        _ref(p, config, f"precompute.pairs[{i}].view", pair.get("view"), "views")
    _increasing(p, "precompute.extinction", pre["extinction"])
    if config["keyframes"]:
        _check_fit_extinction(p, config)
    _increasing(p, "precompute.g", pre["g"])


def _check_fit_extinction(p, config):
    """fit.ranges.extinction in the physical range and covered by precompute.extinction (the fit's tables)."""
    from natscene.fit.settings import extinction_range_problem
    why = extinction_range_problem(config["fit"]["ranges"]["extinction"], config["precompute"]["extinction"])
    if why:
        p.add("fit.ranges.extinction", why)


def view_sees_volume_problem(view: dict, spec: dict, volume: str) -> str | None:
    """Why a view's camera does not see the box of a ``volumes.<name>`` entry, or None (also None for a
    volume imported from a file without ``size``/``altitude``: its box is known only once it is read)."""
    from natscene.geometry import Camera, box_coverage
    from natscene.volume.build import world_box
    if spec["kind"] == "file" and spec.get("size") is None and spec.get("altitude") is None:
        return None
    if camera_problem(view["camera"]):
        return None                                   # reported as its own problem
    nx, ny, nz = (int(r) for r in spec["resolution"])
    lo, hi = world_box(spec, (nx, ny, nz))
    cam = Camera.from_view(view)
    if box_coverage(cam, lo, hi) > 0.0:
        return None
    c = view["camera"]
    return (f"its camera (position {list(c['position'])}, look_at {list(c['look_at'])}, fov {cam.fov:g} deg) does "
            f"not see volume '{volume}' (box {np.round(lo, 1).tolist()} .. {np.round(hi, 1).tolist()} m): 0 % of "
            f"the frame meets the box, the precompute would write empty tables; aim the camera at the box")


def _check_keyframes(p, config):
    for name, kf in config["keyframes"].items():
        _ref(p, config, f"keyframes.{name}.photo", kf.get("photo"), "photos")
        has_volume = _ref(p, config, f"keyframes.{name}.volume", kf.get("volume"), "volumes")
        has_view = _ref(p, config, f"keyframes.{name}.view", kf.get("view"), "views")
        if has_volume and has_view:
            why = view_sees_volume_problem(config["views"][kf["view"]], config["volumes"][kf["volume"]], kf["volume"])
            if why:
                p.add(f"views.{kf['view']}", why)


def _check_shots(p, config):
    for name, shot in config["shots"].items():
        key = f"shots.{name}"
        _ref(p, config, f"{key}.volume", shot.get("volume"), "volumes")
        n = shot["frames"]
        ats = [k["at"] for k in shot["keyframes"]]
        if len(set(ats)) != len(ats):
            p.add(f"{key}.keyframes", f"two keyframes share a frame index ({sorted(ats)})")
        for i, kf in enumerate(shot["keyframes"]):
            kk = f"{key}.keyframes[{i}]"
            if kf["at"] >= n:
                p.add(f"{kk}.at", f"frame {kf['at']} is past the shot's last frame {n - 1}; lower it or raise "
                                  f"'{key}.frames'")
            fit = kf.get("fit")
            view = None
            if fit is not None and _ref(p, config, f"{kk}.fit", fit, "keyframes"):
                view = config["views"].get(config["keyframes"][fit]["view"])
            for part in ("sun", "camera"):
                if kf.get(part) is None and view is None and fit is None:
                    p.add(f"{kk}.{part}", "needed when the keyframe has no 'fit' whose view would give it")
            if fit is None:
                from natscene.keyframes.shot import COLOURS, PARAMS
                missing = [q for q in PARAMS + COLOURS if q not in kf["params"]]
                if missing:
                    p.add(f"{kk}.params", f"{missing} missing; give them or name a fitted keyframe with 'fit'")
            _camera(p, f"{kk}.camera", kf.get("camera"))
            _sun_above(p, f"{kk}.sun", kf.get("sun"), "the shot's frames (the Preetham sky is defined for a sun "
                                                      "above the horizon)")


def _check_textures(p, config, root):
    for name, t in config["textures"].items():
        key = f"textures.{name}"
        _file(p, root, f"{key}.path", t.get("path"), "example photo")
        sc, out = t["scale"], t["output"]
        if sc["from"] == "mask" and sc.get("mask"):
            _file(p, root, f"{key}.scale.mask", sc["mask"], "feature mask")
        if t["types"].get("labels"):
            _file(p, root, f"{key}.types.labels", t["types"]["labels"], "type label image")
        if out["scale"]["kind"] == "image":
            _file(p, root, f"{key}.output.scale.image", out["scale"].get("image"), "target scale-map image")
        if out["scale"]["kind"] != "resample" and sc["from"] == "none":
            p.add(f"{key}.output.scale", "a target scale map needs the example's scale feature (scale.from is none)")
        for k in ("types", "colour"):
            if out.get(k):
                _file(p, root, f"{key}.output.{k}", out[k], f"target {k} map")
        work = t.get("working_size")
        if t["method"] == "quilting" and work and min(work) < t["quilting"]["cell"] * (
                1 + 2 * t["quilting"]["overlap"]):  # (validated: the schema's defaults are in)
            p.add(f"{key}.quilting.cell", f"a cell with its overlap does not fit in the {work[0]}x{work[1]} example "
                                          f"(working_size)")
        sizes, size = t["optimisation"]["sizes"], out["size"]
        if sizes and size and min(size) < max(sizes):
            W, H = size
            p.add(f"{key}.output.size", f"{W}x{H} is smaller than the largest neighbourhood {max(sizes)} "
                                        f"(optimisation.sizes)")


def _check_tiles(p, config, root):
    for name, t in config["tiles"].items():
        if bool(t.get("path")) == bool(t.get("product")):
            p.add(f"tiles.{name}", "give the example as exactly one of 'path' (a file) and 'product' (another "
                                   "stage's product, e.g. textures/<name>/synth.png)")
        elif t.get("product"):
            why = _product_problem(config, str(t["product"]), [])
            if why:
                p.add(f"tiles.{name}.product", f"{t['product']!r} {why}")
        else:
            _file(p, root, f"tiles.{name}.path", t.get("path"), "example texture")
        for i, e in enumerate(t["embed"]):
            _file(p, root, f"tiles.{name}.embed[{i}].path", e.get("path"), "embedded object image")


def _check_patterns(p, config, root):
    for name, pat in config["patterns"].items():
        shape = pat["shape"]
        if shape.get("kind") == "file":
            _file(p, root, f"patterns.{name}.shape.path", shape.get("path"), "petal shape mask")
    for name, r in config["recolour"].items():
        _file(p, root, f"recolour.{name}.photo", r.get("photo"), "flower photo")


def _check_mie(p, config):
    demo = config["mie"]["demo"]
    if demo.get("volume") is not None:
        _ref(p, config, "mie.demo.volume", demo["volume"], "volumes")
        deck_shots = [s for s in ("glory", "fogbow", "silver_lining") if demo[s]["cloud"] == "deck"]
        if demo.get("deck") is not None:
            _ref(p, config, "mie.demo.deck", demo["deck"], "volumes")
        elif deck_shots:
            p.add("mie.demo.deck", f"names no volume, but the demo shots {deck_shots} look at the deck "
                                   f"(cloud: deck); name a stratocumulus volume of 'volumes' or set their cloud "
                                   f"to 'volume'")
        _sun_above(p, "mie.demo.sun", demo["sun"], "the Mie demo (glory, fogbow, silver lining)")


def _material_problem(material, wavelengths: tuple[float, float]) -> str | None:
    """Why a thin-film layer or substrate index (table name, real number or "n+kj" string) cannot be used over
    the composite's wavelength range."""
    if isinstance(material, (int, float)) and not isinstance(material, bool):
        return None if material > 0 else f"{material!r}: a real index must be > 0"
    from natscene.errors import InputError
    from natscene.spectral.indices import complex_index
    try:
        complex_index(material, list(wavelengths))  # a measured table must cover the spectral grid
    except InputError as e:
        return str(e)
    return None


def _check_composite(p, config, root):
    shots = config["shots"]
    for name, c in config["composite"].items():
        key = f"composite.{name}"
        frames = list(c["frames"])
        shot = c.get("shot")
        if shot is not None:
            # frame k of the composite is frame k of the shot: its camera, sun, sky and cloud plate
            if _ref(p, config, f"{key}.shot", shot, "shots"):
                n = shots[shot]["frames"]
                bad = [f for f in frames if f >= n]
                if bad:
                    p.add(f"{key}.frames", f"frames {bad} are past the last frame ({n - 1}) of shot {shot!r}; "
                                           f"lower them or raise 'shots.{shot}.frames'")
        else:
            # without a shot: the composite's own camera, background plate and sun
            _camera(p, f"{key}.camera", c["camera"])
            _image_source(p, config, root, f"{key}.background", c["background"], frames)
            _sun_above(p, f"{key}.sun", c["sun"], "the composite (the sun lights the ground, petals and leaves)")
        sun = c["sun"]
        if sun.get("sky_product"):
            why = _product_problem(config, sun["sky_product"], frames)
            if why:
                p.add(f"{key}.sun.sky_product", f"{sun['sky_product']!r} {why}")
        _image_source(p, config, root, f"{key}.ground.texture", c["ground"]["texture"], frames)
        meadow = c["meadow"]
        for i, flower in enumerate(meadow["flowers"]):
            # petals are textured with patterns/<pattern>/color.exr, made for the entries of 'patterns'
            _ref(p, config, f"{key}.meadow.flowers[{i}].pattern", flower.get("pattern"), "patterns")
        for i, src in enumerate((meadow.get("leaves") or {}).get("textures") or []):
            _image_source(p, config, root, f"{key}.meadow.leaves.textures[{i}]", src, frames)
        wl = c["wavelengths"]
        span = (float(wl["start"]), float(wl["stop"]))
        for i, beetle in enumerate(meadow["beetles"]):
            bk = f"{key}.meadow.beetles[{i}]"
            for j, layer in enumerate(beetle["layers"]):
                why = _material_problem(layer.get("material"), span)
                if why:
                    p.add(f"{bk}.layers[{j}].material", why)
            if "substrate" in beetle:
                why = _material_problem(beetle["substrate"], span)
                if why:
                    p.add(f"{bk}.substrate", why)


def config_problems(config: dict, root: str | os.PathLike) -> list[str]:
    """Every cross-reference, input-file, geometry and value-relation problem of a validated config
    (:func:`natscene.config.validate_config`)."""
    p = _Problems()
    _check_volumes(p, config, root)
    _check_views(p, config)
    _check_photos(p, config, root)
    _check_precompute(p, config)
    _check_keyframes(p, config)
    _check_shots(p, config)
    _check_tiles(p, config, root)
    _check_textures(p, config, root)
    _check_patterns(p, config, root)
    _check_mie(p, config)
    _check_composite(p, config, root)
    return p.items


def check_config(config: dict, root: str | os.PathLike, source: str = "config") -> dict:
    """Raise :class:`ConfigError` listing every problem (each with its key path); return the config."""
    problems = config_problems(config, root)
    if problems:
        head = f"{source}: {len(problems)} problem{'s' if len(problems) > 1 else ''} in the configuration"
        raise ConfigError(head + ":\n  " + "\n  ".join(problems))
    return config
