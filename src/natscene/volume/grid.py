"""
Density grids
=============

Defines the density grids on disk and in memory: Mitsuba's binary ``.vol`` format, user grid import and
validation:

-   :class:`Volume`, :func:`placement`: a density grid placed in the world, and the world box of a grid.
-   :func:`write_vol`, :func:`read_vol`: Mitsuba ``.vol`` files; :func:`load_volume`: the ``volume`` rule's output.
-   :func:`import_grid`: a user grid (``.vdb``, ``.vol``, ``.npy``), validated.
-   :func:`column_statistics`, :func:`mean_optical_depth`: the columns ∫ rho ds through the grid.

Mitsuba 3 ``.vol`` (version 3): bytes ``VOL``, uint8 version 3, int32 encoding (1 = float32), int32 xres,
yres, zres, int32 channels, 6 float32 bounding box (xmin, ymin, zmin, xmax, ymax, zmax), then float32 data
with x varying fastest: ``data[((z * yres + y) * xres + x) * channels + c]``. In memory a grid is a
float32 array indexed ``[z, y, x]`` (the layout of ``mi.TensorXf`` for ``gridvolume``).

World placement (DESIGN §3 and the contract between stages): metres, y up, ground y = 0; :func:`placement`
gives a box centred on x = z = 0 with its base at y = 0, cubic voxels, longest side = ``size``, and the
volume stage lifts it to its altitude (:mod:`natscene.volume.build`). Extinction: mu_t(x) [1/m] = sigma_t *
rho(x) * extinction_scale.
"""
from __future__ import annotations

import struct
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from natscene.errors import InputError
from natscene.io import atomic_path, read_yaml

__all__ = ["Volume", "placement", "write_vol", "read_vol", "load_volume", "import_grid", "column_statistics",
           "mean_optical_depth"]

MAX_RES = 1024


@dataclass
class Volume:
    """A cloud density grid placed in the world."""

    density: np.ndarray       # float32 [nz, ny, nx] in [0, 1]
    bbox_min: np.ndarray      # (3,) world x, y, z
    bbox_max: np.ndarray      # (3,)
    extinction_scale: float   # mu_t = sigma_t * rho * extinction_scale

    @property
    def resolution(self) -> tuple[int, int, int]:
        """(nx, ny, nz)."""
        nz, ny, nx = self.density.shape
        return nx, ny, nz

    @property
    def voxel_size(self) -> np.ndarray:
        return (self.bbox_max - self.bbox_min) / np.array(self.resolution, np.float64)


def placement(resolution, size: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """World bounding box of a grid of ``resolution`` (nx, ny, nz): cubic voxels, longest side ``size``,
    centred on x = z = 0, base at y = 0."""
    res = np.asarray(resolution, np.float64)
    ext = res / res.max() * float(size)
    lo = np.array([-ext[0] / 2, 0.0, -ext[2] / 2])
    return lo, lo + ext


def write_vol(path, density: np.ndarray, bbox_min, bbox_max) -> None:
    """Write a single-channel float32 grid ``[nz, ny, nx]`` as a Mitsuba ``.vol`` file (atomically)."""
    d = np.ascontiguousarray(density, np.float32)
    if d.ndim != 3:
        raise ValueError(f"density must be 3-D [nz, ny, nx], got shape {d.shape}")
    nz, ny, nx = d.shape
    header = b"VOL" + struct.pack("<B", 3) + struct.pack("<iiiii", 1, nx, ny, nz, 1)
    header += struct.pack("<6f", *np.asarray(bbox_min, float), *np.asarray(bbox_max, float))
    with atomic_path(path) as tmp:
        with open(tmp, "wb") as f:
            f.write(header)
            f.write(d.tobytes(order="C"))


def read_vol(path) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Read a Mitsuba ``.vol`` grid: (density [nz, ny, nx] float32 (first channel), bbox_min, bbox_max)."""
    path = Path(path)
    if not path.is_file():
        raise InputError(f"{path}: volume file not found")
    raw = path.read_bytes()
    if len(raw) < 48 or raw[:3] != b"VOL" or raw[3] != 3:
        raise InputError(f"{path}: not a Mitsuba .vol file (version 3)")
    encoding, nx, ny, nz, nc = struct.unpack("<iiiii", raw[4:24])
    if encoding != 1:
        raise InputError(f"{path}: .vol encoding {encoding} not supported (only float32 = 1)")
    bbox = np.array(struct.unpack("<6f", raw[24:48]), np.float64)
    n = nx * ny * nz * nc
    if len(raw) != 48 + 4 * n:
        raise InputError(f"{path}: truncated .vol file ({len(raw)} bytes, expected {48 + 4 * n})")
    data = np.frombuffer(raw, np.float32, n, 48).reshape(nz, ny, nx, nc)[..., 0]
    return data.copy(), bbox[:3], bbox[3:]


def check_density(density: np.ndarray, source: str) -> np.ndarray:
    """Validate a density grid (3-D, each side 1..1024, finite, non-negative, not all zero).

    Values above 1 are rescaled to [0, 1] by the maximum (stored density is normalised). Raises
    :class:`InputError` naming ``source``.
    """
    d = np.asarray(density)
    if d.ndim != 3:
        raise InputError(f"{source}: a volume grid must be 3-D, got shape {d.shape}")
    if min(d.shape) < 1 or max(d.shape) > MAX_RES:
        raise InputError(f"{source}: grid shape {d.shape} outside 1..{MAX_RES} per axis")
    d = d.astype(np.float32, copy=False)
    if not np.isfinite(d).all():
        raise InputError(f"{source}: grid holds {int((~np.isfinite(d)).sum())} NaN/inf values; clean the data")
    if (d < 0).any():
        raise InputError(f"{source}: grid holds negative densities (min {float(d.min()):.3g}); densities must be >= 0")
    m = float(d.max())
    if m <= 0:
        raise InputError(f"{source}: grid is all zeros: there is no cloud to render")
    return d / m if m > 1 else d


def import_grid(path, axes: str = "zyx", grid: str = "density"):
    """Load a user grid as validated ``[nz, ny, nx]`` and its world box when the file has one:
    ``.vdb`` (OpenVDB float grid ``grid``, with its transform), Mitsuba ``.vol`` (with its bbox) or ``.npy``
    in ``axes`` order (no box: None). -> (density, (bbox_min, bbox_max) or None)."""
    path = Path(path)
    if not path.is_file():
        raise InputError(f"{path}: user volume grid not found (config key volumes.<name>.path)")
    box = None
    if path.suffix == ".vdb":
        from natscene.volume.vdb import read_vdb
        d, lo, hi, _ = read_vdb(path, grid)
        box = (lo, hi)
    elif path.suffix == ".vol":
        d, lo, hi = read_vol(path)
        box = (lo, hi)
    elif path.suffix == ".npy":
        try:
            d = np.load(path, allow_pickle=False)
        except Exception as e:  # noqa: BLE001
            raise InputError(f"{path}: cannot read .npy grid ({e})") from e
        if d.ndim == 4 and d.shape[-1] == 1:
            d = d[..., 0]
        if d.ndim == 3 and axes == "xyz":
            d = np.transpose(d, (2, 1, 0))
    else:
        raise InputError(f"{path}: unsupported grid format '{path.suffix}' (use .vdb, .npy or Mitsuba .vol)")
    return check_density(d, str(path)), box


def load_volume(directory) -> Volume:
    """Load ``density.vol`` + ``meta.yaml`` written by the ``volume`` rule."""
    directory = Path(directory)
    density, lo, hi = read_vol(directory / "density.vol")
    meta = read_yaml(directory / "meta.yaml")
    return Volume(density, np.asarray(meta["bbox_min"], np.float64), np.asarray(meta["bbox_max"], np.float64),
                  float(meta["extinction_scale"]))


def column_statistics(density: np.ndarray, voxel: float, axis: int = 0) -> dict:
    """The column ∫ rho ds (metres, world units) along grid ``axis`` (0 = z, horizontal; 1 = y, vertical) over the
    rays that hit the cloud: its mean, 95th percentile and maximum. Times an extinction in 1/m, the optical depth
    through the cloud."""
    col = density.sum(axis=axis, dtype=np.float64) * voxel
    col = col[col > 0]
    if not col.size:
        return {"mean": 0.0, "p95": 0.0, "max": 0.0}
    return {"mean": float(col.mean()), "p95": float(np.percentile(col, 95)), "max": float(col.max())}


def mean_optical_depth(density: np.ndarray, voxel: float, axis: int = 0) -> float:
    """Mean of the integral of rho along ``axis`` (world units), over the rays that hit the cloud."""
    col = density.sum(axis=axis) * voxel
    hit = col > 0
    return float(col[hit].mean()) if hit.any() else 0.0
