"""The final shot (Dong 2007 Ch. 2): a meadow in front of a shot's cloud frames, shaded with the hybrid RGB +
spectral rule. One concept per module: ``set_spec`` (what the set holds), ``inputs`` (config -> set),
``meadow`` / ``placement`` (where things go), ``flower``, ``maple``, ``beetle``, ``grass``, ``mesh`` (geometry),
``files`` (the files a frame reads), ``texture`` / ``footprint`` (filtered texturing), ``sky_dome`` (sky radiance and irradiance), ``tracer`` (ray
casting), ``vectors`` (Dr.Jit vector helpers), ``set_geometry`` (the rays every mode shares), ``renderer`` (hybrid
shading), ``full_spectral`` (the reference), ``hybrid`` (the intermediate image)."""

__all__: list[str] = []  # a map of the package; import the module you need
