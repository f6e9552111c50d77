"""The diffusion jumps' precomputed balls and where they may be taken (natscene.scatter.jumps).

The balls' walks against diffusion theory with the extrapolated boundary: a walk of unit mean free paths has the
diffusion coefficient 1/3, so from the centre of a ball of radius R it needs (R + q)^2 / 2 flights on average to
leave it, q = 0.7104 the extrapolation length of the Milne problem (Chandrasekhar 1960, q(inf) = alpha_2 / alpha_1
of the H-function of conservative isotropic scattering); its exit directions, for R >> 1, have the Milne problem's
emergent distribution, whose mean cosine (weighted by the flux across the sphere) is that same q. The transport with
the jumps against adding-doubling: tests/test_slab.py (its thick slabs take them).
"""
import numpy as np
import pytest

import natscene  # noqa: F401
from natscene.scatter.jumps import BALL_RADII, ball_exits, homogeneous_radii, jump_radii

Q_INF = 0.710446


def test_ball_walks_leave_after_the_diffusion_time():
    n, _ = ball_exits()
    for r, row in zip(BALL_RADII, n):
        expect = (r + Q_INF) ** 2 / 2.0
        assert abs(row.mean() / expect - 1.0) < 0.04, (r, row.mean(), expect)


def test_large_ball_exits_in_the_milne_distribution():
    _, mu = ball_exits()
    assert np.all((mu > 0) & (mu <= 1.0))
    assert abs(mu[-1].mean() / Q_INF - 1.0) < 0.02, mu[-1].mean()
    # Eddington's approximation of that distribution, mu (1 + 1.5 mu), puts 0.8125 of it above mu = 0.5 (an
    # isotropic radiance, 2 mu, 0.75)
    assert abs(np.mean(mu[-1] > 0.5) - 0.8125) < 0.025


@pytest.mark.parametrize("block", [1, 4])
def test_homogeneous_balls_stay_inside_the_box_and_the_uniform_density(block):
    d = np.ones((40, 40, 40), np.float32)
    d[30:, :, :] = 2.0           # a step along z: the trilinear density is 1 up to z = 29.5, 2 from z = 30.5
    radius, top = homogeneous_radii(d, (1.0, 1.0, 1.0), block)
    mid = 20 // block
    for c in range(radius.shape[0]):
        r = float(radius[c, mid, mid])      # a ball about any point of cell c (z in [c b, (c + 1) b])
        if r > 0:
            lo, hi = c * block - r, (c + 1) * block + r
            assert lo >= 0 and hi <= 40, (c, r)
            assert hi <= 29.5 or lo >= 30.5, (c, r)
    assert radius[12 // block, mid, mid] >= 6.0                   # deep inside the lower part
    assert radius[0, mid, mid] == 0.0 and radius[29 // block, mid, mid] == 0.0
    assert np.all(top[radius > 0] >= 1.0) and np.all(top[radius > 0] <= 2.0)


def test_jump_radii_keep_the_ball_out_of_sight():
    radius = np.full((4, 4, 4), 10.0)
    top = np.full((4, 4, 4), 2.0)
    depth = np.full((4, 4, 4), 30.0)            # camera depth (density x length) at extinction 1 per unit density
    r = jump_radii(radius, top, depth, 1.0, 18.5)
    assert np.allclose(r, (30.0 - 18.5) / 2.0)   # the ball's nearest point to the camera still 18.5 deep
    assert np.all(jump_radii(radius, top, np.full((4, 4, 4), 10.0), 1.0, 18.5) == 0.0)
    assert np.allclose(jump_radii(radius, top, np.full((4, 4, 4), 100.0), 1.0, 18.5), 10.0)
