"""Mie demo (Reimschuessel 2011 + the issue's Done-when) on the FULL render (multiple scattering, ambient
and sky included): a thin deck of narrow droplets shows the first glory ring where Mie theory puts it,
which the same render with Henyey-Greenstein lacks; toward a sun hidden just behind a cloud edge the Mie
forward peak makes a rim many times brighter than HG's."""
import numpy as np
import pytest

from natscene.geometry import sun_direction
from natscene.mie.cameras import deck_camera, deck_top, silver_lining_camera
from natscene.mie.march import render_mie
from natscene.mie.measure import angular_profile, rim_peak, ring_contrast
from natscene.mie.phase import compute_mie_table, glory_ring_deg, hg_table
from natscene.mie.points import generate_points, sample_density
from natscene.mie.solver import solve
from natscene.volume.build import build_volume
from helpers import sphere_volume

SUN = sun_direction(130, 35)
PARAMS = {"L_in": 6.0, "L_amb": 0.05, "sky_color": [0.06, 0.12, 0.32], "c_in": [1.0, 0.96, 0.9]}


def _pair(vol, table, passes=3):
    pts = generate_points(vol, SUN, sigma_t=0.3, spacing_voxels=2.0)
    hg = hg_table(float(table.g[1]))
    return (table, solve(pts, table, passes)), (hg, solve(pts, hg, passes))


def _render(vol, cam, pair):
    sky = np.broadcast_to(np.float32(PARAMS["sky_color"]), (cam.height, cam.width, 3))
    return [render_mie(vol, cam, SUN, sol, tab, PARAMS, sky) for tab, sol in pair]


# the demo deck in small: a broken stratocumulus volume 800 m wide at the box floor, its extinction scale set
# for a mean vertical optical depth of 3 at the solver's sigma_t = 0.3 (reference_axis y), as in the configs
DECK = {"kind": "stratocumulus", "resolution": [96, 20, 96], "size": 800.0, "altitude": 0.0, "coverage": 0.95,
        "thickness": 0.7, "cells": 3, "relief": 0.35, "billow": 0.5, "erosion": 0.3, "interior": 0.2, "seed": 2,
        "reference_axis": "y", "reference_optical_depth": 10.0}


def _deck(**kw):
    return build_volume({**DECK, **kw}, "deck")[0]


def test_deck_is_thin_broken_and_optically_moderate():
    deck = _deck()
    tau = deck.density.sum(axis=1) * float(deck.voxel_size[1]) * 0.3 * deck.extinction_scale   # (z, x)
    assert tau[tau > 0].mean() == pytest.approx(3.0, rel=1e-4)          # mean vertical optical depth 3
    assert 1.0 < np.median(tau[tau > 0]) < 6.0                           # optically moderate where cloudy
    assert 0.02 < (tau < 0.3).mean() < 0.5                              # broken: some clear lanes
    assert tau.std() > 0.2 * tau.mean()                                  # textured, not a uniform slab
    # thin and wide: a layer a few tenths of its box's height, hundreds of metres, under a km-wide box
    rows = np.nonzero(deck.density.max(axis=(0, 2)) > 0.05)[0]
    thick_m = (rows.max() - rows.min() + 1) * float(deck.voxel_size[1])
    assert 50 < thick_m < 400 and deck.bbox_max[0] - deck.bbox_min[0] == pytest.approx(800.0)
    assert deck.bbox_min[1] < deck_top(deck) < deck.bbox_max[1]
    assert np.allclose(deck.voxel_size, deck.voxel_size[0])              # cubic voxels (the marcher's)


def test_glory_ring_in_the_full_render_of_a_thin_narrow_droplet_deck():
    table = compute_mie_table(8.0, 0.02, n_radii=40, spectral_nm=())
    ring = 180.0 - glory_ring_deg(table)[1]                              # ≈ 1.9° from the antisolar point
    deck = _deck()
    pair = _pair(deck, table)
    cam = deck_camera("glory", deck, SUN, distance=800.0, fov=8.0, resolution=(96, 96))
    mie, hg = _render(deck, cam, pair)
    ang_m, con_m = ring_contrast(*angular_profile(mie, cam, -SUN, 3.5, 0.1))
    ang_h, con_h = ring_contrast(*angular_profile(hg, cam, -SUN, 3.5, 0.1))
    assert ang_m == pytest.approx(ring, abs=0.5)
    assert con_m > 1.15                     # measured ≈ 1.29 on the main job's deck
    assert con_h < 1.05                     # HG: monotone up to noise


def test_glory_washes_out_with_broad_droplet_spectrum():
    # the same deck with v_eff = 0.1 (cumulus): the ring contrast collapses (Laven 2005)
    narrow = compute_mie_table(8.0, 0.02, n_radii=40, spectral_nm=())
    broad = compute_mie_table(8.0, 0.1, n_radii=40, spectral_nm=())
    deck = _deck()
    cam = deck_camera("glory", deck, SUN, distance=800.0, fov=8.0, resolution=(96, 96))
    con = []
    for t in (narrow, broad):
        pts = generate_points(deck, SUN, sigma_t=0.3, spacing_voxels=2.0)
        img = render_mie(deck, cam, SUN, solve(pts, t, 3), t, PARAMS)
        con.append(ring_contrast(*angular_profile(img, cam, -SUN, 3.5, 0.1))[1])
    assert con[1] < con[0] - 0.05


def test_silver_lining_rim_mie_over_hg():
    vol = sphere_volume(n=48)
    table = compute_mie_table(10.0, 0.1, n_radii=40, spectral_nm=())
    pair = _pair(vol, table)
    sigma_e = pair[0][1].points.sigma_e
    cam = silver_lining_camera(vol, SUN, sigma_e, distance=2.0, fov=6.0, resolution=(64, 48), edge_deg=1.0,
                               hide_tau=4.0)
    # the camera looks straight at the sun, which the sphere hides
    fwd = np.subtract(cam.look_at, cam.position)
    assert np.allclose(fwd / np.linalg.norm(fwd), SUN)
    ts = np.linspace(0, 4, 2001)
    tau = sample_density(vol, np.asarray(cam.position) + ts[:, None] * SUN).sum() * (ts[1] - ts[0]) * sigma_e
    assert tau >= 4.0 * 0.95              # (map pixels of 1.5 voxels)
    mie, hg = _render(vol, cam, pair)
    ratio = rim_peak(mie) / rim_peak(hg)
    assert ratio > 5.0, ratio              # measured ≈ 12 on the main job's cumulonimbus
