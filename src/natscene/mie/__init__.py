"""Mie cloud shading (Reimschuessel 2011): Mie phase tables, point-to-point scattering with a per-point
Mie/isotropic ratio, final ray marching."""
