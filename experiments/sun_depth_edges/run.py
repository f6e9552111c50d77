"""The sun's optical depth in a volume dense up to its box's faces: the medium's D against the chord.

``Medium.ground_sun_depth`` gives a ground point the sun's optical depth D(x_e) at the point x_e where the sun's ray
from it enters the volume's box (:mod:`natscene.scatter.medium`). In a box of density 1 (16 voxels a side, dense up to
its faces) that depth is the length of the chord the ray cuts through the box (the slab test, in numpy here). Where
the ray leaves the box near an edge, D is the smaller of the two faces' distances (a ridge across the box), and a
voxel-centred D interpolated across it reads wrong; the medium of such a volume interpolates the mean density along
the ray instead and multiplies it by the point's own distance to the box's face (``Medium.face_dense``). For each
sun (elevation 10, 30, 60; azimuth 0, 30, 45) it prints the ratio D / chord over 200,000 ground points whose ray
crosses at least one voxel: the worst rays (lowest and highest), the lowest 1 % and the median; ``--voxel-centred``:
the same with the voxel-centred D interpolated (what a volume that ends inside its box gets).

    .venv/bin/python experiments/sun_depth_edges/run.py [--voxel-centred]
"""
import argparse
import math

import numpy as np

import natscene  # noqa: F401  (before drjit: the LLVM backend's library)
import mitsuba as mi

from natscene.scatter.medium import make_medium, sun_depth_volume
from natscene.variant import select_variant
from natscene.volume.grid import Volume

LO, HI = np.array([-8.0, 2.0, -8.0]), np.array([8.0, 18.0, 8.0])


def sun_vector(azimuth: float, elevation: float) -> np.ndarray:
    a, e = math.radians(azimuth), math.radians(elevation)
    return np.array([math.cos(e) * math.sin(a), math.sin(e), math.cos(e) * math.cos(a)])


def chord(x: np.ndarray, s: np.ndarray) -> np.ndarray:
    """Length of the rays x + t s (t >= 0) inside the box."""
    with np.errstate(divide="ignore", invalid="ignore"):
        t0, t1 = (LO - x) / s, (HI - x) / s
    near = np.maximum(np.nanmax(np.minimum(t0, t1), axis=1), 0.0)
    far = np.nanmin(np.maximum(t0, t1), axis=1)
    return np.maximum(far - near, 0.0)


def medium(box: Volume, sun: np.ndarray, voxel_centred: bool):
    med = make_medium(box, sun)
    if voxel_centred:
        med.face_dense = False
        med.sun_depth_tex = mi.Texture3f(mi.TensorXf(sun_depth_volume(med, sun)[..., None]))
    return med


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--voxel-centred", action="store_true", help="interpolate the voxel-centred D")
    args = ap.parse_args()
    select_variant()
    rng = np.random.default_rng(0)
    n = 200_000
    xg = np.stack([rng.uniform(-80, 80, n), np.zeros(n), rng.uniform(-80, 80, n)], 1)
    box = Volume(np.ones((16, 16, 16), np.float32), LO, HI, 1.0)
    p = mi.Point3f(xg[:, 0].astype(np.float32), np.full(n, 0.5, np.float32), xg[:, 2].astype(np.float32))
    down = mi.Vector3f(0.0, -1.0, 0.0)
    print("elevation azimuth  lowest  highest  lowest 1 %  median")
    for el in (10, 30, 60):
        for az in (0, 30, 45):
            s = sun_vector(az, el)
            depth = np.asarray(medium(box, s, args.voxel_centred).ground_sun_depth(p, down), np.float64)
            length = chord(xg, s)
            ok = length > 1.0
            r = depth[ok] / length[ok]
            print(f"{el:9d} {az:7d} {r.min():7.3f} {r.max():8.3f} {np.percentile(r, 1):11.3f} {np.median(r):7.4f}")


if __name__ == "__main__":
    main()
