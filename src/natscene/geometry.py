"""
Scene geometry
==============

Defines the scene geometry shared by every stage (DESIGN §3, Geometry): right-handed world, y up; a pinhole
camera (position, look-at, up, vertical field of view, resolution); the sun as a parallel light given by
azimuth (degrees from +z toward +x) and elevation (degrees above the horizon):

-   :class:`Camera`: the pinhole camera and its rays.
-   :func:`sun_direction`: the unit vector toward the sun.
-   :func:`rotate`: a vector rotated about an axis (Rodrigues' formula).
-   :func:`ray_box`, :func:`box_coverage`: rays against an axis-aligned box, and the share of a frame that sees it.
-   :func:`frame_voxels`: the voxels of a grid that a camera's frame sees.

Pixel (i, j) (row i from the top, column j from the left) looks through its centre. The image's right
is ``right = normalize(forward x up)``, matching Mitsuba's ``perspective`` sensor with ``fov_axis='y'``
and ``to_world = look_at(position, look_at, up)`` (verified in tests against Mitsuba).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Camera", "sun_direction", "rotate", "ray_box", "box_coverage", "frame_voxels"]


def sun_direction(azimuth_deg: float, elevation_deg: float) -> np.ndarray:
    """Unit vector pointing *toward* the sun."""
    az, el = np.radians(azimuth_deg), np.radians(elevation_deg)
    return np.array([np.cos(el) * np.sin(az), np.sin(el), np.cos(el) * np.cos(az)])


def rotate(v, axis, angle_rad: float) -> np.ndarray:
    """``v`` rotated about ``axis`` (any length) by ``angle_rad``, right-handed (Rodrigues' formula)."""
    axis = axis / np.linalg.norm(axis)
    return (v * np.cos(angle_rad) + np.cross(axis, v) * np.sin(angle_rad)
            + axis * np.dot(axis, v) * (1 - np.cos(angle_rad)))


def _normalize(v) -> np.ndarray:
    v = np.asarray(v, np.float64)
    n = np.linalg.norm(v)
    if n == 0:
        raise ValueError("zero-length vector")
    return v / n


@dataclass(frozen=True)
class Camera:
    """A pinhole camera. ``fov`` is the vertical field of view in degrees; resolution is (width, height). No field
    has a default: a view's come from its config entry (:meth:`from_view`; the schema's defaults are the only
    ones)."""

    position: tuple
    look_at: tuple
    up: tuple
    fov: float
    width: int
    height: int

    @classmethod
    def from_view(cls, view: dict, resolution=None) -> "Camera":
        """Build from a validated ``views.<name>`` config entry (the schema's defaults filled in; ``resolution``
        overrides the view's)."""
        cam = view["camera"]
        w, h = resolution or view["resolution"]
        return cls(tuple(cam["position"]), tuple(cam["look_at"]), tuple(cam["up"]), float(cam["fov"]), int(w), int(h))

    def basis(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(right, true_up, forward) unit vectors."""
        fwd = _normalize(np.subtract(self.look_at, self.position))
        right = np.cross(fwd, _normalize(self.up))
        if np.linalg.norm(right) < 1e-9:
            raise ValueError("camera 'up' is parallel to the viewing direction")
        right = _normalize(right)
        up = np.cross(right, fwd)
        return right, up, fwd

    def ray_directions(self, jitter: np.ndarray | None = None) -> np.ndarray:
        """Unit ray directions (height, width, 3) through pixel centres (or centres + jitter in pixels)."""
        right, up, fwd = self.basis()
        tan_half = np.tan(np.radians(self.fov) / 2)
        aspect = self.width / self.height
        j = np.arange(self.width) + 0.5
        i = np.arange(self.height) + 0.5
        jj, ii = np.meshgrid(j, i)
        if jitter is not None:
            jj = jj + jitter[..., 0]
            ii = ii + jitter[..., 1]
        x = (2 * jj / self.width - 1) * tan_half * aspect
        y = (1 - 2 * ii / self.height) * tan_half
        d = x[..., None] * right + y[..., None] * up + fwd
        return d / np.linalg.norm(d, axis=-1, keepdims=True)


def ray_box(origins: np.ndarray, dirs: np.ndarray, lo, hi) -> tuple[np.ndarray, np.ndarray]:
    """Slab test: entry and exit distances of rays with an axis-aligned box (t_exit < t_entry: miss)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = 1.0 / dirs
        t0 = (np.asarray(lo) - origins) * inv
        t1 = (np.asarray(hi) - origins) * inv
    tmin = np.nanmax(np.minimum(t0, t1), axis=-1)
    tmax = np.nanmin(np.maximum(t0, t1), axis=-1)
    return np.maximum(tmin, 0.0), tmax


def box_coverage(camera: Camera, lo, hi, samples: tuple[int, int] = (64, 48)) -> float:
    """Share of the camera's frame whose rays meet the axis-aligned box [lo, hi] (rays through a
    ``samples`` grid of the frame, the camera's aspect and field of view)."""
    from dataclasses import replace
    probe = replace(camera, width=int(samples[0]), height=int(samples[1]))
    d = probe.ray_directions().reshape(-1, 3)
    o = np.broadcast_to(np.asarray(camera.position, np.float64), d.shape)
    t0, t1 = ray_box(o, d, lo, hi)
    return float(np.mean(t1 >= t0))


def frame_voxels(camera: Camera, lo, hi, shape, pad: float = 0.0) -> np.ndarray:
    """bool [nz, ny, nx]: the voxels of the grid ``shape`` over the box [lo, hi] that the camera's frame sees,
    each voxel grown by ``pad`` voxels on every side (conservative: a sphere about its centre of radius (pad + 1/2)
    voxel diagonals, on the inner side of each of the frustum's four planes or within its radius of it)."""
    nz, ny, nx = (int(n) for n in shape)
    lo = np.asarray(lo, np.float64)
    size = (np.asarray(hi, np.float64) - lo) / np.array([nx, ny, nz])
    right, up, fwd = camera.basis()
    tan_y = np.tan(np.radians(camera.fov) / 2)
    tan_x = tan_y * camera.width / camera.height
    radius = (float(pad) + 0.5) * float(np.linalg.norm(size))
    out = np.zeros((nz, ny, nx), bool)
    xs = lo[0] + (np.arange(nx) + 0.5) * size[0] - camera.position[0]
    ys = lo[1] + (np.arange(ny) + 0.5) * size[1] - camera.position[1]
    for iz in range(nz):            # one layer at a time: a main-job grid's offsets would take 100 MB at once
        zc = lo[2] + (iz + 0.5) * size[2] - camera.position[2]
        d = np.stack(np.broadcast_arrays(xs[None, :], ys[:, None], np.full((1, 1), zc)), -1)
        z = d @ fwd
        # the plane u = z tan lies at a distance (|u| - z tan) / sqrt(1 + tan^2) from a centre at (u, z)
        inside = ((np.abs(d @ right) - z * tan_x <= radius * np.sqrt(1 + tan_x ** 2))
                  & (np.abs(d @ up) - z * tan_y <= radius * np.sqrt(1 + tan_y ** 2)))
        out[iz] = inside          # the four half-spaces meet in the frustum alone: none holds points behind
    return out
