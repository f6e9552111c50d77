"""
Meadow of the set
=================

Defines the meadow: seeded placement of flowers, fallen maple leaves and beetles on the ground in front of the
camera, turned into the set's shapes and materials:

-   :func:`build_meadow`: the surfaces, films and shapes of the meadow (:data:`BEETLES`, :data:`STEM_RGB`,
    :data:`CHITIN_RGB`).

Placement is in the set's frame (metres, the set origin on the ground below the camera of the first frame,
the view toward +z), inside the wedge ``near <= r <= far``, |azimuth| <= ``half_angle``. Flowers grow in
patches: ``patches`` centres uniform over the wedge's area, each flower a Gaussian step (``patch_radius``)
from a random centre; the head leans ``tilt`` degrees toward the camera ± ``facing_spread`` (flowers turn to
the light and the viewer sees their faces). Leaves lie uniformly over the area with random yaw, resting on the grass
blades (a random fraction of their mean height where they grow), each a fraction of a millimetre above
the previous one so that overlapping leaves never share a plane. Grass blades stand in the
near field (:mod:`natscene.composite.grass`), with a clearing round each beetle. Beetles stand where the
config puts them. Everything is decided by ``seed``: the same config gives the same meadow in every frame.
"""
from __future__ import annotations

import numpy as np

from natscene.composite.beetle import GOLD_BUG, JEWEL_BEETLE, BeetleShape, beetle_meshes
from natscene.composite.flower import PetalShape, PetalTexture, flower
from natscene.composite.maple import leaf_cells, leaf_mesh
from natscene.composite.grass import grass_blades
from natscene.composite.mesh import merge, rotation_axis, rotation_y
from natscene.composite.placement import patch_points, wedge_points
from natscene.composite.set_spec import Shape, Surface
from natscene.composite.texture import MipTexture

__all__ = ["STEM_RGB", "CHITIN_RGB", "BEETLES", "build_meadow"]

STEM_RGB = (0.07, 0.16, 0.03)
CHITIN_RGB = (0.02, 0.015, 0.01)
BEETLES = {"gold_bug": GOLD_BUG, "jewel_beetle": JEWEL_BEETLE}


def _uniform(rng, lo_hi):
    lo, hi = (lo_hi, lo_hi) if np.isscalar(lo_hi) else lo_hi
    return float(rng.uniform(lo, hi))


def build_meadow(cfg: dict, petal_textures: dict, leaf_textures: list, films: list, ground=None):
    """Surfaces, films and shapes of the meadow.

    ``cfg``: a validated ``composite.<name>.meadow``; ``petal_textures`` {pattern name: RGBA (h, w, 4) albedo
    with alpha}; ``leaf_textures`` list of RGBA maple leaves (:func:`natscene.composite.maple.warp_season_map`);
    ``films`` the :class:`Film` of every beetle, in ``cfg["beetles"]`` order; ``ground`` the set's
    :class:`natscene.composite.set_spec.Ground` (its texture colours the grass blades).
    """
    rng = np.random.default_rng(int(cfg.get("seed", 0)))
    area = cfg["area"]
    surfaces: list[Surface] = []
    shapes: list[Shape] = []

    def surface(**kw) -> int:
        surfaces.append(Surface(**kw))
        return len(surfaces) - 1

    stem = surface(name="stem", color=STEM_RGB, translucency=0.1)
    fl = cfg.get("flowers", [])
    if fl:
        pts = patch_points(rng, sum(int(f["count"]) for f in fl), area, int(cfg.get("patches", 8)),
                           float(cfg.get("patch_radius", 0.5)))
        order = rng.permutation(pts.shape[0])
        start = 0
        for f in fl:
            name = f["pattern"]
            tex = np.asarray(petal_textures[name], np.float32)
            h, w = tex.shape[:2]
            petal = surface(name=f"petal:{name}", texture=MipTexture(tex), cutout=True,
                            translucency=float(f.get("translucency", 0.35)))
            pt = PetalTexture(tex[..., 3], w / h)
            disc = surface(name=f"centre:{name}", color=tuple(f.get("centre_rgb", (0.55, 0.4, 0.04))))
            parts = []
            for j in order[start:start + int(f["count"])]:
                x, z = pts[j]
                toward_camera = np.degrees(np.arctan2(-x, -z))
                shape = PetalShape(length=_uniform(rng, f.get("petal_length", [0.028, 0.04])),
                                   opening=_uniform(rng, f.get("opening", [35.0, 60.0])),
                                   bend=_uniform(rng, f.get("bend", [30.0, 60.0])), cup=float(f.get("cup", 0.25)))
                parts.append(flower(pt, int(f.get("petals", 5)), (x, z),
                                    _uniform(rng, f.get("height", [0.12, 0.35])),
                                    tilt=_uniform(rng, f.get("tilt", [15.0, 50.0])),
                                    facing=toward_camera + rng.uniform(-1, 1) * float(f.get("facing_spread", 50.0)),
                                    shape=shape, phase=rng.uniform(0, 360), jitter=float(f.get("jitter", 6.0)),
                                    rng=rng))
            start += int(f["count"])
            if parts:
                shapes.append(Shape(merge([p for fp in parts for p in fp.petals]), surface=petal))
                shapes.append(Shape(merge([fp.centre for fp in parts]), surface=disc))
                shapes.append(Shape(merge([fp.stem for fp in parts]), surface=stem))
    gr = cfg.get("grass") or {}

    def rest_height(xz) -> float:
        """A fallen leaf rests on the grass blades: a random fraction of their mean height, as dense as they are."""
        if not gr or float(gr.get("density", 0)) <= 0:
            return 0.0
        f0, f1 = gr.get("fade", (2.0, 4.0))
        t = float(np.clip((np.hypot(*xz) - f0) / max(f1 - f0, 1e-9), 0, 1))
        return float(np.mean(gr.get("height", (0.04, 0.11)))) * rng.uniform(0.4, 0.9) * (1 - t * t * (3 - 2 * t))

    lv = cfg.get("leaves")
    if lv and leaf_textures:
        n = int(lv["count"])
        pts = wedge_points(rng, n, {**area, "far": min(area["far"], float(lv.get("far", area["far"])))})
        which = rng.integers(0, len(leaf_textures), n)
        mats = [surface(name=f"leaf:{i}", texture=MipTexture(t), cutout=True,
                        translucency=float(lv.get("translucency", 0.25))) for i, t in enumerate(leaf_textures)]
        per = [[] for _ in leaf_textures]
        keep = [leaf_cells(t[..., 3]) for t in leaf_textures]
        for i in range(n):
            L = _uniform(rng, lv.get("length", [0.09, 0.15]))
            m = leaf_mesh(keep[which[i]], L, curl=_uniform(rng, [0.1, 0.35]),
                          cup=_uniform(rng, [0.0, 0.2]))
            tilt_axis = rotation_y(rng.uniform(0, 360)) @ np.array([1.0, 0.0, 0.0])
            R = rotation_axis(tilt_axis, rng.uniform(0, 8.0)) @ rotation_y(rng.uniform(0, 360))
            y = 0.001 + 0.002 * i / max(n, 1) + rest_height(pts[i])
            per[which[i]].append(m.transformed(R, [pts[i, 0], y, pts[i, 1]]))
        for k, ms in enumerate(per):
            if ms:
                shapes.append(Shape(merge(ms), surface=mats[k]))
    if gr and ground is not None and float(gr.get("density", 0)) > 0:
        clear = [(b["position"][0], b["position"][1], float(gr.get("clearing", 0.06))) for b in cfg.get("beetles", [])]
        blades = grass_blades(rng, area, float(gr["density"]), tuple(gr.get("height", (0.04, 0.11))),
                              float(gr.get("width", 0.004)), tuple(gr.get("fade", (2.0, 4.0))), clear,
                              ground.extent, ground.offset)
        g = surface(name="grass", texture=ground.texture, translucency=float(gr.get("translucency", 0.3)))
        shapes.append(Shape(blades, surface=g, shadows_ground=False))
    chitin = None
    for i, b in enumerate(cfg.get("beetles", [])):
        base = BEETLES[b.get("shape", "gold_bug")]
        shp = BeetleShape(**{**base.__dict__, **({"length": float(b["length"]),
                                                 "width": base.width * float(b["length"]) / base.length,
                                                 "height": base.height * float(b["length"]) / base.length}
                                                if "length" in b else {})})
        m = beetle_meshes(shp, b["position"], float(b.get("yaw", 0.0)))
        if chitin is None:
            chitin = surface(name="chitin", color=CHITIN_RGB)
        shapes.append(Shape(m["shell"], film=i))
        shapes.append(Shape(m["legs"], surface=chitin))
    return surfaces, list(films), shapes
