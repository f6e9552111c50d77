"""
OpenVDB worker
==============

Defines the OpenVDB grid I/O through the OpenVDB library's own Python binding (``pyopenvdb``, or ``openvdb``
>= 11):

-   :func:`binding`: the OpenVDB Python module.
-   :func:`write`, :func:`read`, :func:`list_grids`: write a float grid, read one, list a file's grids.
-   :func:`main`: the command line below.

Runs in-process where the binding imports, else as a separate program under a Python that has it
(Debian's ``python3-openvdb`` for ``/usr/bin/python3``; see :mod:`natscene.volume.vdb`): this file imports
nothing from natscene, only numpy, json and the binding, and exchanges arrays as ``.npy`` files:

    python vdb_worker.py write GRID.npy OUT.vdb SPEC.json
    python vdb_worker.py read IN.vdb NAME OUT.npy OUT.json
    python vdb_worker.py list IN.vdb OUT.json

Layout: a natscene grid is float32 ``[nz, ny, nx]``; OpenVDB index (i, j, k) = (x, y, z), so the array is
transposed to ``[x, y, z]`` for ``copyFromArray``. The transform is linear and axis-aligned: index (i, j, k)
maps to world ``origin + (i, j, k) * voxel`` where ``origin`` is the centre of voxel (0, 0, 0), i.e.
``bbox_min + voxel / 2`` (OpenVDB's cell-centred convention).
"""
from __future__ import annotations

import json
import sys

import numpy as np

__all__ = ["binding", "write", "read", "list_grids", "main"]


def binding():
    """The OpenVDB Python module (``openvdb`` of OpenVDB >= 11, or ``pyopenvdb``)."""
    try:
        import openvdb as vdb  # noqa: F401
        if hasattr(vdb, "FloatGrid"):
            return vdb
    except ImportError:
        pass
    import pyopenvdb as vdb
    return vdb


def _type_name(g) -> str:
    for attr in ("valueTypeName",):
        v = getattr(g, attr, None)
        if v is not None:
            return str(v() if callable(v) else v)
    return type(g).__name__


def list_grids(path: str) -> list:
    """[(name, value type)] of the grids in a .vdb file (metadata only)."""
    vdb = binding()
    out = []
    for g in vdb.readAllGridMetadata(path):
        out.append([g.name, _type_name(g)])
    return out


def write(path: str, data: np.ndarray, spec: dict) -> None:
    """Write ``data`` ([nz, ny, nx] float32) as a float fog-volume grid ``spec['grid']`` with per-axis voxel
    size ``spec['voxel']`` (x, y, z), voxel-(0,0,0)-centre ``spec['origin']`` and string/float metadata."""
    vdb = binding()
    g = vdb.FloatGrid()
    g.name = spec.get("grid", "density")
    g.gridClass = vdb.GridClass.FOG_VOLUME
    arr = np.ascontiguousarray(np.asarray(data, np.float32).transpose(2, 1, 0))   # [x, y, z]
    g.copyFromArray(arr, ijk=(0, 0, 0), tolerance=0.0)
    v = [float(a) for a in spec["voxel"]]
    o = [float(a) for a in spec["origin"]]
    m = [[v[0], 0.0, 0.0, 0.0], [0.0, v[1], 0.0, 0.0], [0.0, 0.0, v[2], 0.0], [o[0], o[1], o[2], 1.0]]
    g.transform = vdb.createLinearTransform(m)
    for k, val in (spec.get("metadata") or {}).items():
        g[str(k)] = tuple(val) if isinstance(val, list) else val
    vdb.write(path, grids=[g])


def read(path: str, name: str):
    """Read float grid ``name``: (dense [nz, ny, nx] float32, info dict with bbox_min/max, voxel, index box,
    metadata). Raises KeyError/TypeError with the file's grid list when the grid is missing or not float."""
    vdb = binding()
    grids = list_grids(path)
    names = [n for n, _ in grids]
    if name not in names:
        raise KeyError(json.dumps({"missing": name, "grids": grids}))
    typ = dict((n, t) for n, t in grids)[name]
    if typ not in ("float", "double"):
        raise TypeError(json.dumps({"not_float": name, "type": typ, "grids": grids}))
    g = vdb.read(path, name)
    meta = {}
    for k in g.metadata.keys() if hasattr(g, "metadata") else []:
        try:
            val = g[k]
            if isinstance(val, (int, float, str, bool)):
                meta[k] = val
            elif isinstance(val, (tuple, list)):
                meta[k] = list(val)
        except Exception:  # noqa: BLE001 - metadata of a type the binding cannot convert
            pass
    shape = meta.get("natscene:shape_xyz")
    if shape is not None:
        lo, hi = (0, 0, 0), tuple(int(s) - 1 for s in shape)
    else:
        lo, hi = g.evalActiveVoxelBoundingBox()
    n = [int(hi[a]) - int(lo[a]) + 1 for a in range(3)]
    if min(n) < 1:
        raise ValueError(json.dumps({"empty": name}))
    arr = np.zeros(n, np.float32)
    g.copyToArray(arr, ijk=tuple(int(a) for a in lo))
    t = g.transform
    p0 = np.array(t.indexToWorld(tuple(float(a) for a in lo)))
    ex = [np.array(t.indexToWorld((lo[0] + (a == 0), lo[1] + (a == 1), lo[2] + (a == 2)))) - p0 for a in range(3)]
    voxel = [float(np.linalg.norm(e)) for e in ex]
    axis_aligned = all(abs(ex[a][b]) < 1e-9 * max(voxel) for a in range(3) for b in range(3) if a != b)
    info = {"index_min": [int(a) for a in lo], "index_max": [int(a) for a in hi], "voxel": voxel,
            "axis_aligned": bool(axis_aligned),
            "bbox_min": (p0 - 0.5 * np.array(voxel)).tolist(),
            "bbox_max": (p0 + (np.array(n) - 0.5) * np.array(voxel)).tolist(), "metadata": meta, "type": typ}
    return np.ascontiguousarray(arr.transpose(2, 1, 0)), info


def main(argv) -> int:
    cmd = argv[1]
    try:
        if cmd == "write":
            spec = json.loads(open(argv[4]).read())
            write(argv[3], np.load(argv[2]), spec)
        elif cmd == "read":
            arr, info = read(argv[2], argv[3])
            np.save(argv[4], arr)
            with open(argv[5], "w") as f:
                json.dump(info, f)
        elif cmd == "list":
            with open(argv[3], "w") as f:
                json.dump(list_grids(argv[2]), f)
        else:
            raise SystemExit(f"unknown command {cmd}")
    except (KeyError, TypeError, ValueError) as e:
        msg = e.args[0] if e.args else str(e)
        sys.stderr.write("NATSCENE_VDB_ERROR " + str(msg) + "\n")
        return 3
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
