"""Small test fixtures shared by several test files (imported as ``from helpers import ...``)."""
import numpy as np

from natscene.volume.grid import Volume


def sphere_volume(n: int = 40, radius: float = 0.4, ext: float = 40.0) -> Volume:
    """A constant-density sphere of ``radius`` (box units) in an n^3 grid over the unit box x, z in
    [-0.5, 0.5], y in [0, 1], with extinction scale ``ext``."""
    x = (np.arange(n) + 0.5) / n - 0.5
    zz, yy, xx = np.meshgrid(x, x, x, indexing="ij")
    d = (np.sqrt(xx**2 + yy**2 + zz**2) < radius).astype(np.float32)
    return Volume(d, np.array([-0.5, 0.0, -0.5]), np.array([0.5, 1.0, 0.5]), ext)
