"""
Specification of the set
========================

Defines what the final shot's set holds (Dong 2007 Ch. 2 set-up): camera, background plate, sky, sun, ground,
RGB surfaces (textured petals and leaves with cut-out alpha, plain stems), thin-film objects (the beetles'
shells) and the air between them, all in metres in the set's frame (y up, ground y = 0; the set's origin is
a world point near the camera, so that float32 geometry keeps millimetres while the world's cloud is
kilometres away).

-   :class:`SetSpec`: the set: camera, plate, ground, surfaces, films, shapes, sky, sun and atmosphere.
-   :class:`Surface`, :class:`Film`, :class:`Shape`, :class:`Ground`, :class:`Atmosphere`: its parts;
    :func:`gradient_sky_default`: its default sky.
-   :func:`sun_spectrum_from_rgb`: the spectral sun of an RGB colour and intensity.

The sun's spectrum: ``"d65"`` (Dong §2.5) scaled to luminance L_in·Y(c_in), or ``"matched"`` (a daylight SPD
matched to c_in, :func:`natscene.spectral.illuminants.sun_spd`) times L_in. In the cloud model the single
scattering radiance is c_in·L_in·β·p·S_sun (Dobashi Eq. 5), i.e. the clouds are lit by a sun of irradiance
c_in·L_in; the set takes the same sun.

References
----------
-   Dobashi, Y., Iwasaki, W., Ono, A., Yamamoto, T., Yue, Y., & Nishita, T. (2012). An inverse problem approach
    for automatically adjusting the parameters for rendering clouds using photographs. ACM Transactions on
    Graphics, 31(6).
-   Dong, W. (2007). Rendering Algorithms for Natural Scenes. PhD thesis, Université Henri Poincaré - Nancy I.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from natscene.composite.mesh import TriMesh
from natscene.composite.texture import MipTexture
from natscene.geometry import Camera, sun_direction
from natscene.spectral.grid import DEFAULT_GRID, WavelengthGrid
from natscene.spectral.illuminants import d65, sun_spd

__all__ = ["Surface", "Film", "Shape", "Ground", "Atmosphere", "gradient_sky_default", "SetSpec",
           "sun_spectrum_from_rgb"]


@dataclass
class Surface:
    """An RGB (Lambertian) material: a texture (RGB albedo, alpha = cut-out when ``cutout``) or a colour;
    ``translucency`` τ: the fraction of the albedo transmitted diffusely through the sheet (petals, leaves)."""

    name: str
    texture: MipTexture | None = None
    color: tuple = (0.5, 0.5, 0.5)
    cutout: bool = False
    translucency: float = 0.0


@dataclass
class Film:
    """A thin-film coating (Dong's gold bug: 500 nm Au on Cu; the jewel beetle: a chitin/melanoprotein stack)."""

    name: str
    layers: list = field(default_factory=lambda: [("Au", 500.0)])
    substrate: object = "Cu"
    gloss: float = 200.0  # Blinn-Phong exponent of the sun lobe
    highlight_rgb: tuple = (0.04, 0.04, 0.04)  # Dong's RGB specular highlight


@dataclass
class Shape:
    """A mesh with its material: ``surface`` (index into SetSpec.surfaces) or ``film`` (into SetSpec.films).
    ``shadows_ground``: whether it casts sun shadows on the ground plane (grass blades do not: the ground
    texture is the grass canopy seen from above, its own blades' shading already in it)."""

    mesh: TriMesh
    surface: int | None = None
    film: int | None = None
    shadows_ground: bool = True


@dataclass
class Ground:
    """The ground plane y = 0 to the horizon, textured by a wrapping texture that covers ``extent`` metres
    (x, z) per copy; ``offset`` (x, z) shifts the texture (metres)."""

    texture: MipTexture
    extent: tuple = (2.0, 2.0)
    offset: tuple = (0.0, 0.0)


@dataclass
class Atmosphere:
    """Aerial perspective of Dobashi Eq. 3 with the frame's κ_a (per channel) per ``reference_distance``
    metres (the camera-to-cloud distance the cloud frames normalise t_c by)."""

    kappa: np.ndarray
    reference_distance: float


def gradient_sky_default():
    from natscene.composite.sky_dome import gradient_sky
    return gradient_sky([0.25, 0.35, 0.6], [0.55, 0.6, 0.7])


@dataclass
class SetSpec:
    camera: Camera  # in the set's frame
    plate: np.ndarray  # (H, W, 3) linear background (the shot frame) at the camera's resolution
    ground: Ground | None = None
    surfaces: list = field(default_factory=list)
    films: list = field(default_factory=list)
    shapes: list = field(default_factory=list)
    sun_dir: np.ndarray = field(default_factory=lambda: sun_direction(130, 35))
    sun_spd: np.ndarray | None = None  # spectral sun irradiance on the grid (None: D65 * sun_scale)
    sun_scale: float = 3.0
    sky: Callable = field(default_factory=gradient_sky_default)  # radiance toward directions (M, 3) -> (M, 3)
    atmosphere: Atmosphere | None = None
    spp: int = 4
    max_aniso: int = 16
    grid: WavelengthGrid = DEFAULT_GRID
    upsampling: str = "mallett2019"
    angle_step_deg: float = 1.0

    def sun_spectrum(self) -> np.ndarray:
        return (d65(self.grid) * self.sun_scale) if self.sun_spd is None else np.asarray(self.sun_spd, np.float64)


def sun_spectrum_from_rgb(c_in, L_in: float, grid: WavelengthGrid = DEFAULT_GRID, kind: str = "matched") -> np.ndarray:
    """Spectral sun irradiance for the RGB colour c_in and intensity L_in (see the module docstring)."""
    c = np.asarray(c_in, np.float64)
    if kind == "d65":
        return d65(grid) * float(L_in) * float(c @ np.array([0.2126, 0.7152, 0.0722]))
    return sun_spd(c, grid) * float(L_in)
