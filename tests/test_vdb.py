"""OpenVDB in and out (natscene.volume.vdb): round trip of values and transform, files written by the OpenVDB
library's own writer read through the import path, clear errors for files without the grid asked for."""
import shutil
import subprocess
import sys
import textwrap

import numpy as np
import pytest

from natscene.errors import InputError
from natscene.volume import vdb
from natscene.volume.build import build_volume

try:
    vdb.backend()
    HAVE_VDB = True
except InputError as e:  # pragma: no cover - depends on the machine's set-up
    HAVE_VDB, WHY = False, str(e)

pytestmark = pytest.mark.skipif(not HAVE_VDB, reason="OpenVDB's Python binding is not installed (make setup)")


def _openvdb_python(code: str, *args):
    """Run ``code`` with the OpenVDB library's own binding (this interpreter or the worker's)."""
    kind, py = vdb.backend()
    exe = sys.executable if kind == "inprocess" else py
    subprocess.run([exe, "-c", textwrap.dedent(code), *map(str, args)], check=True)


def test_round_trip_values_and_transform(tmp_path):
    rng = np.random.default_rng(1)
    d = rng.uniform(0, 1, (17, 12, 23)).astype(np.float32)          # [nz, ny, nx]
    d[d < 0.3] = 0                                                   # sparse: inactive background voxels
    d[0] = 0                                                         # an empty first slice stays in the box
    lo, hi = np.array([-1150.0, 1500.0, -850.0]), np.array([1150.0, 1500.0 + 1200.0, 850.0])
    vdb.write_vdb(tmp_path / "d.vdb", d, lo, hi, metadata={"natscene:extinction_scale": 0.125})
    back, blo, bhi, info = vdb.read_vdb(tmp_path / "d.vdb")
    assert back.dtype == np.float32 and np.array_equal(back, d)
    np.testing.assert_allclose(blo, lo, rtol=0, atol=1e-9)
    np.testing.assert_allclose(bhi, hi, rtol=0, atol=1e-9)
    np.testing.assert_allclose(info["voxel"], [100.0, 100.0, 100.0])
    assert info["metadata"]["natscene:extinction_scale"] == 0.125
    assert vdb.list_grids(tmp_path / "d.vdb") == [("density", "float")]


def test_same_grid_same_bytes_and_a_content_uuid(tmp_path):
    """OpenVDB stamps each file with a random UUID (36 ASCII characters at byte 21 of the header); write_vdb
    replaces it with a version-5 UUID of the file's other bytes: two writes of one grid are byte-identical, a
    different grid gets another UUID, and the library still reads the file (UUID read back by its parser)."""
    import uuid
    d = np.random.default_rng(3).uniform(0, 1, (6, 5, 7)).astype(np.float32)
    lo, hi = np.zeros(3), np.array([7.0, 5.0, 6.0])
    for name in ("a.vdb", "b.vdb"):
        vdb.write_vdb(tmp_path / name, d, lo, hi)
    e = d.copy()
    e[3, 2, 1] += 0.5
    vdb.write_vdb(tmp_path / "c.vdb", e, lo, hi)
    a, b, c = [(tmp_path / n).read_bytes() for n in ("a.vdb", "b.vdb", "c.vdb")]
    assert a == b
    ua, uc = uuid.UUID(a[21:57].decode()), uuid.UUID(c[21:57].decode())
    assert ua.version == 5 and ua != uc
    back, _, _, _ = vdb.read_vdb(tmp_path / "a.vdb")
    assert np.array_equal(back, d)
    _openvdb_python("""
        import sys
        try:
            import openvdb as vdb
            assert hasattr(vdb, "FloatGrid")
        except Exception:
            import pyopenvdb as vdb
        g, meta = vdb.readAll(sys.argv[1])
        assert [x.name for x in g] == ["density"]
    """, tmp_path / "a.vdb")
    (tmp_path / "junk.vdb").write_bytes(b"not a vdb file at all, but longer than sixty bytes to pass the size check")
    with pytest.raises(RuntimeError, match="junk.vdb"):
        vdb.content_uuid(tmp_path / "junk.vdb")


def test_library_writer_reads_through_the_import_path(tmp_path):
    # a fog volume written by OpenVDB itself (a sphere of density 1 - r/R on a translated, scaled grid)
    _openvdb_python("""
        import sys, numpy as np
        try:
            import openvdb as vdb
            assert hasattr(vdb, "FloatGrid")
        except Exception:
            import pyopenvdb as vdb
        n = 24
        i, j, k = np.meshgrid(*[np.arange(n)] * 3, indexing="ij")
        r = np.sqrt((i - 11.5) ** 2 + (j - 11.5) ** 2 + (k - 11.5) ** 2)
        a = np.clip(1 - r / 10, 0, None).astype(np.float32)
        a[20:, :, :] = 0
        g = vdb.FloatGrid()
        g.name = "smoke_density"
        g.copyFromArray(a)
        g.transform = vdb.createLinearTransform(voxelSize=50.0)
        g2 = vdb.Vec3SGrid()
        g2.name = "velocity"
        vdb.write(sys.argv[1], grids=[g, g2])
    """, tmp_path / "lib.vdb")
    vol, stats = build_volume({"kind": "file", "grid": "smoke_density"}, "user", str(tmp_path / "lib.vdb"))
    # the active voxels of a sphere of radius 10 around index 11.5 span indices 2..21 (x: 2..19, cut at 20)
    assert vol.density.shape == (20, 20, 18)                         # [z, y, x]
    np.testing.assert_allclose(vol.bbox_min, [2 * 50 - 25, 2 * 50 - 25, 2 * 50 - 25])
    np.testing.assert_allclose(vol.bbox_max, [19 * 50 + 25, 21 * 50 + 25, 21 * 50 + 25])
    c = vol.density[11 - 2, 11 - 2, 11 - 2]                          # voxel (11, 11, 11): r = sqrt(0.75)
    assert c == pytest.approx(1 - np.sqrt(0.75) / 10, rel=1e-6)


def test_missing_or_non_float_grids_are_named(tmp_path):
    _openvdb_python("""
        import sys
        try:
            import openvdb as vdb
            assert hasattr(vdb, "FloatGrid")
        except Exception:
            import pyopenvdb as vdb
        v = vdb.Vec3SGrid(); v.name = "vel"; v.fill((0, 0, 0), (3, 3, 3), (1, 0, 0))
        b = vdb.BoolGrid(); b.name = "mask"; b.fill((0, 0, 0), (3, 3, 3), True)
        vdb.write(sys.argv[1], grids=[v, b])
        f = vdb.FloatGrid(); f.name = "temperature"; f.fill((0, 0, 0), (3, 3, 3), 1.0)
        vdb.write(sys.argv[2], grids=[f, v])
    """, tmp_path / "nofloat.vdb", tmp_path / "other.vdb")
    with pytest.raises(InputError, match="no float grid") as e:
        build_volume({"kind": "file"}, "user", str(tmp_path / "nofloat.vdb"))
    assert "nofloat.vdb" in str(e.value) and "'vel' (vec3s)" in str(e.value) and "'mask' (bool)" in str(e.value)
    with pytest.raises(InputError, match="no grid named 'density'") as e:
        build_volume({"kind": "file"}, "user", str(tmp_path / "other.vdb"))
    assert "other.vdb" in str(e.value) and "'temperature' (float)" in str(e.value)
    with pytest.raises(InputError, match="not a float grid"):
        build_volume({"kind": "file", "grid": "vel"}, "user", str(tmp_path / "other.vdb"))
    (tmp_path / "junk.vdb").write_bytes(b"not a vdb file at all")
    with pytest.raises(InputError, match="junk.vdb"):
        build_volume({"kind": "file"}, "user", str(tmp_path / "junk.vdb"))


def test_generated_volume_round_trips_through_vdb(tmp_path):
    vol, _ = build_volume({"kind": "cumulus", "resolution": [40, 32, 40], "seed": 2}, "c")
    vdb.write_vdb(tmp_path / "density.vdb", vol.density, vol.bbox_min, vol.bbox_max)
    back, _ = build_volume({"kind": "file"}, "c", str(tmp_path / "density.vdb"))
    assert np.array_equal(back.density, vol.density)
    np.testing.assert_allclose(back.bbox_min, vol.bbox_min, atol=1e-6)
    np.testing.assert_allclose(back.bbox_max, vol.bbox_max, atol=1e-6)
    assert back.extinction_scale == pytest.approx(vol.extinction_scale, rel=1e-6)
