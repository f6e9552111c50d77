"""Mie cloud shading (Reimschuessel 2011): Mie phase tables, point-to-point scattering with a per-point
Mie/isotropic ratio, final ray marching.

Modules: ``phase`` (the Mie phase tables, Fig. 3), ``points`` (the point cloud marched from the sun, Table 1),
``solver`` (the scattering passes and the ratio R_i, Eqs. 1–5), ``march`` (the final ray marching, Eqs. 6–8),
``ratio_slice`` (the picture of R_i, Fig. 8), ``cameras`` (the effect shots' cameras), ``measure`` (the effects
measured on images), ``reference`` (the Mitsuba 3 reference).
"""

__all__: list[str] = []  # a map of the package; import the module you need
