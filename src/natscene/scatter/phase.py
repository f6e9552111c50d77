"""
Phase function of the cloud transport
=====================================

Re-exports the Henyey–Greenstein phase function of :mod:`natscene.phase` (its one home) under the names the
scatter package imports from here:

-   :data:`INV_4PI`, :func:`hg`, :func:`hg_dr`, :func:`hg_p1_dr`, :func:`hg_sample_cos`, :func:`hg_sample_cos_dr`: see
    :mod:`natscene.phase`.
"""
from natscene.phase import INV_4PI, hg, hg_dr, hg_p1_dr, hg_sample_cos, hg_sample_cos_dr

__all__ = ["INV_4PI", "hg", "hg_dr", "hg_p1_dr", "hg_sample_cos", "hg_sample_cos_dr"]
