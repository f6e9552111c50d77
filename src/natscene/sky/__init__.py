"""Sky extraction from a cloud photograph (Dobashi et al. 2012 §4.1).

- :mod:`natscene.sky.segmentation`: cloud / sky / neither classification by chroma (Dobashi 2010 as
  summarised in §4.1), optional hand-painted mask, morphology, soft cloud alpha;
- :mod:`natscene.sky.laplace`: the sky behind the clouds, ∇²L_sky = 0 with the sky as Dirichlet boundary
  (Pérez et al. 2003), exact sparse direct solve;
- :mod:`natscene.sky.sun_colour`: the colour of the light incident on the clouds c_in (Otsu split of the
  cloud pixels' grey levels, mean colour of the brighter class);
- :mod:`natscene.sky.resample`: area-averaged products at the fit resolutions;
- :mod:`natscene.sky.extract`: the whole stage on one photo.
"""
from natscene.sky.extract import SkyResult, SkySettings, extract_sky

__all__ = ["SkyResult", "SkySettings", "extract_sky"]
