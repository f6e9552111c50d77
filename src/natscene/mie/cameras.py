"""
Cameras of the Mie effect shots
===============================

Defines the cameras that frame the effects of the Mie shading (Reimschuessel 2011, Ch. 4, Fig. 11; the rule
``mie_render``'s shots, config ``mie.demo``):

-   :func:`effect_camera`: the camera of one effect shot (:data:`SHOTS`).
-   :func:`deck_camera`, :func:`deck_top`, :func:`deck_aim`: a camera above a stratocumulus deck, the sun
    behind it.
-   :func:`silver_lining_camera`: a camera behind the cloud looking at the hidden sun.
-   :func:`scattering_angle_at_centre`: the phase angle at a camera's look-at point.

One sun, cameras placed around the cloud so that the same point-cloud solution is reused (the thesis' view
independence). :func:`effect_camera`:

- ``glory``: camera between the sun and the cloud, the cloud centre at the antisolar point (θ = 180°);
- ``fogbow``: the cloud centre ``fogbow_angle`` degrees from the antisolar point (θ = 180° - that);
- ``silver_lining``: camera behind the cloud, the sun ``silver_offset`` degrees from the cloud centre
  (θ near 0°, the forward peak).

Where nature shows these effects (and so where the shots look for them):

- glory and fogbow: on the tops of *thin, uniform-droplet* stratocumulus decks and fog banks, with the sun
  behind the observer. The rings need a narrow droplet spectrum (effective variance v_eff ≲ 0.05; at
  v_eff = 0.1 they wash out, Laven 2005) and a view where single scattering is a large share of the light
  (optical depth of a few, not the τ ≈ 70 of a towering cumulus). Such a deck is a ``stratocumulus``
  volume of the volume stage (a broken, cellular layer a few hundred metres thick with a billowy top, its
  extinction scale set for a mean vertical optical depth of a few: ``reference_axis: y``);
  :func:`deck_camera` looks at it from above;
- silver lining: toward the sun, the sun just hidden behind a cloud edge: the diffraction peak of the
  droplets (4π p(0°) in the thousands, ≈ 1–2° wide) lights the thin edge brilliantly within a degree or
  two of the sun. :func:`silver_lining_camera` finds such a line of sight (sun behind ≥ ``hide_tau`` of
  cloud, the nearest clear sky ``edge_deg`` away, on the cloud's upper edge) and frames it narrowly.

References
----------
-   Laven, P. (2005). Atmospheric glories: simulations and observations. Applied Optics, 44(27), 5667–5674.
-   Reimschuessel, C. A. (2011). Rendering Realistic Cloud Effects for Computer Generated Films. MSc thesis,
    Brigham Young University.
"""
from __future__ import annotations

import numpy as np

from natscene.geometry import Camera, rotate

__all__ = ["SHOTS", "effect_camera", "deck_top", "deck_aim", "deck_camera", "silver_lining_camera",
           "scattering_angle_at_centre"]

SHOTS = ("glory", "fogbow", "silver_lining")


def effect_camera(shot: str, volume, sun_dir, distance: float = 2.2, fov: float = 32.0, resolution=(480, 360),
                  fogbow_angle: float = 39.0, silver_offset: float = 6.0) -> Camera:
    """The camera of one effect shot (``glory``, ``fogbow``, ``silver_lining``, see the module docstring) on a
    circle around the volume, looking at the centre of its bounding box."""
    c = (np.asarray(volume.bbox_min, float) + np.asarray(volume.bbox_max, float)) / 2
    s = np.asarray(sun_dir, float) / np.linalg.norm(sun_dir)
    side = np.cross(s, [0.0, 1.0, 0.0])
    if np.linalg.norm(side) < 1e-6:
        side = np.array([1.0, 0.0, 0.0])
    if shot == "glory":
        to_cam = s
    elif shot == "fogbow":
        to_cam = rotate(s, side, np.radians(fogbow_angle))   # away from the antisolar direction
    elif shot == "silver_lining":
        to_cam = -rotate(s, side, np.radians(silver_offset))
    else:
        raise ValueError(f"unknown effect shot '{shot}' (one of {SHOTS})")
    pos = c + distance * to_cam
    up = np.array([0.0, 1.0, 0.0]) if abs(to_cam[1]) < 0.99 else np.array([0.0, 0.0, 1.0])
    w, h = resolution
    return Camera(tuple(pos), tuple(c), tuple(up), float(fov), int(w), int(h))


def deck_top(deck, level: float = 0.1) -> float:
    """Height of a deck's top (world y): the median, over the cloudy columns (peak density >= 0.5), of the
    top of the highest voxel whose density reaches ``level``."""
    d = np.asarray(deck.density)
    vy = float(deck.voxel_size[1])
    above = d >= level                                            # [z, y, x]
    cloudy = d.max(axis=1) >= 0.5
    if not cloudy.any():
        raise ValueError("deck_top: the deck has no column with density >= 0.5")
    ny = d.shape[1]
    highest = ny - 1 - np.argmax(above[:, ::-1, :], axis=1)       # [z, x] index of the highest such voxel
    return float(deck.bbox_min[1]) + vy * (float(np.median(highest[cloudy])) + 1.0)


def deck_aim(deck, radius: float) -> tuple[float, float]:
    """World (x, z) of the deck column nearest its centre around which the deck is closed (every column
    within ``radius`` of it, capped at a quarter of the deck's width, has peak density >= 0.5): a broken deck
    has clear lanes between its cells, and a glory is watched on the cloud, not on a lane. The centre
    itself when no column qualifies."""
    from scipy import ndimage

    d = np.asarray(deck.density)
    vox = float(deck.voxel_size[0])
    nz, _, nx = d.shape
    lo, hi = np.asarray(deck.bbox_min, float), np.asarray(deck.bbox_max, float)
    cloudy = d.max(axis=1) >= 0.5                                         # [z, x]
    r = int(np.ceil(min(radius, 0.25 * (hi[0] - lo[0])) / vox))
    if r > 0:
        yy, xx = np.mgrid[-r:r + 1, -r:r + 1]
        ok = ndimage.binary_erosion(cloudy, structure=(xx ** 2 + yy ** 2) <= r * r, border_value=0)
    else:
        ok = cloudy
    if not ok.any():
        return float((lo[0] + hi[0]) / 2), float((lo[2] + hi[2]) / 2)
    zi, xi = np.nonzero(ok)
    k = int(np.argmin((zi + 0.5 - nz / 2) ** 2 + (xi + 0.5 - nx / 2) ** 2))
    return float(lo[0] + (xi[k] + 0.5) * vox), float(lo[2] + (zi[k] + 0.5) * vox)


def deck_camera(shot: str, deck, sun_dir, distance: float = 1.5, fov: float = 10.0, resolution=(480, 360),
                angle: float = 0.0) -> Camera:
    """A camera above a deck with the sun behind it, aimed from ``distance`` at the deck's top over
    :func:`deck_aim` (the cloud-covered spot nearest the deck's centre); ``glory`` looks at the antisolar
    point; ``fogbow`` ``angle`` degrees from it, sideways (same side of the sun's vertical plane for positive
    angles), so the side arc of the bow crosses the frame."""
    s = np.asarray(sun_dir, float) / np.linalg.norm(sun_dir)
    if s[1] <= 0.05:
        raise ValueError("deck_camera: the sun must be above the horizon to light the deck from above")
    top = deck_top(deck)
    x, z = deck_aim(deck, distance * np.tan(np.radians(min(fov, 30.0) / 2)))
    c = np.array([x, top, z])
    to_cam = s
    if shot == "fogbow":
        # sideways (about the axis in the sun's vertical plane): the view still looks down at the deck,
        # at a shallower angle than the antisolar point, so the bow's side arc lies on the deck top
        axis = np.array([0.0, 1.0, 0.0]) - s[1] * s
        to_cam = rotate(s, axis / np.linalg.norm(axis), np.radians(angle))
    elif shot != "glory":
        raise ValueError(f"deck_camera: shot must be 'glory' or 'fogbow', got '{shot}'")
    pos = c + distance * to_cam
    up = np.array([0.0, 1.0, 0.0]) if abs(to_cam[1]) < 0.99 else np.array([0.0, 0.0, 1.0])
    w, h = resolution
    return Camera(tuple(pos), tuple(c), tuple(up), float(fov), int(w), int(h))


def silver_lining_camera(volume, sun_dir, sigma_e: float, distance: float = 2.2, fov: float = 8.0,
                         resolution=(480, 360), edge_deg: float = 0.8, hide_tau: float = 10.0) -> Camera:
    """A camera behind the cloud looking straight at the sun, which is hidden behind ≥ ``hide_tau`` of
    cloud (optical depth along the sun's line of sight, σ_e = ``sigma_e``) and the cloud's upper edge
    (clear sky, τ < 0.05) ``edge_deg`` degrees above it (seen from ``distance`` behind the cloud's centre
    plane); of all such lines the one highest in the image (the top of the cloud), then the most central.
    Deterministic (no random search)."""
    from natscene.mie.points import sample_density

    s = np.asarray(sun_dir, float) / np.linalg.norm(sun_dir)
    up0 = np.array([0.0, 1.0, 0.0]) if abs(s[1]) < 0.99 else np.array([0.0, 0.0, 1.0])
    ex = np.cross(s, up0)
    ex /= np.linalg.norm(ex)
    ey = np.cross(ex, s)                                         # image up, perpendicular to the sun line
    lo, hi = np.asarray(volume.bbox_min, float), np.asarray(volume.bbox_max, float)
    centre = (lo + hi) / 2
    rel = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])]) - centre
    px = float(np.min(volume.voxel_size)) * 1.5                  # map pixel (world units)
    xs = np.arange(np.min(rel @ ex), np.max(rel @ ex) + px, px)
    ys = np.arange(np.min(rel @ ey), np.max(rel @ ey) + px, px)
    zs = np.arange(np.min(rel @ s), np.max(rel @ s) + px, px)
    tau = np.zeros((len(ys), len(xs)))
    for k in range(0, len(ys), 32):                              # τ along the sun's line, in row blocks
        yy = ys[k:k + 32]
        p = centre + yy[:, None, None, None] * ey + xs[None, :, None, None] * ex + zs[None, None, :, None] * s
        tau[k:k + 32] = sample_density(volume, p).sum(axis=-1) * px * sigma_e
    hidden = tau >= min(hide_tau, 0.5 * float(tau.max()))          # a thin cloud: its thicker half
    if not hidden.any():
        raise ValueError("silver_lining_camera: the volume is empty (no optical depth toward the sun)")
    # distance (world) from each map pixel up (+ey) to the first clear-sky pixel of its column
    clear = tau < 0.05
    up = np.full(tau.shape, np.inf)
    nxt = np.full(len(xs), np.inf)
    for i in range(len(ys) - 1, -1, -1):
        nxt = np.where(clear[i], ys[i], nxt)
        up[i] = nxt - ys[i]
    target = distance * np.tan(np.radians(edge_deg))
    err = np.where(hidden, np.abs(up - target), np.inf)
    cand = err <= max(px, 0.15 * target, float(err.min()))       # else the nearest achievable edge distance
    iy, ix = np.nonzero(cand)
    k = int(np.argmax(ys[iy] * 1e6 - np.abs(xs[ix])))            # highest in the image, then most central
    p0 = centre + ys[iy[k]] * ey + xs[ix[k]] * ex
    pos = p0 - distance * s
    w, h = resolution
    return Camera(tuple(pos), tuple(pos + s), tuple(up0), float(fov), int(w), int(h))


def scattering_angle_at_centre(camera: Camera, sun_dir) -> float:
    """Phase angle (deg) of sunlight scattered toward the camera at its look-at point."""
    to_cam = np.subtract(camera.position, camera.look_at)
    to_cam = to_cam / np.linalg.norm(to_cam)
    w = -np.asarray(sun_dir, float) / np.linalg.norm(sun_dir)
    return float(np.degrees(np.arccos(np.clip(np.dot(w, to_cam), -1, 1))))
