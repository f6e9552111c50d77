"""
Ground tiles
============

Ground tiles: GA-optimised ω-tile sets and real-time scan-line tiling (Dong 2007, Ch. 5; Ng et al. 2005).

- :mod:`.omega`: tile sets B, N1, N2 (and N3, N4) and the completability check (§5.3);
- :mod:`.scanline`: seeded scan-line tiling and the vectorised atlas gather;
- :mod:`.tile_ga`: the ω-tile GA, sample-patch selection (§5.4.2, Eqs. 5.1-5.6);
- :mod:`.graphcut`: junction removal with a graph-cut seam constrained to a circle (§5.2);
- :mod:`.blend`: Poisson blending of a merged tile across its seams;
- :mod:`.construct`: the whole tile-set construction (§5.4.3);
- :mod:`.embed`: meaning embedment (§5.6).

The package exports nothing itself: import the module that holds what you need.

References
----------
-   Dong, W. (2007). Rendering algorithms for natural scenes. PhD thesis, Université Henri Poincaré – Nancy 1.
-   Ng, T.-Y., Wen, C., Tan, T.-S., Zhang, X., & Kim, Y. J. (2005). Generating an ω-tile set for texture
    synthesis. Proceedings of Computer Graphics International 2005 (CGI'05), 177–184.
"""

__all__: list[str] = []
