"""Seasonal leaf colour (Dong 2007 Ch. 4): the directions of Fig. 4.5."""
import numpy as np

from natscene.leaves.optics import leaf_rgb
from natscene.leaves.season import apply_case, normal_climate, parse_date, simulate_season, stage_days

N = normal_climate()


def run(kind, **kw):
    return simulate_season(apply_case(N, {"kind": kind, **kw}), N)


def test_chlorophyll_falls_and_anthocyanin_rises_in_autumn():
    s = run("normal")
    aug, nov = parse_date("08-15"), parse_date("11-01")
    assert s.chlorophyll[nov] < 0.3 * s.chlorophyll[aug]
    assert s.anthocyanin[nov] > 3 * s.anthocyanin[aug]
    assert np.allclose(s.carotene[aug:nov], s.carotene[aug])  # constant carotene


def test_warm_autumn_delays_red():
    a, b = stage_days(run("normal")), stage_days(run("warm_autumn", delta_T=4.0))
    assert b["red"] is None or b["red"] > a["red"]


def test_dry_summer_brings_yellow_earlier():
    a, b = stage_days(run("normal")), stage_days(run("precipitation_deficiency", factor=0.3))
    assert b["yellow"] < a["yellow"]


def test_dim_autumn_retains_chlorophyll():
    a, b = run("normal"), run("sunlight_deficiency", factor=0.6)
    d = parse_date("10-20")
    assert b.chlorophyll[d] > a.chlorophyll[d]


def test_anthocyanin_threshold_response():
    # Eq. 4.8 with n = 5: a warm spell (T >> X_c) switches synthesis off
    s_cold = run("normal")
    s_warm = run("warm_autumn", delta_T=10.0)
    assert s_warm.anthocyanin[parse_date("10-15")] < 0.5 * s_cold.anthocyanin[parse_date("10-15")]


def test_leaf_colour_green_to_red():
    green = leaf_rgb(1.0, 0.35, 0.0)
    red = leaf_rgb(0.0, 0.35, 1.0)
    yellow = leaf_rgb(0.0, 0.35, 0.0)
    assert green[1] > green[0] and green[1] > green[2]
    assert red[0] > 1.5 * red[1]
    assert yellow[0] > yellow[2] and yellow[1] > yellow[2]
