"""Ground tiles: GA-optimised ω-tile sets and real-time scan-line tiling (Dong 2007 Ch. 5; Ng et al. 2005).

Modules: ``omega`` (tile sets B, N1, N2 and the completability check, §5.3), ``scanline`` (seeded
scan-line tiling and the vectorised atlas gather), ``tile_ga`` (the ω-tile GA: sample-patch selection, §5.4.2,
Eqs. 5.1-5.6), ``graphcut`` (junction removal with a seam constrained to a circle, §5.2), ``construct``
(the whole tile-set construction), ``embed`` (meaning embedment, §5.6).
"""
