"""Seasonal maple leaf colour (Dong 2007 Ch. 4): climate-driven pigment concentrations (Eqs. 4.3-4.8),
PROSPECT-D leaf optics and per-date leaf textures (§4.3.3)."""
