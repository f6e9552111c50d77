"""Scattering precompute, image composition and the forward renderer (Dobashi 2012 §4.3, Eqs. 3–9), with the
all-orders transport beyond the paper.

- :mod:`.medium`: density texture + sun optical-depth volume (Dr.Jit / Mitsuba);
- :mod:`.single`: ray-marched S_sun, S_amb, T (Eqs. 5, 9);
- :mod:`.multiple`: per-order path tracing with NEE to the sun, all g from the same paths (Eqs. 6–8; the
  Dobashi transport);
- :mod:`.majorant`, :mod:`.photons`, :mod:`.inscatter`, :mod:`.bands`, :mod:`.skylight`,
  :mod:`.allorders`: the all-orders transport (photon tracing of the sun's light and the skylight into an
  in-scatter cache, order bands with a closed-form albedo dependence, the sky dome);
- :mod:`.tables`: the precomputed tables (Tables, precompute, save_tables, load_tables);
- :mod:`.compose`: compose_cloud / apply_atmosphere / compose over a GA population (Eqs. 3, 4, 8, 9);
- :mod:`.render`: the same model evaluated directly at any view, sun and resolution;
- :mod:`.mitsuba_scene`: the independent Mitsuba ``volpath`` reference scene.

The package exports nothing itself: import the module that holds what you need.
"""
