"""The Henyey–Greenstein phase function of the cloud transport: :mod:`natscene.phase` (its one home), under the
names the scatter package has always imported from here."""
from natscene.phase import INV_4PI, hg, hg_dr, hg_sample_cos_dr

__all__ = ["INV_4PI", "hg", "hg_dr", "hg_sample_cos_dr"]
