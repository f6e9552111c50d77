"""
Seasonal pigment concentrations of maple leaves
===============================================

Defines the seasonal pigment concentrations of maple leaves of Dong (2007, §4.3.1-4.3.2, Eqs. 4.3-4.8):

-   :func:`simulate_season`: the daily concentrations of one year (a :class:`Season`) for a :class:`Climate`
    and :class:`SeasonParams`.
-   :func:`normal_climate`, :func:`apply_case`: the normal year and the climate cases of Fig. 4.5.
-   :func:`alpha`: Eq. 4.3.
-   :func:`stage_days`: the days the leaf turns yellow and red.
-   :func:`parse_date`: a date to a day index (:data:`DAYS` a year).

Climate: daily series over one year (day 0 = 1 January) of sunlight I_s (relative flux, 1 = clear
midsummer), temperature (deg C) and precipitation I_p (mm/day). The temperature driver of the alpha
factors is the growing-degree value I_d = max(T - T_base, 0) (a sum of raw deg C is meaningless).

Eq. 4.3   alpha_k(t) = u / A_k * int_0^t I_k dt,  k in {s, d, p}, A_k = annual sum in the normal year.
Eq. 4.4   c_ch(t) = alpha_d alpha_p * g(t),  g' = U_c - U_d (the integral of composition - decomposition);
Eq. 4.6   both are Michaelis-Menten rates U = k X / (K + X) with k = a * I (light flux, §4.3.1):
          composition U_c = a_c I_s * X_T / (K_c + X_T), substrate X_T = max(T - T_stop, 0) (synthesis
          "requires more sunlight and higher temperature ... stops when temperature is low");
          decomposition U_d = a_d I_s * g / (K_d + g) (chlorophyll is consumed in photosynthesis, so
          deficient sunlight retains it, §4.3.2).
Eq. 4.7   c_an(t) = alpha_s alpha_p * int_0^t U_an dt,
Eq. 4.8   U_an / k = 1 / (1 + (X / X_c)^n), X = max(T, 0), n = 5 (switch-off threshold), gated by light
          (I_s) and by the sugar made by photosynthesis (§4.2.2: "only happens when the concentration of
          sugar is quite high, and also requires light"): sugar = int c_ch I_s dt / sugar_scale, <= 1.
Carotene: constant c_ca.
The leaf exists from ``leaf_out`` to ``leaf_fall``; concentrations before leaf-out are 0.
Climate cases (Fig. 4.5): normal; precipitation deficiency (summer rain x ``factor``); warm autumn
(+``delta_T`` deg C from ``start``); sunlight deficiency (sunlight x ``factor`` from ``start``).

References
----------
-   Dong, W. (2007). Rendering Algorithms for Natural Scenes. PhD thesis, Université Henri Poincaré - Nancy I.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from natscene.errors import InputError

__all__ = ["DAYS", "Climate", "normal_climate", "apply_case", "SeasonParams", "Season", "alpha", "simulate_season",
           "stage_days", "parse_date"]

DAYS = 365


@dataclass
class Climate:
    sunlight: np.ndarray      # (365,) relative
    temperature: np.ndarray   # (365,) deg C
    precipitation: np.ndarray  # (365,) mm/day


def normal_climate(t_mean: float = 10.0, t_amp: float = 12.0, t_peak_day: int = 200,
                   sun_mean: float = 0.6, sun_amp: float = 0.35, sun_peak_day: int = 172,
                   precip: float = 2.5, precip_summer: float = 1.0) -> Climate:
    """A mid-latitude normal year: cosine annual cycles of temperature and sunlight, precipitation
    ``precip`` mm/day with an extra ``precip_summer`` mm/day in June-August."""
    d = np.arange(DAYS, dtype=float)
    T = t_mean + t_amp * np.cos(2 * np.pi * (d - t_peak_day) / DAYS)
    S = np.clip(sun_mean + sun_amp * np.cos(2 * np.pi * (d - sun_peak_day) / DAYS), 0.0, None)
    P = np.full(DAYS, precip) + np.where((d >= 152) & (d < 244), precip_summer, 0.0)
    return Climate(S, T, P)


def apply_case(base: Climate, case: dict) -> Climate:
    """A climate case of Fig. 4.5 applied to the normal year: {kind: normal | precipitation_deficiency |
    warm_autumn | sunlight_deficiency, factor, delta_T, start, end}."""
    kind = case.get("kind", "normal")
    d = np.arange(DAYS)
    S, T, P = base.sunlight.copy(), base.temperature.copy(), base.precipitation.copy()
    if kind == "normal":
        pass
    elif kind == "precipitation_deficiency":
        sel = (d >= case.get("start", 121)) & (d < case.get("end", 244))
        P[sel] *= case.get("factor", 0.3)
    elif kind == "warm_autumn":
        sel = d >= case.get("start", 244)
        T[sel] += case.get("delta_T", 4.0)
    elif kind == "sunlight_deficiency":
        sel = d >= case.get("start", 152)
        S[sel] *= case.get("factor", 0.6)
    else:
        raise InputError(f"unknown climate case kind '{kind}'; use normal, precipitation_deficiency, "
                         f"warm_autumn or sunlight_deficiency")
    return Climate(S, T, P)


@dataclass
class SeasonParams:
    """The season model's parameters (config ``leaves.season``; no defaults here: workflow/schemas/leaves.schema.yaml's
    are the only ones, :func:`natscene.config.settings_from_section`)."""

    u: float                  # surrounding-environment weight (Eq. 4.3)
    T_base: float             # growing-degree base (deg C)
    T_stop: float             # chlorophyll synthesis substrate threshold (deg C)
    a_c: float                # composition efficiency (per day per unit light)
    K_c: float                # Michaelis constant of composition (deg C)
    a_d: float                # decomposition efficiency
    K_d: float                # Michaelis constant of decomposition
    k_an: float               # anthocyanin rate constant (Eq. 4.8)
    X_c: float                # half-response temperature (deg C)
    n: int                    # threshold steepness (Dong: n = 5)
    sugar_scale: float        # photosynthate that saturates the sugar gate
    c_ca: float               # constant carotene
    leaf_out: int
    leaf_fall: int
    chl_scale: float          # divides c_ch: the normal-year summer peak becomes ~1

    SCHEMA = (("leaves.schema.yaml", ("season",)),)


@dataclass
class Season:
    chlorophyll: np.ndarray
    carotene: np.ndarray
    anthocyanin: np.ndarray
    alphas: dict = field(default_factory=dict)


def alpha(series: np.ndarray, annual_normal: float, u: float) -> np.ndarray:
    """Eq. 4.3: alpha(t) = u / A * int_0^t I dt (daily cumulative sum)."""
    if annual_normal <= 0:
        raise InputError("climate: the normal year's annual sum of a driver is 0; Eq. 4.3 needs it > 0")
    return u * np.cumsum(series) / annual_normal


def simulate_season(climate: Climate, normal: Climate, p: SeasonParams | None = None) -> Season:
    """Daily c_ch, c_ca, c_an over one year (Eqs. 4.3-4.8); ``p``: the parameters (None: the schema's defaults)."""
    if p is None:
        from natscene.config import default_settings
        p = default_settings(SeasonParams)
    gdd = lambda c: np.maximum(c.temperature - p.T_base, 0.0)
    a_s = alpha(climate.sunlight, normal.sunlight.sum(), p.u)
    a_d = alpha(gdd(climate), gdd(normal).sum(), p.u)
    a_p = alpha(climate.precipitation, normal.precipitation.sum(), p.u)
    S, T = climate.sunlight, climate.temperature
    g = np.zeros(DAYS)
    an_int = np.zeros(DAYS)
    sugar = 0.0
    gi = ai = 0.0
    for d in range(DAYS):  # 365 scalar steps: the ODE is sequential in time (not a pixel loop)
        if p.leaf_out <= d < p.leaf_fall:
            xt = max(T[d] - p.T_stop, 0.0)
            uc = p.a_c * S[d] * xt / (p.K_c + xt)
            ud = p.a_d * S[d] * gi / (p.K_d + gi)
            gi = max(gi + uc - ud, 0.0)
            sugar += gi * S[d]
            x = max(T[d], 0.0)
            u_an = p.k_an * S[d] * min(sugar / p.sugar_scale, 1.0) / (1.0 + (x / p.X_c) ** p.n)
            ai += u_an
        elif d >= p.leaf_fall:
            gi = ai = 0.0
        g[d], an_int[d] = gi, ai
    ch = a_d * a_p * g / p.chl_scale
    an = a_s * a_p * an_int
    alive = (np.arange(DAYS) >= p.leaf_out) & (np.arange(DAYS) < p.leaf_fall)
    ca = np.where(alive, p.c_ca, 0.0)
    return Season(ch, ca, an, {"s": a_s, "d": a_d, "p": a_p})


def stage_days(season: Season, yellow_ratio: float = 1.0, red_level: float = 0.5) -> dict:
    """Transition days after midsummer: 'yellow' = first day c_ca >= yellow_ratio * c_ch (carotene shows),
    'red' = first day c_an >= red_level * max(normal-scale 1) (anthocyanin dominates)."""
    d = np.arange(DAYS)
    after = d >= max(182, int(np.argmax(season.chlorophyll)))
    yel = np.flatnonzero(after & (season.carotene > 0) & (season.carotene >= yellow_ratio * season.chlorophyll))
    red = np.flatnonzero(after & (season.anthocyanin >= red_level))
    return {"yellow": int(yel[0]) if yel.size else None, "red": int(red[0]) if red.size else None}


def parse_date(s) -> int:
    """'MM-DD' (non-leap year) or a day-of-year int -> day index 0..364."""
    if isinstance(s, int):
        return int(s) % DAYS
    import datetime

    try:
        return datetime.date(2001, int(str(s)[:2]), int(str(s)[3:5])).timetuple().tm_yday - 1
    except (ValueError, IndexError):
        raise InputError(f"leaf date '{s}' is not MM-DD (e.g. 09-15)") from None
