"""
Beetles of the set
==================

Defines the beetles for the set: Dong's gold bug (Chrysina-like scarab) and the jewel-beetle shell (Buprestidae),
at their natural size (a few centimetres), as triangle meshes:

-   :func:`beetle_meshes`: the film-coated shell and the chitin legs of a beetle standing on the ground.
-   :class:`BeetleShape`: a beetle's proportions; :data:`GOLD_BUG`, :data:`JEWEL_BEETLE`: the two beetles.

The shell is what carries the thin film (Dong 2007 §2.5: only the thin-film objects are shaded spectrally):
elytra (a super-ellipsoid dome, boxier than an ellipsoid, exponent ``elytra_exponent``, tapering to the
rear), the pronotum (a flatter, wider-than-long dome in front of them) and the head. Legs (three pairs, two
segments each) and antennae are thin tubes of dark chitin, shaded in RGB. The beetle stands on y = 0 with
its legs; ``yaw`` turns it about the vertical (0: head toward +z).

References
----------
-   Dong, W. (2007). Rendering Algorithms for Natural Scenes. PhD thesis, Université Henri Poincaré - Nancy I.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from natscene.composite.mesh import TriMesh, merge, rotation_y, superellipsoid, tube

__all__ = ["BeetleShape", "GOLD_BUG", "JEWEL_BEETLE", "beetle_meshes"]


@dataclass
class BeetleShape:
    length: float = 0.028  # metres, head to elytra tip
    width: float = 0.016
    height: float = 0.011  # top of the elytra above the ground
    elytra_exponent: float = 2.6
    leg_radius: float = 0.0006


#: body proportions of the two beetles of the default set
GOLD_BUG = BeetleShape(length=0.028, width=0.017, height=0.012, elytra_exponent=2.4)  # Chrysina resplendens
JEWEL_BEETLE = BeetleShape(length=0.036, width=0.013, height=0.009, elytra_exponent=2.8)  # Chrysochroa


def _taper(m: TriMesh, front: float, rear: float, length: float) -> TriMesh:
    """Narrow the mesh toward its rear (−z): width scale ``rear`` at z = −length/2 .. ``front`` at +length/2."""
    p = m.positions.copy()
    t = np.clip(p[:, 2] / length + 0.5, 0, 1)
    s = rear + (front - rear) * t
    p[:, 0] *= s
    from natscene.composite.mesh import vertex_normals
    return TriMesh(p, m.faces, m.uv, vertex_normals(p, m.faces))


def beetle_meshes(shape: BeetleShape, position, yaw: float = 0.0) -> dict:
    """{"shell": TriMesh (film-coated), "legs": TriMesh (dark chitin)} of a beetle standing at ground point
    ``position`` (x, z)."""
    L, W, H = shape.length, shape.width, shape.height
    clear = 0.22 * H  # belly above the ground
    # elytra: rear 62 % of the length, dome over the belly
    le = 0.62 * L
    el = superellipsoid((W / 2, H - clear, le / 2), shape.elytra_exponent, 14, 28, lat_range=(-0.12, np.pi / 2))
    el = _taper(el, 1.0, 0.55, le)
    el = el.transformed(np.eye(3), [0.0, clear, -L / 2 + le / 2])
    # pronotum: 24 % of the length, 85 % of the width, lower
    lp = 0.24 * L
    pr = superellipsoid((0.43 * W, 0.72 * (H - clear), lp / 2), 2.3, 10, 20, lat_range=(-0.12, np.pi / 2))
    pr = pr.transformed(np.eye(3), [0.0, clear, -L / 2 + le + lp / 2 - 0.02 * L])
    # head: the front 14 %
    lh = 0.16 * L
    hd = superellipsoid((0.25 * W, 0.4 * (H - clear), lh / 2), 2.0, 8, 14)
    hd = hd.transformed(np.eye(3), [0.0, clear + 0.25 * (H - clear), L / 2 - lh / 2])
    shell = merge([el, pr, hd])
    # legs: femur out and up from the body side, tibia down to the ground
    legs = []
    for z in (0.2 * L, 0.0, -0.18 * L):
        for side in (-1.0, 1.0):
            hip = np.array([side * 0.3 * W, clear + 0.1 * H, z])
            knee = np.array([side * 0.62 * W, clear + 0.45 * H, z + 0.06 * L * np.sign(z)])
            foot = np.array([side * 0.85 * W, 0.0003, z + 0.16 * L * (np.sign(z) if z else -0.3)])
            pts = np.concatenate([np.linspace(hip, knee, 4), np.linspace(knee, foot, 5)[1:]])
            legs.append(tube(pts, shape.leg_radius, sides=5))
    for side in (-1.0, 1.0):  # antennae
        a0 = np.array([side * 0.12 * W, clear + 0.35 * (H - clear), L / 2 - 0.02 * L])
        a1 = a0 + np.array([side * 0.25 * W, 0.25 * H, 0.25 * L])
        legs.append(tube(np.linspace(a0, a1, 5), shape.leg_radius * 0.6, sides=4))
    R = rotation_y(yaw)
    t = [position[0], 0.0, position[1]]
    return {"shell": shell.transformed(R, t), "legs": merge(legs).transformed(R, t)}
