"""
Settings of the keyframe fit
============================

Defines the settings of config section ``fit`` (Dobashi et al. 2012, §4.2 and §5): one dataclass per object of
``workflow/schemas/fit.schema.yaml``, whose defaults are the schema's (``tests/test_settings.py`` checks every
pair), read from a validated section by :func:`natscene.config.settings_from_section`.

-   :func:`fit_settings`: the section as a :class:`FitSettings`.
-   :class:`FitSettings`, :class:`KappaGridSettings`, :class:`GradientSettings`: the section and its objects.
-   :func:`extinction_range_problem`, :func:`check_extinction_range`: ``fit.ranges.extinction`` against the
    physical range and the precomputed extinction grid (also checked before any job: light to import).

References
----------
-   Dobashi, Y., Iwasaki, W., Ono, A., Yamamoto, T., Yue, Y., & Nishita, T. (2012). An inverse problem approach
    for automatically adjusting the parameters for rendering clouds using photographs. ACM Transactions on
    Graphics, 31(6).
"""
from __future__ import annotations

from dataclasses import dataclass

from natscene.config import settings_from_section
from natscene.errors import InputError

__all__ = ["KappaGridSettings", "GradientSettings", "FitSettings", "fit_settings", "extinction_range_problem",
           "check_extinction_range"]


@dataclass(frozen=True)
class KappaGridSettings:
    """The kappa_a values the line search tries per channel (Fig. 3; :func:`natscene.fit.kappa.kappa_grid`): ``fit.kappa``."""

    min: float
    max: float
    step: float

    SCHEMA = (("fit.schema.yaml", ("kappa",)),)


@dataclass(frozen=True)
class GradientSettings:
    """The §5.1 finite-difference steepest-descent baseline (``fit.method: gradient``): ``fit.gradient``."""

    h: float
    alpha0: float
    n_alpha: int
    max_iter: int

    SCHEMA = (("fit.schema.yaml", ("gradient",)),)


@dataclass(frozen=True)
class FitSettings:
    """The GA of §4.2 (population, bits, rates, scaling, the stop rule of epsilon_O, n_suc, n_max), the
    objective (Eq. 2's levels and metric), the search ranges and the skylight of the all-orders transport. No
    field has a default here: the schema's are the only ones (:func:`fit_settings`)."""

    CONFIG_NAMES = {"epsilon_O": "epsilon_o"}
    SCHEMA = (("fit.schema.yaml", ()),)

    method: str
    population: int
    bits: int
    crossover_rate: float
    mutation_rate: float
    scaling: str
    ranges: dict                    # parameter -> [min, max] (the schema fills every parameter in)
    skylight: bool
    ground_albedo: float
    kappa: KappaGridSettings
    epsilon_o: float
    n_suc: int
    n_max: int
    n_levels: int
    encoding: str
    metric: str
    top_k: int
    distinct_tol: float
    gradient: GradientSettings
    contact_columns: int


def fit_settings(section: dict | None) -> FitSettings:
    """:class:`FitSettings` of a validated ``fit`` section (its ``kappa`` and ``gradient`` objects included; a
    part of one or None: each key it lacks the schema's default); an unknown key raises ConfigError naming
    ``fit.<key>``."""
    s = dict(section or {})
    kappa = settings_from_section(KappaGridSettings, s.pop("kappa", None), "fit.kappa")
    gradient = settings_from_section(GradientSettings, s.pop("gradient", None), "fit.gradient")
    return settings_from_section(FitSettings, {**s, "kappa": kappa, "gradient": gradient}, "fit")


def extinction_range_problem(fit_range, grid) -> str | None:
    """What is wrong with ``fit.ranges.extinction`` (1/m, searched on a log scale), or None: it must lie inside the
    physical range (:data:`natscene.scatter.tables.EXTINCTION_RANGE`) and inside the precompute's extinction
    grid."""
    from natscene.scatter.tables import EXTINCTION_RANGE
    lo, hi = (float(x) for x in fit_range)
    plo, phi = EXTINCTION_RANGE
    if not plo <= lo <= hi <= phi:
        return (f"[{lo:g}, {hi:g}] /m must lie in the physical range [{plo:g}, {phi:g}] /m (haze ~0.002, cumulus "
                f"0.02-0.15, a storm core ~0.3) with min <= max")
    glo, ghi = float(min(grid)), float(max(grid))
    if lo < glo or hi > ghi:
        return (f"[{lo:g}, {hi:g}] /m is not covered by the precompute's nodes (config key 'precompute.extinction': "
                f"[{glo:g}, {ghi:g}] /m); add nodes or narrow the range")
    return None


def check_extinction_range(fit_range, grid) -> None:
    """:func:`extinction_range_problem` as an InputError naming ``fit.ranges.extinction``."""
    why = extinction_range_problem(fit_range, grid)
    if why:
        raise InputError(f"config key 'fit.ranges.extinction': {why}")
