"""Settings of the keyframe fit (config section ``fit``; Dobashi 2012 §4.2 and §5): one dataclass per object of
``workflow/schemas/fit.schema.yaml``, whose defaults are the schema's (``tests/test_settings.py`` checks every
pair), read from a validated section by :func:`natscene.config.settings_from_section`."""
from __future__ import annotations

from dataclasses import dataclass, field, replace

from natscene.config import settings_from_section


@dataclass(frozen=True)
class KappaGridSettings:
    """The kappa_a values the line search tries per channel (Fig. 3; :func:`natscene.fit.kappa.kappa_grid`): ``fit.kappa``."""

    min: float = 0.0
    max: float = 1.0
    step: float = 0.1


@dataclass(frozen=True)
class GradientSettings:
    """The §5.1 finite-difference steepest-descent baseline (``fit.method: gradient``): ``fit.gradient``."""

    h: float = 0.01
    alpha0: float = 0.25
    n_alpha: int = 10
    max_iter: int = 100


@dataclass(frozen=True)
class FitSettings:
    """The GA of §4.2 (population, bits, rates, scaling, the stop rule of epsilon_O, n_suc, n_max), the
    objective (Eq. 2's levels and metric), the search ranges and the skylight of the all-orders transport."""

    CONFIG_NAMES = {"epsilon_O": "epsilon_o"}

    method: str = "ga"
    population: int = 20
    bits: int = 32
    crossover_rate: float = 0.8
    mutation_rate: float = 0.02
    scaling: str = "linear"
    ranges: dict = field(default_factory=dict)      # parameter -> [min, max]; missing: genetic.DEFAULT_RANGES
    skylight: bool = True
    ground_albedo: float = 0.2
    kappa: KappaGridSettings = field(default_factory=KappaGridSettings)
    epsilon_o: float = 0.5
    n_suc: int = 20
    n_max: int = 100
    n_levels: int = 256
    encoding: str = "srgb"
    metric: str = "difference"
    top_k: int = 10
    distinct_tol: float = 0.01
    gradient: GradientSettings = field(default_factory=GradientSettings)
    contact_columns: int = 4


def fit_settings(section: dict | None) -> FitSettings:
    """:class:`FitSettings` of a validated ``fit`` section (its ``kappa`` and ``gradient`` objects included);
    an unknown key raises ConfigError naming ``fit.<key>``."""
    s = dict(section or {})
    kappa = settings_from_section(KappaGridSettings, s.pop("kappa", None), "fit.kappa")
    gradient = settings_from_section(GradientSettings, s.pop("gradient", None), "fit.gradient")
    return replace(settings_from_section(FitSettings, s, "fit"), kappa=kappa, gradient=gradient)
