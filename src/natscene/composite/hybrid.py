"""
Hybrid intermediate image
=========================

Defines the hybrid intermediate image of Dong (2007, §2.3.2) and its colour transformation (§2.4):

-   :class:`HybridImage`: the RGB part, the spectral part and the coverage of every pixel.
-   :func:`final_rgb`: the §2.4 colour transformation.

Each pixel holds an RGB part (linear sRGB, what RGB materials lit by RGB-converted lights produced), a
spectral part S(λ) (what spectral materials produced, radiance on the wavelength grid) and a coverage A.
On disk: one EXR with channels ``R, G, B, S380 ... S780, A``. The displayable colour is

    final = RGB + M_XYZ->sRGB · κ ∫ S(λ) x̄(λ) dλ        (Color_inter = Color_RGB + Color_spectrum, §2.3.2)

References
----------
-   Dong, W. (2007). Rendering Algorithms for Natural Scenes. PhD thesis, Université Henri Poincaré - Nancy I.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from natscene.spectral.grid import DEFAULT_GRID, WavelengthGrid, spectrum_to_rgb_matrix

__all__ = ["HybridImage", "final_rgb"]


@dataclass
class HybridImage:
    rgb: np.ndarray  # (H, W, 3) linear sRGB part
    spectral: np.ndarray  # (H, W, N) spectral radiance part
    alpha: np.ndarray  # (H, W) coverage of the set's geometry (0 where the background plate shows)
    grid: WavelengthGrid = DEFAULT_GRID
    mask: np.ndarray | None = None  # (H, W) bool: pixels whose spectral part may be non-zero (None: any)

    def channel_names(self) -> list[str]:
        return ["R", "G", "B"] + self.grid.channel_names("S") + ["A"]

    def to_array(self) -> np.ndarray:
        return np.concatenate([self.rgb, self.spectral, self.alpha[..., None]], axis=-1).astype(np.float32)

    @classmethod
    def from_array(cls, pixels: np.ndarray, channels: list[str], grid: WavelengthGrid | None = None) -> "HybridImage":
        """Rebuild from an EXR read by natscene.io.read_exr (channels R, G, B, S<λ>..., A)."""
        s_names = [c for c in channels if c.startswith("S") and c[1:].replace(".", "").isdigit()]
        wl = np.array([float(c[1:]) for c in s_names])
        if grid is None:
            step = float(wl[1] - wl[0]) if wl.size > 1 else 5.0
            grid = WavelengthGrid(float(wl[0]), float(wl[-1]), step)
        idx = [channels.index(c) for c in ("R", "G", "B")]
        sidx = [channels.index(c) for c in s_names]
        spectral = pixels[..., sidx]
        return cls(pixels[..., idx], spectral, pixels[..., channels.index("A")], grid, np.any(spectral != 0, -1))

    def final(self) -> np.ndarray:
        """RGB + M_XYZ->sRGB κ ∫ S x̄ dλ, (H, W, 3) float32 (the integral only where the spectral part lives)."""
        if self.mask is None:
            return final_rgb(self.rgb, self.spectral, self.grid)
        out = np.array(self.rgb, np.float32)
        out[self.mask] = final_rgb(out[self.mask], self.spectral[self.mask], self.grid)
        return out


def final_rgb(rgb: np.ndarray, spectral: np.ndarray, grid: WavelengthGrid = DEFAULT_GRID) -> np.ndarray:
    """Dong §2.4 colour transformation of the intermediate image."""
    A = spectrum_to_rgb_matrix(grid).astype(np.float32)
    return (np.asarray(rgb, np.float32) + np.asarray(spectral, np.float32) @ A).astype(np.float32)
