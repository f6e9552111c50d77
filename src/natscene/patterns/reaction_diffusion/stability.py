"""
Stability of the explicit reaction-diffusion update
===================================================

Defines the linear stability of the explicit (semi-implicit reaction) update of Eq. 3.5 (Dong 2007, §3.3.2) at
the homogeneous steady state:

-   :func:`amplification`: the per-step amplification matrix.
-   :func:`stable_dt`: the largest stable time step; :func:`reaction_stable`: whether a time step is stable.

The reaction is linearised per cell on its own species (the update of a is divided by
1 + dt max(-dR_a/da, 0) = 1 + dt max(S_A (K_A - 2ab), 0), that of b by 1 + dt S_B K_B a^2), so stiff kinetics
such as K_B ~ 1e8 no longer force dt ~ 1e-6. The step is accepted when the spectral radius of the linearised
update is <= 1, or <= exp(dt max Re lambda(J)) where the kinetics themselves grow. (The diffusion limits of the
explicit scheme are checked where it is set up, :func:`natscene.patterns.reaction_diffusion.explicit.simulate_explicit`.)

References
----------
-   Dong, W. (2007). Rendering Algorithms for Natural Scenes. PhD thesis, Université Henri Poincaré - Nancy I.
"""
from __future__ import annotations

import numpy as np

from natscene.patterns.reaction_diffusion.parameters import RDParams

__all__ = ["amplification", "reaction_stable", "stable_dt"]


def amplification(p: RDParams, dt: float | None = None) -> np.ndarray:
    """Per-step amplification matrix of the reaction update at the homogeneous steady state: the
    semi-implicit scheme ``u' = u + dt R(u) / (1 + dt max(-dR_i/du_i, 0))`` linearised, i.e.
    ``G = I + dt diag(1 / (1 + dt max(-J_ii, 0))) J``."""
    dt = p.dt if dt is None else dt
    J = p.jacobian()
    den = 1.0 + dt * np.maximum(-np.diag(J), 0.0)
    return np.eye(2) + dt * J / den[:, None]


def reaction_stable(p: RDParams, dt: float) -> bool:
    grow = float(np.linalg.eigvals(p.jacobian()).real.max())
    bound = max(1.0, float(np.exp(min(dt * grow, 50.0))))
    return float(np.abs(np.linalg.eigvals(amplification(p, dt))).max()) <= bound * (1 + 1e-9)


def stable_dt(p: RDParams) -> float:
    """Largest dt for which the semi-implicit reaction update is linearly stable at the homogeneous steady
    state (spectral radius of ``amplification`` <= 1, or <= exp(dt max Re lambda(J)) where the kinetics
    themselves grow), found on a log grid 1e-6..1e6 (every smaller grid dt must pass too)."""
    best = 0.0
    for dt in np.logspace(-6, 6, 481):
        if not reaction_stable(p, float(dt)):
            break
        best = float(dt)
    return best
