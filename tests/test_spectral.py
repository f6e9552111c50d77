"""Tests of natscene.spectral: thin films against Fresnel / energy conservation / quarter-wave / an
independent transfer-matrix computation; CIE integration against colour-science's ColorChecker values."""
import colour
import numpy as np
import pytest

from natscene.color import linear_srgb_to_lab
from natscene.spectral import grid as G
from natscene.spectral.illuminants import d65, sun_spd
from natscene.spectral.indices import complex_index
from natscene.spectral.thin_film import film_table, multilayer
from natscene.spectral.upsampling import rgb_to_radiance, rgb_to_reflectance

WL = np.linspace(380, 780, 41)
TH = np.radians(np.array([0.0, 20.0, 45.0, 70.0, 85.0]))


def fresnel_textbook(n1, n2, th):
    """Hecht's Fresnel power reflectances for a single interface (s and p)."""
    ci = np.cos(th)
    ct = np.sqrt(1 - (n1 / n2) ** 2 * np.sin(th) ** 2 + 0j)
    rs = (n1 * ci - n2 * ct) / (n1 * ci + n2 * ct)
    rp = (n2 * ci - n1 * ct) / (n2 * ci + n1 * ct)
    return np.abs(rs) ** 2, np.abs(rp) ** 2


def tmm_textbook(ns, ds, wl, th):
    """Characteristic-matrix method (Born & Wolf §1.6 / Macleod): R for s and p, independent of Eqs. 1.14-1.25."""
    n0 = ns[0]
    out = {}
    for pol in "sp":
        R = np.zeros((th.size, wl.size))
        for a, t in enumerate(th):
            for b, lam in enumerate(wl):
                beta = n0 * np.sin(t)
                def eta(n):
                    c = np.sqrt(n ** 2 - beta ** 2 + 0j)
                    c = c if c.imag >= 0 else -c
                    return (c if pol == "s" else n ** 2 / c), c
                M = np.eye(2, dtype=complex)
                for n, d in zip(ns[1:-1], ds):
                    e, c = eta(n)
                    delta = 2 * np.pi * c * d / lam
                    M = M @ np.array([[np.cos(delta), -1j * np.sin(delta) / e], [-1j * e * np.sin(delta), np.cos(delta)]])
                es, _ = eta(ns[-1])
                e0, _ = eta(n0)
                B, C = M @ np.array([1, es])
                r = (e0 * B - C) / (e0 * B + C)
                R[a, b] = abs(r) ** 2
        out[pol] = R
    return out


def test_single_interface_is_fresnel():
    for n2 in (1.5, 2.4):
        res = multilayer([1.0, n2], [], WL, TH)
        rs, rp = fresnel_textbook(1.0, n2, TH[:, None])
        np.testing.assert_allclose(res["R_s"], np.broadcast_to(rs, res["R_s"].shape), atol=1e-12)
        np.testing.assert_allclose(res["R_p"], np.broadcast_to(rp, res["R_p"].shape), atol=1e-12)
        # Brewster: R_p vanishes at atan(n2)
        rb = multilayer([1.0, n2], [], [550.0], [np.arctan(n2)])
        assert rb["R_p"][0, 0] < 1e-20
        # normal incidence: ((n-1)/(n+1))^2
        assert multilayer([1.0, n2], [], [550.0], [0.0])["R"][0, 0] == pytest.approx(((n2 - 1) / (n2 + 1)) ** 2)


def test_lossless_stack_conserves_energy():
    res = multilayer([1.0, 1.38, 2.3, 1.46, 1.52], [120.0, 75.0, 300.0], WL, TH)
    np.testing.assert_allclose(res["R_s"] + res["T_s"], 1.0, atol=1e-12)
    np.testing.assert_allclose(res["R_p"] + res["T_p"], 1.0, atol=1e-12)
    assert res["R"].min() >= 0 and res["R"].max() <= 1


def test_quarter_wave_antireflection_minimum_at_design_wavelength():
    lam0, ns, nf = 550.0, 1.52, 1.38
    wl = np.arange(400.0, 701.0, 1.0)
    R = multilayer([1.0, nf, ns], [lam0 / (4 * nf)], wl, [0.0])["R"][0]
    assert wl[np.argmin(R)] == pytest.approx(lam0, abs=1.0)
    # analytic minimum ((n0 ns - nf^2) / (n0 ns + nf^2))^2
    assert R.min() == pytest.approx(((ns - nf ** 2) / (ns + nf ** 2)) ** 2, rel=1e-6)


def test_absorbing_stack_matches_transfer_matrix():
    wl = np.array([400.0, 500.0, 600.0, 700.0])
    th = np.radians([0.0, 35.0, 70.0])
    ns = [1.0, complex_index("Au", wl), 1.56 + 0.06j, complex_index("Cu", wl)]
    res = multilayer(ns, [30.0, 150.0], wl, th)
    for b in range(wl.size):
        ref = tmm_textbook([1.0, ns[1][b], ns[2], ns[3][b]], [30.0, 150.0], wl[b:b + 1], th)
        np.testing.assert_allclose(res["R_s"][:, b], ref["s"][:, 0], atol=1e-10)
        np.testing.assert_allclose(res["R_p"][:, b], ref["p"][:, 0], atol=1e-10)
    assert np.all(res["T"] == 0)  # absorbing substrate (Eq. 1.25)


def test_thick_gold_film_is_gold_and_bare_copper_is_copper():
    gold = film_table([("Au", 500.0)], "Cu")
    bare_au = film_table([], "Au")
    np.testing.assert_allclose(gold.R, bare_au.R, atol=1e-6)  # 500 nm of gold is optically thick
    rgb = G.reflectance_to_rgb(gold.R[0])
    assert rgb[0] > rgb[1] > rgb[2]  # yellow
    # measured normal-incidence reflectance of gold around 650 nm is ~0.95 (Palik/Johnson-Christy)
    assert 0.9 < np.interp(650, gold.grid.wavelengths, gold.R[0]) < 0.99


def test_colorchecker_under_d65_matches_colour_science():
    grid = G.DEFAULT_GRID
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    ill = colour.SDS_ILLUMINANTS["D65"]
    for name, sd in colour.SDS_COLOURCHECKERS["BabelColor Average"].items():
        R = np.asarray(sd.copy().align(grid.shape).values)
        ours = G.reflectance_to_rgb(R)
        ref = colour.XYZ_to_sRGB(colour.sd_to_XYZ(sd.copy().align(grid.shape), cmfs, ill) / 100,
                                 apply_cctf_encoding=False)
        de = colour.delta_E(linear_srgb_to_lab(ours), linear_srgb_to_lab(ref), method="CIE 2000")
        assert de < 0.5, (name, ours, ref)


def test_d65_is_rgb_white_and_upsampling_round_trips():
    np.testing.assert_allclose(G.spectrum_to_rgb(d65()), 1.0, atol=5e-4)
    rgb = np.random.default_rng(1).random((50, 3))
    np.testing.assert_allclose(G.spectrum_to_rgb(rgb_to_radiance(rgb)), rgb, atol=2e-3)
    refl = rgb_to_reflectance(rgb)
    assert refl.min() >= -1e-9 and refl.max() <= 1 + 1e-6
    # Smits: white maps to (almost) flat 1, colours round-trip approximately
    np.testing.assert_allclose(rgb_to_reflectance([1.0, 1.0, 1.0], method="smits1999"), 1.0, atol=1e-3)
    sm = G.spectrum_to_rgb(rgb_to_radiance(rgb, method="smits1999"))
    assert np.abs(sm - rgb).mean() < 0.05


def test_sun_spd_matches_c_in():
    for c in ([1.0, 0.85, 0.6], [0.8, 0.9, 1.0]):
        np.testing.assert_allclose(G.spectrum_to_rgb(sun_spd(c)), c, atol=2e-3)


def test_complex_index_strings():
    import pytest
    from natscene.errors import InputError
    from natscene.spectral.indices import complex_index
    wl = np.array([400.0, 550.0, 700.0])
    np.testing.assert_array_equal(complex_index("2.0+0.05j", wl), np.full(3, 2.0 + 0.05j))
    np.testing.assert_array_equal(complex_index(1.56, wl), np.full(3, 1.56 + 0j))
    with pytest.raises(InputError):
        complex_index("1.5-0.1j", wl)  # kappa < 0 would amplify
    with pytest.raises(InputError, match="available"):
        complex_index("Unobtainium", wl)
