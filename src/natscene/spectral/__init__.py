"""
Spectral colour
===============

Spectral colour (Dong 2007, Ch. 2 and §1.1.6):

- :mod:`.grid`: the wavelength grid, CIE tables on it and spectrum -> XYZ -> linear sRGB (§2.4);
- :mod:`.upsampling`: RGB -> spectrum upsampling (§2.3.1, §2.4);
- :mod:`.illuminants`: illuminant SPDs (D65, CIE daylight, a sun matched to a fitted c_in);
- :mod:`.indices`: measured complex refractive indices of metals;
- :mod:`.thin_film`: multilayer thin-film reflectance and transmittance (§1.1.6, Eqs. 1.14-1.25).

The package exports nothing itself: import the module that holds what you need.

References
----------
-   Dong, W. (2007). Rendering algorithms for natural scenes. PhD thesis, Université Henri Poincaré – Nancy 1.
"""

__all__: list[str] = []
