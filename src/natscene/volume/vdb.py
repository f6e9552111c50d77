"""
OpenVDB in and out
==================

Defines natscene density grids as ``.vdb`` files (a float fog-volume grid, ``density`` by default):

-   :func:`write_vdb`, :func:`read_vdb`, :func:`list_grids`: write a grid, read a float grid, list a file's grids.
-   :func:`content_uuid`: replace a file's random UUID by a name-based one (reproducible bytes).
-   :func:`backend`: which OpenVDB binding serves this process (in-process or a separate program).

The library is the OpenVDB project's own (ASWF OpenVDB, the reference implementation that Houdini, Blender,
EmberGen and the Disney cloud data set use), through its Python binding. Which one:

- in this process, where ``openvdb`` (OpenVDB >= 11, nanobind) or ``pyopenvdb`` imports (e.g. a conda-forge
  environment);
- else Debian's ``python3-openvdb`` (OpenVDB 10.0.1) under the system Python ``/usr/bin/python3`` (or the
  interpreter in ``NATSCENE_VDB_PYTHON``), running :mod:`natscene.volume.vdb_worker` as a separate program.
  That binding cannot load in the project's virtual environment: it is built with Boost.Python against
  Debian's NumPy 1.24, and the environment has NumPy 2 (the CPython 3.11 ABI itself would match), so the grid
  travels through a temporary ``.npy`` file (its cost: docs/stages/volume.md, "OpenVDB").

``tools/setup.sh`` installs ``python3-openvdb`` with apt-get when neither is found. Values are written with
tolerance 0 (lossless float32; zero voxels stay inactive background) and the transform is linear and
axis-aligned: the centre of voxel (0, 0, 0) at ``bbox_min + voxel / 2``, world metres, y up.

Reproducible bytes: the library stamps every file it writes with a fresh random UUID (``Archive::writeHeader``;
readers use it only to tell files apart, e.g. for delayed loading). :func:`write_vdb` replaces it with a
name-based UUID (RFC 4122 version 5) of the file's other bytes, so the same grid gives the same file on every
run and two different grids still get different UUIDs.

References
----------
-   Leach, P., Mealling, M., & Salz, R. (2005). A Universally Unique IDentifier (UUID) URN Namespace. RFC 4122.
-   Museth, K. (2013). VDB: high-resolution sparse volumes with dynamic topology. ACM Transactions on Graphics,
    32(3).
"""
from __future__ import annotations

import functools
import hashlib
import json
import os
import struct
import subprocess
import tempfile
import uuid
from pathlib import Path

import numpy as np

from natscene.errors import InputError
from natscene.io import atomic_path

__all__ = ["write_vdb", "read_vdb", "list_grids", "content_uuid", "backend"]

WORKER = Path(__file__).with_name("vdb_worker.py")

# The header of an OpenVDB file of format >= 222 (OpenVDB io/Archive.cc, Archive::writeHeader): int64 magic,
# uint32 file format version, uint32 library major and minor version, char hasGridOffsets, then the file's UUID
# as 36 ASCII characters (the per-file compression flag before it was dropped at format 222).
VDB_MAGIC = 0x56444220
UUID_OFFSET, UUID_CHARS = 21, 36
UUID_NAMESPACE = uuid.uuid5(uuid.NAMESPACE_URL, "natscene:openvdb-file")


@functools.lru_cache(maxsize=1)
def backend() -> tuple[str, str | None]:
    """("inprocess", None) or ("subprocess", python executable); raises InputError when there is none."""
    try:
        from natscene.volume import vdb_worker
        vdb_worker.binding()
        return ("inprocess", None)
    except Exception:  # noqa: BLE001 - not importable here (missing, or built for another NumPy)
        pass
    tried = []
    for py in [os.environ.get("NATSCENE_VDB_PYTHON"), "/usr/bin/python3"]:
        if not py or py in tried:
            continue
        tried.append(py)
        try:
            r = subprocess.run([py, "-c", "import pyopenvdb"], capture_output=True, timeout=60)
        except (OSError, subprocess.TimeoutExpired):
            continue
        if r.returncode == 0:
            return ("subprocess", py)
    raise InputError("OpenVDB's Python binding was not found (neither in this Python nor as pyopenvdb under "
                     f"{', '.join(tried)}): run `make setup` (installs Debian's python3-openvdb) or set "
                     "NATSCENE_VDB_PYTHON to a Python that can `import pyopenvdb`")


def _run(args) -> None:
    kind, py = backend()
    r = subprocess.run([py, str(WORKER), *map(str, args)], capture_output=True, text=True)
    if r.returncode != 0:
        err = r.stderr.strip().splitlines()
        tagged = [e for e in err if e.startswith("NATSCENE_VDB_ERROR ")]
        if tagged:
            raise _VdbError(tagged[-1][len("NATSCENE_VDB_ERROR "):])
        raise RuntimeError(f"OpenVDB worker failed ({py} {WORKER.name} {args[0]}): {' '.join(err[-3:])}")


class _VdbError(Exception):
    """A tagged error of the worker (JSON payload)."""


def list_grids(path) -> list[tuple[str, str]]:
    """[(name, value type)] of the grids in ``path``."""
    path = Path(path)
    if not path.is_file():
        raise InputError(f"{path}: OpenVDB file not found")
    kind, _ = backend()
    try:
        if kind == "inprocess":
            from natscene.volume import vdb_worker
            return [tuple(g) for g in vdb_worker.list_grids(str(path))]
        with tempfile.TemporaryDirectory() as tmp:
            _run(["list", path, Path(tmp) / "g.json"])
            return [tuple(g) for g in json.loads((Path(tmp) / "g.json").read_text())]
    except (_VdbError, RuntimeError, OSError) as e:
        raise InputError(f"{path}: not a readable OpenVDB file ({e})") from e
    except Exception as e:  # noqa: BLE001 - the in-process binding raises its own types
        raise InputError(f"{path}: not a readable OpenVDB file ({e})") from e


def write_vdb(path, density: np.ndarray, bbox_min, bbox_max, grid: str = "density", metadata: dict | None = None):
    """Write a float32 grid ``[nz, ny, nx]`` placed in the box [bbox_min, bbox_max] (world metres) as ``path``
    (atomically), one float fog-volume grid named ``grid`` with ``metadata`` (str/float/int values); the same
    arguments give the same bytes (:func:`content_uuid`)."""
    d = np.ascontiguousarray(density, np.float32)
    nz, ny, nx = d.shape
    lo, hi = np.asarray(bbox_min, np.float64), np.asarray(bbox_max, np.float64)
    voxel = (hi - lo) / np.array([nx, ny, nz], np.float64)
    meta = {"natscene:shape_xyz": (int(nx), int(ny), int(nz)), "natscene:units": "m",
            "natscene:up_axis": "y", **(metadata or {})}
    spec = {"grid": grid, "voxel": voxel.tolist(), "origin": (lo + voxel / 2).tolist(), "metadata": meta}
    kind, _ = backend()
    with atomic_path(path) as tmp:
        tmp = Path(tmp)
        if kind == "inprocess":
            from natscene.volume import vdb_worker
            vdb_worker.write(str(tmp), d, spec)
        else:
            with tempfile.TemporaryDirectory() as td:
                np.save(Path(td) / "g.npy", d)
                spec["metadata"]["natscene:shape_xyz"] = list(spec["metadata"]["natscene:shape_xyz"])
                (Path(td) / "spec.json").write_text(json.dumps(spec))
                _run(["write", Path(td) / "g.npy", tmp, Path(td) / "spec.json"])
        content_uuid(tmp)


def content_uuid(path) -> str:
    """Replace the random UUID in the header of the OpenVDB file ``path`` (in place) by the version-5 UUID of
    the SHA-256 of the file's other bytes; returns the new UUID. Raises RuntimeError for a file whose header is
    not the one this module writes (OpenVDB file format >= 222, a 36-character UUID at byte 21)."""
    path = Path(path)
    data = bytearray(path.read_bytes())
    end = UUID_OFFSET + UUID_CHARS
    if len(data) < end:
        raise RuntimeError(f"{path}: too short for an OpenVDB header ({len(data)} bytes)")
    magic, fmt = struct.unpack_from("<qI", data, 0)
    if magic != VDB_MAGIC or fmt < 222:
        raise RuntimeError(f"{path}: not an OpenVDB file of format >= 222 (magic {magic:#x}, format {fmt})")
    try:
        uuid.UUID(data[UUID_OFFSET:end].decode("ascii"))
    except (UnicodeDecodeError, ValueError) as e:
        raise RuntimeError(f"{path}: no UUID string at byte {UUID_OFFSET} of the header") from e
    digest = hashlib.sha256(bytes(data[:UUID_OFFSET]) + bytes(data[end:])).hexdigest()
    new = str(uuid.uuid5(UUID_NAMESPACE, digest))
    data[UUID_OFFSET:end] = new.encode("ascii")
    path.write_bytes(bytes(data))
    return new


def _grid_list_text(grids) -> str:
    return ", ".join(f"'{n}' ({t})" for n, t in grids) or "none"


def read_vdb(path, grid: str = "density") -> tuple[np.ndarray, np.ndarray, np.ndarray, dict]:
    """Read float grid ``grid`` of a ``.vdb``: (density [nz, ny, nx] float32, bbox_min, bbox_max, info).

    The dense array covers the grid's active voxel box (or, for natscene's own files, the whole written grid).
    A missing grid, a file with no float grid, or a grid of another type raises :class:`InputError` naming the
    file and the grids it has."""
    path = Path(path)
    grids = list_grids(path)
    floats = [n for n, t in grids if t in ("float", "double")]
    if not floats:
        raise InputError(f"{path}: no float grid in this OpenVDB file (its grids: {_grid_list_text(grids)}); "
                         "natscene reads a scalar float density grid")
    if grid not in [n for n, _ in grids]:
        raise InputError(f"{path}: no grid named '{grid}' (its grids: {_grid_list_text(grids)}); set "
                         f"volumes.<name>.grid to one of its float grids: {', '.join(floats)}")
    if grid not in floats:
        raise InputError(f"{path}: grid '{grid}' is not a float grid (its grids: {_grid_list_text(grids)})")
    kind, _ = backend()
    try:
        if kind == "inprocess":
            from natscene.volume import vdb_worker
            arr, info = vdb_worker.read(str(path), grid)
        else:
            with tempfile.TemporaryDirectory() as td:
                _run(["read", path, grid, Path(td) / "g.npy", Path(td) / "info.json"])
                arr = np.load(Path(td) / "g.npy")
                info = json.loads((Path(td) / "info.json").read_text())
    except (_VdbError, ValueError) as e:
        raise InputError(f"{path}: grid '{grid}' has no active voxels ({e})") from e
    if not info.get("axis_aligned", True):
        raise InputError(f"{path}: grid '{grid}' has a rotated transform; natscene needs an axis-aligned grid")
    return (arr.astype(np.float32, copy=False), np.asarray(info["bbox_min"], np.float64),
            np.asarray(info["bbox_max"], np.float64), info)
