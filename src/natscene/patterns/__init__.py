"""Flower pigment pattern maps (Dong 2007 Ch. 3): venation (§3.3.1), venation-aware reaction-diffusion
(§3.3.2, Eqs. 3.1-3.5), pigment spectra, flower colour expression (§3.4, Eqs. 3.6-3.10) and YIQ
recolouring of a photograph (§3.5).

Modules: ``venation`` (petal shape and vein tree, §3.3.1), ``reaction_diffusion`` (the package of the
venation-aware reaction-diffusion, §3.3.2), ``presets`` (a pattern job from its config entry, the Table 3.3
presets), ``shape`` (shape descriptors of a map, to check the Fig. 3.3 patterns), ``pigments`` (pigment absorption
spectra), ``expression`` (flower colour expression, §3.4), ``recolour`` (recolouring a photograph, §3.5).
"""

__all__: list[str] = []  # a map of the package; import the module you need
