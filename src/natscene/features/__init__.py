"""Feature-aware texture analysis and synthesis (Dong 2007, Ch. 6).

A perspective or otherwise non-isotropic texture photo is described by feature maps: the texel scale (§6.3,
:mod:`natscene.features.scale`), the texel type (§6.4, :mod:`natscene.features.type_map`) and the global colour
(§6.5, :mod:`natscene.features.colour`). Texture optimisation with the control energy of Eq. 6.3
(:mod:`natscene.features.optimisation`) synthesises a texture whose feature maps follow a target: the input's
maps resampled to the output (feature-preserved, §6.6.1) or the user's (§6.6.2, e.g. a constant scale that makes
a perspective photo isotropic); :mod:`natscene.features.quilting` does the same by feature-preserved
hierarchical quilting (§6.6.1), the faster method; :mod:`natscene.features.completion` fills a hole of a textured
photo (§6.7). :mod:`natscene.features.maps` makes an entry's feature maps and :mod:`natscene.features.entry` runs
one ``textures.<name>`` entry from photo to synthesis.
"""

__all__: list[str] = []  # a map of the package; import the module you need
