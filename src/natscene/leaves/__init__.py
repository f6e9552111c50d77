"""Seasonal maple leaf colour (Dong 2007 Ch. 4): climate-driven pigment concentrations (Eqs. 4.3-4.8),
PROSPECT-D leaf optics and per-date leaf textures (§4.3.3).

Modules: ``season`` (the pigment concentrations over a year, Eqs. 4.3-4.8), ``optics`` (leaf colour from the
concentrations), ``texture`` (the maple leaf's shape, veins and per-date texture).
"""

__all__: list[str] = []  # a map of the package; import the module you need
