"""
Scattering
==========

Scattering precompute, image composition and the forward renderer (Dobashi et al. 2012, §4.3, Eqs. 3–9), with
the all-orders transport beyond the paper (its §7):

- :mod:`.medium`: density texture + sun optical-depth volume (Dr.Jit / Mitsuba);
- :mod:`.rays`: camera rays on the Dr.Jit side;
- :mod:`.phase`: the Henyey–Greenstein phase function (from :mod:`natscene.phase`);
- :mod:`.single`: ray-marched S_sun, S_amb, T (Eqs. 5, 9);
- :mod:`.multiple`: per-order path tracing with NEE to the sun, all g from the same paths (Eqs. 6–8; the
  Dobashi transport);
- :mod:`.majorant`, :mod:`.photons`, :mod:`.importance`, :mod:`.inscatter`, :mod:`.bands`, :mod:`.skylight`,
  :mod:`.allorders`: the all-orders transport (photon tracing of the sun's light and the skylight, with weight
  windows, into an in-scatter cache, order bands with a closed-form albedo dependence, the sky dome);
- :mod:`.transport`: the transport models behind one interface (``all_orders``, ``dobashi``);
- :mod:`.params`: the parameter sets (Table 1), one or a GA population;
- :mod:`.nodes`: interpolation on the tables' extinction and g nodes;
- :mod:`.tables`: the precomputed tables (Tables, precompute, save_tables, load_tables);
- :mod:`.contact`: the tables' contact sheet;
- :mod:`.compose`: compose_cloud / apply_atmosphere / compose over a GA population (Eqs. 3, 4, 8, 9);
- :mod:`.render`: the same model evaluated directly at any view, sun and resolution;
- :mod:`.mitsuba_scene`: the independent Mitsuba ``volpath`` reference scene;
- :mod:`.reference_scene`: the scenes of the stored ``volpath`` references.

The package exports nothing itself: import the module that holds what you need.

References
----------
-   Dobashi, Y., Iwasaki, W., Ono, A., Yamamoto, T., Yue, Y., & Nishita, T. (2012). An inverse problem approach
    for automatically adjusting the parameters for rendering clouds using photographs. ACM Transactions on
    Graphics, 31(6).
"""

__all__: list[str] = []
