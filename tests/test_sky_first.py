"""The skylight's first order by shadow rays (natscene.scatter.sky_first).

Reference known independently of the code under test: in a box of constant density lit by a dome of uniform
radiance L (sky and ground), the light arriving at x from the direction -ω has crossed the box from its face,
so S_1(x) = L ∫ exp(-mu_t t(x, -ω)) p(ω · ω_cam, g) dω with t the analytic distance to the box's face. The
integral is evaluated here by a dense quadrature over a Fibonacci sphere (400 000 directions), with none of the
estimator's sampling, marching or cell averaging.
"""
import numpy as np
import pytest

import natscene  # noqa: F401
from natscene.phase import hg
from natscene.scatter.inscatter import voxel_camera_depth
from natscene.scatter.medium import make_medium
from natscene.scatter.photons import SkySource
from natscene.scatter.skylight import uniform_dome
from natscene.scatter.sky_first import first_order_numerators, shadow_samples
from natscene.volume.grid import Volume

N = 16
L = 0.7


def _box(scale: float) -> Volume:
    return Volume(np.ones((N, N, N), np.float32), np.zeros(3), np.ones(3), scale)


def _fibonacci(n: int) -> np.ndarray:
    i = np.arange(n) + 0.5
    mu = 1 - 2 * i / n
    phi = np.pi * (1 + 5 ** 0.5) * i
    s = np.sqrt(1 - mu ** 2)
    return np.stack([s * np.cos(phi), mu, s * np.sin(phi)], -1)


def _exit_distance(x: np.ndarray, d: np.ndarray) -> np.ndarray:
    """Distance from x inside the unit box along the unit rows of d to its face."""
    with np.errstate(divide="ignore"):
        t = np.where(d > 0, (1 - x) / d, np.where(d < 0, -x / d, np.inf))
    return t.min(axis=1)


def _quadrature(x: np.ndarray, cam: np.ndarray, mu_t: float, g: float) -> float:
    """S_1(x) by a Fibonacci sphere of directions."""
    om = _fibonacci(100_000)                                  # directions of travel, uniform
    to_cam = (cam - x) / np.linalg.norm(cam - x)
    src_t = _exit_distance(x[None], -om)
    return float(L * np.mean(np.exp(-mu_t * src_t) * hg(om @ to_cam, g)) * 4 * np.pi)


def _cell_reference(ix: int, iy: int, iz: int, cam: np.ndarray, mu_t: float, g: float) -> float:
    """The cell's mean of S_1 weighted by the camera transmittance w (as the cache weights it), by 3 x 3 x 3
    Gauss-Legendre points; w = exp(-mu_t x the distance to the camera inside the box), exact."""
    x, wx = np.polynomial.legendre.leggauss(3)
    u, wu = (x + 1) / 2, wx / 2
    num = den = 0.0
    for a, wa in zip(u, wu):
        for b, wb in zip(u, wu):
            for c, wc in zip(u, wu):
                p = (np.array([ix, iy, iz]) + [a, b, c]) / N
                to_cam = (cam - p) / np.linalg.norm(cam - p)
                w = wa * wb * wc * np.exp(-mu_t * _exit_distance(p[None], to_cam[None])[0])
                num += w * _quadrature(p, cam, mu_t, g)
                den += w
    return num / den


@pytest.mark.parametrize("mu_t,g", [(0.5, 0.0), (2.0, 0.85), (6.0, 0.9), (6.0, 0.5)])
def test_first_order_in_a_constant_box_matches_quadrature(mu_t, g):
    """Per cell (one voxel) the estimate's w rho-weighted mean of S_1 against the quadrature's (w the camera
    transmittance, the weighting of the cache), on 24 cells of the box's half toward the camera: within 2 % on
    average over the cells and 15 % in every cell. 1024 points per cell; the cells' spread is the estimator's
    noise (at mu_t 6, g 0.9: ±25 % with 256 points, ±11 % with 1024, the mean within 1 % at both)."""
    vol = _box(mu_t)
    med = make_medium(vol)
    cam = np.array([0.5, 0.6, -3.0])
    depth = voxel_camera_depth(med, cam)
    s = shadow_samples(med, depth, cam, SkySource(uniform_dome(L), np.zeros(3), np.ones(3)), [g], 1, per_cell=1024,
                       seed=3)
    q = np.ones((N, N, N))                                    # S_1 itself: C / Q with Q = 1
    est = first_order_numerators(s, mu_t, g, q).mean(0)[0]    # the two halves, channel R (the dome's)
    ground = first_order_numerators(s, mu_t, g, q).mean(0)[3]
    rng = np.random.default_rng(0)
    cells = np.stack([rng.integers(1, N - 1, 24), rng.integers(1, N - 1, 24), rng.integers(0, N // 2, 24)], -1)
    ratios = []
    for ix, iy, iz in cells:
        ref = _cell_reference(ix, iy, iz, cam, mu_t, g)
        ratios.append((est[iz, iy, ix] + ground[iz, iy, ix] * L) / ref)   # the dome's R is L
    ratios = np.array(ratios)
    print(f"mu_t {mu_t}, g {g}: ratio mean {ratios.mean():.4f}, range {ratios.min():.3f}-{ratios.max():.3f}")
    assert abs(ratios.mean() - 1) <= 0.02
    assert np.all(np.abs(ratios - 1) <= 0.15)


def test_halves_are_independent_and_every_point_is_counted():
    """Each cell holds per_cell points, half of them in each half; a zero extinction gives S_1 = L exactly (the
    phase function integrates to one, nothing attenuates), so each half's R + ground reads L to sampling error."""
    vol = _box(1e-6)
    med = make_medium(vol)
    cam = np.array([0.5, 0.5, -3.0])
    s = shadow_samples(med, voxel_camera_depth(med, cam), cam, SkySource(uniform_dome(L), np.zeros(3), np.ones(3)),
                       [0.0, 0.9], 1, per_cell=32, seed=1)
    assert s.rho.size == N ** 3 * 32
    assert np.all(np.bincount(s.index, minlength=2 * N ** 3) == 16)
    c = first_order_numerators(s, 0.0, 0.9, np.ones((N, N, N)))
    total = c[:, 0] + c[:, 3] * L                             # (2 halves, cells): the dome's R is L
    assert abs(total.mean() / L - 1) <= 0.01
    assert not np.allclose(total[0], total[1])


def test_numerators_do_not_depend_on_the_chunk_size():
    """The sums over the points run in chunks (to bound the temporaries): chunks of 1000 points, which split
    cells, give the numerators of one chunk holding every point, to float64 rounding."""
    vol = _box(2.0)
    med = make_medium(vol)
    cam = np.array([0.5, 0.6, -3.0])
    s = shadow_samples(med, voxel_camera_depth(med, cam), cam, SkySource(uniform_dome(L), np.zeros(3), np.ones(3)),
                       [0.0, 0.85], 1, per_cell=48, seed=2)
    q = np.ones((N, N, N))
    whole = first_order_numerators(s, 2.0, 0.85, q, chunk=s.index.size)
    parts = first_order_numerators(s, 2.0, 0.85, q, chunk=1000)
    assert s.index.size > 10 * 1000 and whole.max() > 0
    np.testing.assert_allclose(parts, whole, rtol=1e-12, atol=1e-15 * whole.max())
