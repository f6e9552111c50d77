"""
Sky
===

The sky: extracted from a cloud photograph (Dobashi et al. 2012, §4.1), or the analytic daylight sky.

- :mod:`natscene.sky.segmentation`: cloud / sky / neither classification by chroma (Dobashi 2010 as
  summarised in §4.1), optional hand-painted mask, morphology, soft cloud alpha;
- :mod:`natscene.sky.laplace`: the sky behind the clouds L_sky, ∇²L_sky = 0 with the sky as Dirichlet boundary
  (Pérez et al. 2003), solved exactly by multigrid-preconditioned CG (:mod:`natscene.sky.multigrid`, the
  default) or a sparse direct factorisation;
- :mod:`natscene.sky.sun_colour`: the colour of the light incident on the clouds c_in (Otsu split of the
  cloud pixels' grey levels, mean colour of the brighter class);
- :mod:`natscene.sky.plausibility`: the checks that refuse a photo that is not a cloud photo;
- :mod:`natscene.sky.resample`: area-averaged products at the fit resolutions;
- :mod:`natscene.sky.extract`: the whole stage on one photo;
- :mod:`natscene.sky.daylight`: the Preetham et al. (1999) daylight sky and a shot's sky (the sky behind shot
  frames, the dome that lights the clouds and the composite's set).

The package imports none of its modules: ``natscene.sky.daylight`` (used by the cloud renderer) loads without
the photo stage's image libraries.

References
----------
-   Dobashi, Y., Shinzo, Y., & Yamamoto, T. (2010). Modeling of clouds from a single photograph. Computer
    Graphics Forum, 29(7), 2083–2090.
-   Dobashi, Y., Iwasaki, W., Ono, A., Yamamoto, T., Yue, Y., & Nishita, T. (2012). An inverse problem approach
    for automatically adjusting the parameters for rendering clouds using photographs. ACM Transactions on
    Graphics, 31(6).
-   Otsu, N. (1979). A threshold selection method from gray-level histograms. IEEE Transactions on Systems, Man,
    and Cybernetics, 9(1), 62–66.
-   Pérez, P., Gangnet, M., & Blake, A. (2003). Poisson image editing. ACM Transactions on Graphics, 22(3),
    313–318.
-   Preetham, A. J., Shirley, P., & Smits, B. (1999). A practical analytic model for daylight. Proceedings of
    ACM SIGGRAPH 1999, 91–100.
"""

__all__: list[str] = []
