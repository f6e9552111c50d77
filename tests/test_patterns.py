"""Pattern maps (Dong 2007 Ch. 3): reaction-diffusion against linear stability, venation transport
direction, colour expression properties."""
import numpy as np
import pytest

from natscene.patterns.expression import chromaticity, express_rgb, express_xyz, precompute
from natscene.patterns.pigments import Pigment, WAVELENGTHS, band_absorption, pigment
from natscene.patterns.reaction_diffusion import (RDParams, dominant_wavelength, fastest_wavelength,
                                                  laplacian, simulate, stable_dt)
from natscene.patterns.venation import Venation, venation_from_nodes


def test_turing_wavelength_matches_linear_stability():
    # t = 0 (no venation) on a square: the FFT peak is the fastest-growing mode of the linearised Eq. 3.5
    # (S and D scaled by 1/64 from S = 0.5, D_B = 32: same wavelength, within the explicit limit D dt <= 1/2)
    p = RDParams(S=0.5 / 64, D_A=1.6 / 64, D_B=32.0 / 64, t=0, K_A=1.0, K_B=1.0, beta=0.2, noise=0.05, dt=1.0,
                 max_steps=12000, tol=1e-7, seed=3)
    lam = fastest_wavelength(p)
    assert 8 < lam < 20
    r = simulate(np.ones((96, 96), np.float32), None, p)
    assert r.a.max() - r.a.min() > 0.2  # a pattern formed
    assert abs(dominant_wavelength(r.a) - lam) / lam < 0.15


def test_stable_parameters_have_no_turing_mode():
    # Table 3.3 (3.3(b)-1): D_A > D_B cannot be Turing-unstable (trace argument)
    assert fastest_wavelength(RDParams(S=0.1, D_A=0.15, D_B=0.1)) == float("inf")


def test_laplacian_is_conservative_and_reduces_to_eq_3_4():
    mask = np.ones((12, 12), np.float32)
    mask[:, :3] = 0
    L0, cells = laplacian(mask, None, t=0.0)
    assert np.allclose(L0.sum(axis=1), 0)  # no-flux: constants are in the kernel
    # interior row: Eq. 3.4, 1/4 on each neighbour, -1 on the centre
    i = int(np.searchsorted(cells, 6 * 12 + 7))
    row = L0.getrow(i).toarray().ravel()
    assert row[i] == pytest.approx(-1.0) and sorted(row[row > 0]) == pytest.approx([0.25] * 4)
    v = venation_from_nodes((12, 12), {"root": [0.4, 0.5], "nodes": [{"xy": [1.0, 0.5], "width": 1.0}]}, 1.0)
    L2, _ = laplacian(mask, v, t=2.0)
    assert np.allclose(L2.sum(axis=1), 0)
    assert (abs(L2 - L2.T) > 1e-12).nnz == 0  # symmetric


def test_vein_carries_the_root_supply():
    # a straight vein from the root at the left edge: the transport function (p_vv >> p_mm) carries the
    # root's hormone supply along the vein, so pigment A is higher on the vein than in the tissue beside it
    h, w = 41, 60
    mask = np.ones((h, w), np.float32)
    ven = venation_from_nodes((h, w), {"root": [0.0, 0.5], "nodes": [{"xy": [1.0, 0.5], "width": 1.0}]}, 1.0)
    row = h // 2
    res = {}
    for t in (0.0, 10.0):
        p = RDParams(S=0.1, D_A=0.15, D_B=0.1, t=t, root_supply=(4.0, 4.0), noise=0.0, dt=2.5,
                     max_steps=300, tol=1e-6)
        r = simulate(mask, ven, p)
        on = r.a[row, 10:50].mean()
        off = r.a[row - 10, 10:50].mean()
        res[t] = on - off
    a0 = RDParams().steady_state()[0]
    assert res[10.0] > 0.01 * a0
    assert res[10.0] > 5 * abs(res[0.0])


def test_unstable_dt_is_refused():
    from natscene.errors import InputError

    p = RDParams(S=0.5, dt=10.0)
    assert p.dt > stable_dt(p)
    with pytest.raises(InputError, match="dt"):
        simulate(np.ones((8, 8), np.float32), None, p)


def test_zero_concentration_gives_base_colour():
    t = precompute([pigment("anthocyanin"), pigment("blank")])
    assert np.allclose(express_xyz(t, np.zeros(2)), t.X0)
    # the base is the lit tissue (L - T): Y below the illuminant's 1 and neutral-ish (chromaticity near D65)
    assert 0.2 < t.X0[1] < 1.0
    assert np.allclose(chromaticity(t.X0), [0.3127, 0.3290], atol=0.03)
    # the blank pigment changes nothing
    assert np.allclose(express_xyz(t, np.array([0.0, 1.0])), t.X0)


def test_chromaticity_moves_monotonically_with_concentration():
    t = precompute([pigment("anthocyanin")])
    c = np.linspace(0, 1, 11)[:, None]
    xy = chromaticity(express_xyz(t, c))
    d = np.linalg.norm(xy - xy[0], axis=1)
    assert np.all(np.diff(d) > 0)
    Y = express_xyz(t, c)[:, 1]
    assert np.allclose(np.diff(Y), np.diff(Y)[0])  # Eq. 3.10: lightness linear in c


def test_green_absorber_is_reddish():
    k = band_absorption([(540.0, 35.0, 1.0)])
    assert WAVELENGTHS[np.argmax(k)] == 540.0
    t = precompute([Pigment("green", k, depth=3.0)])
    rgb = express_rgb(t, np.ones(1))
    assert rgb[0] > 1.5 * rgb[1]
    x, y = chromaticity(express_xyz(t, np.ones(1)))
    assert y < 0.3290 - 0.03  # away from green: below the white point, toward red-magenta


def test_prospect_spectra_shapes():
    chl = pigment("chlorophyll").k
    # chlorophyll absorbs blue and red, little green
    g = chl[np.searchsorted(WAVELENGTHS, 550)]
    assert chl[np.searchsorted(WAVELENGTHS, 430)] > 2 * g and chl[np.searchsorted(WAVELENGTHS, 670)] > 2 * g
    ant = pigment("anthocyanin").k
    assert 500 <= WAVELENGTHS[np.argmax(ant)] <= 580


def test_semi_implicit_reaction_accepts_stiff_slow_kinetics():
    # K_A = 3e-3, K_B = 5e7, beta = 1e-8 (slow rates ~2e-4 per step, stiff off-diagonal 2 S K_B a b = 2e4):
    # the per-cell linearised update is stable at dt = 1 (row-sum criterion would need dt ~ 5e-5) and the
    # uniform steady state with a neutral root supply and no noise stays exact
    from natscene.patterns.reaction_diffusion import amplification

    p = RDParams(S=0.1, D_A=0.15, D_B=0.1, t=0, K_A=3e-3, K_B=5e7, beta=1e-8, noise=0.0, dt=1.0, max_steps=50)
    assert 1.0 / np.abs(p.jacobian()).sum(axis=1).max() < 1e-4
    assert np.abs(np.linalg.eigvals(amplification(p))).max() < 1.0
    assert stable_dt(p) >= 1.0
    r = simulate(np.ones((10, 10), np.float32), None, p)
    a0, b0 = p.steady_state()
    assert np.allclose(r.a, a0, rtol=1e-4) and np.allclose(r.b, b0, rtol=1e-4)
