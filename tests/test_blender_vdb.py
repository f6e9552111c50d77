"""A real OpenVDB client opens natscene's density.vdb: Debian's Blender (3.4) imports it headless as a volume
object and renders it with Cycles; the cloud's pixels are lit, the sky around it stays dark.

Skips when ``blender`` is not installed (``make setup-extras`` installs it)."""
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

from natscene.errors import InputError

BLENDER = shutil.which("blender")
SCRIPT = Path(__file__).resolve().parents[1] / "tools" / "blender" / "render_vdb.py"


@pytest.mark.skipif(BLENDER is None, reason="blender is not installed (run `make setup-extras`)")
def test_blender_imports_and_renders_density_vdb(tmp_path):
    from natscene.volume import vdb
    try:
        vdb.backend()
    except InputError as e:
        pytest.skip(str(e))
    from natscene.volume.build import build_volume
    vol, _ = build_volume({"kind": "cumulus", "resolution": [48, 36, 48], "seed": 2}, "c")
    path = tmp_path / "density.vdb"
    vdb.write_vdb(path, vol.density, vol.bbox_min, vol.bbox_max)
    png = tmp_path / "blender.png"
    r = subprocess.run([BLENDER, "-b", "--factory-startup", "--python", str(SCRIPT), "--", str(path), str(png), "64"],
                       capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stdout[-2000:] + r.stderr[-2000:]
    assert "NATSCENE_GRIDS ['density']" in r.stdout, r.stdout[-2000:]
    assert png.is_file()
    import imageio.v3 as iio
    img = iio.imread(png)[..., :3].astype(np.float64) / 255.0
    lum = img.mean(axis=-1)
    # where the cloud is (its projected optical depth, rotated into the image): lit; far from it: the dark sky
    tau = vol.density.sum(axis=0)                                   # [y, x] front view, y up
    assert tau.max() > 0
    centre = lum[24:40, 24:40].mean()
    corners = np.mean([lum[:6, :6].mean(), lum[:6, -6:].mean(), lum[-6:, :6].mean(), lum[-6:, -6:].mean()])
    assert centre > 0.15 and corners < 0.02, (centre, corners)
    assert (lum > 0.1).mean() > 0.05                                # a cloud, not a few bright pixels
