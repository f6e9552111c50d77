"""Mie cloud shading (Reimschuessel 2011): the phase table against Mie theory, the point-to-point passes
(Fig. 8 behaviour of R_i, energy), the final marcher (Beer-Lambert transmittance, reuse)."""
import numpy as np
import pytest

from natscene.errors import InputError
from natscene.geometry import Camera
from natscene.mie.march import render_mie
from natscene.mie.phase import (compute_mie_table, fogbow_peak_deg, glory_ring_deg, hg_table, read_table,
                                sphere_integral, write_table)
from natscene.mie.points import generate_points
from natscene.mie.solver import load_solution, save_solution, solve
from natscene.volume.grid import Volume
from helpers import sphere_volume


@pytest.fixture(scope="module")
def table():
    return compute_mie_table(r_eff_um=10.0, v_eff=0.1, n_radii=80, spectral_nm=(450, 650))


@pytest.fixture(scope="module")
def sphere_solution(table):
    vol = sphere_volume()
    sun = np.array([1.0, 0.0, 0.0])
    pts = generate_points(vol, sun, sigma_t=0.3, spacing_voxels=1.5)
    sol, hist = solve(pts, table, passes=6, keep_history=True)
    return vol, sun, pts, sol, hist


# ------------------------------------------------------------------------------------- phase table
def test_table_normalised_over_the_sphere(table):
    # independent quadrature: Simpson in theta with the sin(theta) Jacobian on a resampled uniform grid
    from scipy.integrate import simpson
    th = np.linspace(0, np.pi, 200001)
    for c in range(3):
        p = np.interp(th, table.theta, table.rgb[:, c])
        assert 2 * np.pi * simpson(p * np.sin(th), x=th) == pytest.approx(1.0, abs=2e-3)
    assert np.allclose(sphere_integral(table.theta, table.spectral), 1.0, atol=1e-9)


def test_asymmetry_of_cumulus_droplets(table):
    # r_eff = 10 µm water droplets in the visible: g ≈ 0.85-0.87 (Hansen & Travis 1974)
    assert np.all((table.g > 0.84) & (table.g < 0.88))


def test_population_g_matches_miepython_efficiencies():
    # g of the tabulated (angle-resolved) phase function equals the C_sca-weighted mean of miepython's
    # per-sphere asymmetry parameters over the same gamma population (a different code path: no angles)
    import miepython
    from natscene.mie.phase import (asymmetry, gamma_size_distribution, mie_phase_polydisperse, radius_grid,
                                    water_index)
    th = np.radians(np.linspace(0, 180, 20001))
    p = mie_phase_polydisperse(550.0, th, r_eff_um=2.0, v_eff=0.1, n_radii=300)
    m = complex(water_index(550.0))
    r = radius_grid(2.0, 0.1, 300)
    eff = np.array([miepython.efficiencies_mx(m, 2 * np.pi * rk / 0.55) for rk in r])
    w = gamma_size_distribution(r, 2.0, 0.1) * np.pi * r**2 * eff[:, 1]
    g_ref = np.sum(w * eff[:, 3]) / np.sum(w)
    assert asymmetry(th, p)[0] == pytest.approx(g_ref, abs=3e-3)


def test_fogbow_and_glory_positions_and_colour_order(table):
    fog = fogbow_peak_deg(table)
    assert np.all((fog >= 138.0) & (fog <= 143.0)), fog
    # geometric optics: red bows at smaller scattering angle (outside the bow) than blue
    assert fog[0] < fog[2]
    # glory: maximum at 180° and the first ring's angular radius grows with wavelength (red outside)
    d = table.theta_deg
    back = d > 175
    assert np.all(np.argmax(table.rgb[back], axis=0) == np.argmax(d[back]))
    ring = glory_ring_deg(table)
    assert ring[0] < ring[1] < ring[2] < 179.7
    # diffraction peak: forward scattering is hundreds of times the isotropic value
    assert np.all(table.rgb[0] > 100 / (4 * np.pi))


def test_table_round_trip_and_hg(tmp_path, table):
    write_table(tmp_path / "t.exr", table)
    back = read_table(tmp_path / "t.exr")
    assert np.allclose(back.rgb, table.rgb, rtol=1e-5)
    assert np.allclose(back.wavelengths_nm, [450, 650])
    hg = hg_table(0.85)
    assert hg.g[1] == pytest.approx(0.85, abs=2e-3)
    hg_analytic = (1 - 0.85 ** 2) / (4 * np.pi * (1 + 0.85 ** 2 - 2 * 0.85 * 0.3) ** 1.5)  # HG at cos = 0.3
    assert np.allclose(hg.evaluate(0.3)[1], hg_analytic, rtol=1e-3)


# ----------------------------------------------------------------------------------------- solver
def test_points_from_the_sun_follow_beer_lambert():
    vol = sphere_volume()
    sun = np.array([0.0, 1.0, 0.0])
    pts = generate_points(vol, sun, sigma_t=0.3, spacing_voxels=1.0)
    # along the central ray (uniform density) Ci decays as exp(-sigma_e * depth) from the top
    rel = pts.position - np.array([0.0, 0.5, 0.0])
    sel = (np.abs(rel[:, 0]) < 0.02) & (np.abs(rel[:, 2]) < 0.02) & (pts.density > 0.999)
    depth = (0.4 - rel[sel, 1])
    tol = pts.spacing * pts.sigma_e  # one lattice step at the surface
    assert np.allclose(np.log(pts.ci0[sel]), -pts.sigma_e * depth, atol=tol + 0.05)
    # the light that entered: Σ_rays h²(1 - T) = π R² (1 - mean T) for an opaque sphere ≈ π R²
    assert pts.sun_in == pytest.approx(np.pi * 0.4**2, rel=0.05)


def test_no_pass_creates_energy(sphere_solution):
    _, _, pts, sol, _ = sphere_solution
    e = sol.energy
    direct = float(np.sum(pts.interact * pts.ci0)) * pts.spacing**2
    assert e[0, 1] == pytest.approx(direct, rel=1e-5)
    assert np.all(e[0] <= pts.sun_in * (1 + 1e-6))           # direct light <= what entered from the sun
    assert np.all(np.diff(e, axis=0) <= 1e-9)                 # each pass scatters at most what it received
    assert np.all(e[1:, 1] > 0.5 * e[:-1, 1])                 # ... and does pass most of it on (albedo 1)


def test_absorbing_droplets_lose_light(table, sphere_solution):
    _, _, pts, sol, _ = sphere_solution
    sol_a = solve(pts, table, passes=3, albedo=0.5)
    assert np.all(sol_a.energy[1:] <= 0.5 * sol_a.energy[:-1] + 1e-12)


def test_ratio_follows_fig8(sphere_solution):
    # Fig. 8: the lit side ends more isotropic than the side band and the unlit side
    _, sun, pts, sol, hist = sphere_solution
    rel = pts.position - np.array([0.0, 0.5, 0.0])
    toward_sun = rel @ sun
    shell = np.linalg.norm(rel, axis=1) > 0.3
    lit = shell & (toward_sun > 0.25)
    band = shell & (np.abs(toward_sun) < 0.08)
    unlit = shell & (toward_sun < -0.25)
    assert sol.ratio[lit].mean() < sol.ratio[band].mean() - 0.05
    assert sol.ratio[lit].mean() < sol.ratio[unlit].mean() - 0.05
    assert np.all(hist[0] == 1.0) and np.all(np.diff(np.stack(hist), axis=0) <= 0)  # R only decreases
    # the unlit side receives forward-scattered light: its prominent direction stays the sun's
    assert np.mean(sol.direction[unlit] @ (-sun)) > 0.9


def test_solution_round_trip(tmp_path, sphere_solution):
    _, _, _, sol, _ = sphere_solution
    save_solution(tmp_path / "s.npz", sol)
    back = load_solution(tmp_path / "s.npz")
    assert np.array_equal(back.ratio, sol.ratio) and np.array_equal(back.co, sol.co)
    assert back.points.shape == sol.points.shape


# ------------------------------------------------------------------------------------------ march
def test_march_transmittance_and_background(table, sphere_solution):
    vol, sun, pts, sol, _ = sphere_solution
    cam = Camera((0.0, 0.5, -3.0), (0.0, 0.5, 0.0), (0, 1, 0), 2.0, 9, 9)
    sky = np.full((9, 9, 3), 0.5, np.float32)
    # no sun, no ambient: the sky through the cloud, T = exp(-sigma_e * chord) at the centre
    img = render_mie(vol, cam, sun, sol, table, {"L_in": 0.0, "L_amb": 0.0}, sky)
    chord = 0.8
    assert img[4, 4, 1] == pytest.approx(0.5 * np.exp(-pts.sigma_e * chord), rel=0.05, abs=1e-6)
    cam2 = Camera((0.0, 0.5, -3.0), (0.0, 0.5, 0.0), (0, 1, 0), 40.0, 9, 9)
    img2 = render_mie(vol, cam2, sun, sol, table, {"L_in": 0.0, "L_amb": 0.0}, sky)
    assert np.allclose(img2[0, 0], 0.5)  # corner ray misses the cloud


def test_march_linear_in_light_colour_and_rejects_other_sun(table, sphere_solution):
    vol, sun, pts, sol, _ = sphere_solution
    cam = Camera((0.0, 0.5, -2.5), (0.0, 0.5, 0.0), (0, 1, 0), 30.0, 16, 12)
    a = render_mie(vol, cam, sun, sol, table, {"L_in": 1.0, "L_amb": 0.0, "c_in": [1, 1, 1]})
    b = render_mie(vol, cam, sun, sol, table, {"L_in": 2.0, "L_amb": 0.0, "c_in": [1, 0.5, 0.25]})
    assert a.max() > 0
    assert np.allclose(b, a * np.array([2.0, 1.0, 0.5]), rtol=1e-5, atol=1e-7)
    with pytest.raises(InputError):
        render_mie(vol, cam, np.array([0.0, 1.0, 0.0]), sol, table, {})


def test_glory_view_shows_mie_backscatter_colours(table, sphere_solution):
    # looking from the sun: single scattering at 180° follows the table's colour ratio at the glory,
    # while HG's backscatter is grey
    vol, sun, pts, _, _ = sphere_solution
    sol0 = solve(pts, table, passes=0)
    centre = np.array([0.0, 0.5, 0.0])
    cam = Camera(tuple(centre + 3 * sun), tuple(centre), (0, 1, 0), 3.0, 5, 5)
    img = render_mie(vol, cam, sun, sol0, table, {"L_in": 1.0, "L_amb": 0.0, "c_in": [1, 1, 1]})[2, 2]
    back = table.rgb[-1]
    assert img / img[1] == pytest.approx(back / back[1], rel=0.02)
    hg = hg_table(float(table.g[1]))
    img_hg = render_mie(vol, cam, sun, solve(pts, hg, passes=0), hg, {"L_in": 1.0, "L_amb": 0.0,
                                                                       "c_in": [1, 1, 1]})[2, 2]
    assert np.allclose(img_hg / img_hg[1], 1.0, atol=1e-5)


def test_per_sun_cache_reused_and_never_stale(table, sphere_solution):
    # the per-sun fields are computed once per solution and reused for other views; a frame with the
    # cache warm equals one with a fresh cache, and another volume or table is not served stale entries
    from dataclasses import replace

    from natscene.mie.march import per_sun_fields
    vol, sun, pts, sol, _ = sphere_solution
    sol = replace(sol, cache={})
    cam = Camera((0.0, 0.5, -2.5), (0.0, 0.5, 0.0), (0, 1, 0), 30.0, 16, 12)
    cam2 = Camera((0.3, 0.9, -2.4), (0.0, 0.5, 0.0), (0, 1, 0), 25.0, 12, 10)
    params = {"L_in": 1.0, "L_amb": 0.1, "sky_color": [0.2, 0.3, 0.6]}
    a = render_mie(vol, cam, sun, sol, table, params)
    first = per_sun_fields(vol, sol, table)
    render_mie(vol, cam2, sun, sol, table, params)
    assert all(x is y for x, y in zip(per_sun_fields(vol, sol, table), first))  # reused, not recomputed
    assert np.array_equal(render_mie(vol, cam, sun, sol, table, params),
                          render_mie(vol, cam, sun, replace(sol, cache={}), table, params))
    assert np.array_equal(a, render_mie(vol, cam, sun, sol, table, params))
    thin = Volume(vol.density * 0.5, vol.bbox_min, vol.bbox_max, vol.extinction_scale)
    assert np.array_equal(render_mie(thin, cam, sun, sol, table, params),
                          render_mie(thin, cam, sun, replace(sol, cache={}), table, params))
    hg = hg_table(float(table.g[1]))
    assert per_sun_fields(vol, sol, hg)[2] is not first[2]
