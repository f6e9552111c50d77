"""The four Fig. 3.3 presets (Dong 2007 §3.3, Table 3.3) on a reduced petunia grid: each map has the shape its
name says (centre spot, radial stripes, ring, marginal band), the shapes do not depend on the grid resolution
(kinetics rescaled with the grid), and the implicit scheme reaches the same steady state as the explicit one."""
import numpy as np
import pytest

from natscene.patterns.presets import TABLE_3_3, petal_shape, rd_params, venation
from natscene.patterns.reaction_diffusion import RDParams, schnakenberg_constants, simulate
from natscene.patterns.shape import angular_contrast, radial_profile

ROOT_DIR = __import__("pathlib").Path(__file__).resolve().parents[1]


def petunia(scale):
    w, h = int(549 * scale), int(528 * scale)
    mask = petal_shape({"kind": "file", "path": "resources/patterns/petunia_petal_549x528.png"}, (w, h),
                       lambda q: str(ROOT_DIR / q))
    ven = venation({"kind": "radial", "n_veins": 9, "opening_deg": 90, "vein_px": 4 * scale}, (w, h))
    return mask, ven, h


@pytest.fixture(scope="module")
def maps():
    mask, ven, h = petunia(0.25)
    out = {}
    for name in ("centre_spot", "radial_stripes", "ring", "marginal_band"):
        p = rd_params({"preset": name}, 0, h)
        assert (p.S, p.D_A, p.D_B, p.t) == tuple(TABLE_3_3[name][k] for k in ("S", "D_A", "D_B", "t"))
        r = simulate(mask, ven, p)
        assert r.converged and np.isfinite(r.a).all()
        out[name] = (radial_profile(r.a, mask, ven.root), angular_contrast(r.a, mask, ven.root))
    return out


def test_centre_spot(maps):
    P, _ = maps["centre_spot"]
    assert P[0] > 0.7 and P[5:].mean() < 0.3
    assert np.all(np.diff(P) < 0.02)  # falls from the root to the margin


def test_marginal_band(maps):
    P, _ = maps["marginal_band"]
    assert P[-2:].mean() > 0.75 and P[:3].mean() < 0.3
    assert np.all(np.diff(P) > -0.02)  # rises from the root to the margin


def test_ring(maps):
    P, _ = maps["ring"]
    k = int(np.argmax(P))
    assert 1 <= k <= 5  # the maximum is inside the petal, not at the root or the margin
    assert P[k] - P[0] > 0.25 and P[k] - P[-1] > 0.2


def test_radial_stripes(maps):
    _, con = maps["radial_stripes"]
    assert con > 0.25
    for other in ("centre_spot", "ring", "marginal_band"):
        assert con > 1.3 * maps[other][1]  # measured: 0.31 vs 0.15 (spot), 0.14 (ring), 0.23 (band)


def test_presets_do_not_depend_on_grid_resolution():
    profiles = []
    for scale in (0.2, 1 / 3):
        mask, ven, h = petunia(scale)
        r = simulate(mask, ven, rd_params({"preset": "centre_spot"}, 0, h))
        profiles.append(radial_profile(r.a, mask, ven.root))
    assert np.abs(profiles[0] - profiles[1]).max() < 0.06


def test_implicit_scheme_reaches_the_explicit_steady_state():
    """Strang splitting (large dt) vs explicit Euler (dt = 1) on the same venation-free problem with a root
    supply: the converged maps agree (the splitting error is O(dt^2) at the fixed point)."""
    mask = np.ones((24, 40), np.float32)
    from natscene.patterns.venation import Venation
    ven = Venation.empty(mask.shape, root=(12, 0))
    k = schnakenberg_constants(0.2, 0.8, 0.05)
    base = dict(S=0.1, D_A=0.3, D_B=0.2, t=0.0, root_supply=(3.0, 1.5), noise=0.0, **k)
    ex = simulate(mask, ven, RDParams(**base, dt=1.0, max_steps=40000, tol=1e-7))
    for m in (0, 5):  # plain Strang steps and Anderson-accelerated ones have the same fixed point
        im = simulate(mask, ven, RDParams(**base, dt=20.0, scheme="implicit", anderson=m, max_steps=2000, tol=1e-9))
        assert ex.converged and im.converged
        rel = np.abs(im.a - ex.a).max() / ex.a.max()
        assert rel < 0.01
    assert ex.a.max() / ex.a.min() > 1.2  # the supply makes a real gradient (the check is not trivial)


def test_bad_scheme_is_refused():
    from natscene.errors import InputError
    with pytest.raises(InputError, match="scheme"):
        simulate(np.ones((8, 8), np.float32), None, RDParams(scheme="rk4"))


def test_normalisation_modes():
    """'max' is Dong's c = C / C_0 (C_0 = the petal maximum); 'range' puts the petal minimum at c = 0."""
    from natscene.errors import InputError
    from natscene.patterns.reaction_diffusion import normalise
    mask = np.zeros((4, 5), np.float32)
    mask[1:3, 1:4] = 1
    conc = np.linspace(2.0, 4.0, 20, dtype=np.float32).reshape(4, 5)
    inside = mask > 0
    c = normalise(conc, mask)
    assert np.allclose(c[inside], conc[inside] / conc[inside].max()) and (c[~inside] == 0).all()
    r = normalise(conc, mask, mode="range")
    assert r[inside].min() == 0 and np.isclose(r[inside].max(), 1) and (r[~inside] == 0).all()
    lo, hi = conc[inside].min(), conc[inside].max()
    assert np.allclose(r[inside], (conc[inside] - lo) / (hi - lo), atol=1e-6)
    with pytest.raises(InputError, match="normalisation"):
        normalise(conc, mask, mode="log")
