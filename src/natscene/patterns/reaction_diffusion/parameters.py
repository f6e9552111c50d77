"""
Parameters of the reaction-diffusion
====================================

Defines the parameters of Dong's (2007) reaction-diffusion (§3.3.2, Tables 3.1-3.3):

-   :class:`RDParams`: the parameters of Eq. 3.5, with the steady state and the Jacobian.
-   :func:`schnakenberg_constants`: K_A, K_B, beta for Murray's non-dimensional Schnakenberg kinetics.
-   :data:`P_MM`, :data:`P_MV`, :data:`P_VV`: the transport weights of Eq. 3.1.

The Schnakenberg kinetics of Eq. 3.3 in the discrete form of Eq. 3.5 for pigment concentrations a, b,

    dA = S_A (a^2 b - K_A a + beta) + D_A l^(a)
    dB = S_B (1 - K_B a^2 b)        + D_B l^(b)

with the homogeneous steady state a* = (beta + 1/K_B) / K_A, b* = 1 / (K_B a*^2); the transport weights
p_mm, p_mv, p_vv of Eq. 3.1; the vein-root supply; the time stepping and convergence settings. The update itself:
:func:`natscene.patterns.reaction_diffusion.explicit.eq35_step`.

References
----------
-   Dong, W. (2007). Rendering Algorithms for Natural Scenes. PhD thesis, Université Henri Poincaré - Nancy I.
-   Murray, J. D. (2003). Mathematical Biology, Volume II: Spatial Models and Biomedical Applications. Springer.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

__all__ = ["P_MM", "P_MV", "P_VV", "RDParams", "schnakenberg_constants"]

P_MM, P_MV, P_VV = 1.0, 2.0, 10.0


@dataclass
class RDParams:
    """Parameters of Eq. 3.5 (Table 3.1/3.3 names). S sets S_A = S_B unless they are given."""

    S: float = 0.1
    D_A: float = 0.15
    D_B: float = 0.1
    t: float = 2.0
    K_A: float = 1.0
    K_B: float = 1.0
    beta: float = 0.5
    S_A: float | None = None
    S_B: float | None = None
    p_mm: float = P_MM
    p_mv: float = P_MV
    p_vv: float = P_VV
    root_supply: tuple = (1.0, 1.0)
    noise: float = 0.01
    dt: float = 1.0
    max_steps: int = 4000
    tol: float = 1e-4
    check_every: int = 10
    n_dyadic: int = 8
    seed: int = 0
    #: "explicit" (Euler, dt ~ 1, the paper's per-iteration update) or "implicit" (Strang splitting: exact-ish
    #: local reaction by implicit Euler + implicit diffusion with a cached sparse LU; dt up to ~1/rate, for the
    #: slow kinetics of the Fig. 3.3 presets; its ``tol`` applies to the relative change per step)
    scheme: str = "explicit"
    #: implicit scheme only: Anderson mixing depth (0 = plain Strang steps)
    anderson: int = 0

    @property
    def sa(self) -> float:
        return self.S if self.S_A is None else self.S_A

    @property
    def sb(self) -> float:
        return self.S if self.S_B is None else self.S_B

    def steady_state(self) -> tuple[float, float]:
        a = (self.beta + 1.0 / self.K_B) / self.K_A
        return a, 1.0 / (self.K_B * a * a)

    def jacobian(self) -> np.ndarray:
        """Reaction Jacobian of Eq. 3.5 at the homogeneous steady state."""
        a, b = self.steady_state()
        return np.array([[self.sa * (2 * a * b - self.K_A), self.sa * a * a],
                         [-self.sb * self.K_B * 2 * a * b, -self.sb * self.K_B * a * a]])

    def to_dict(self) -> dict:
        d = asdict(self)
        d["root_supply"] = list(self.root_supply)
        return d


def schnakenberg_constants(a_m: float, b_m: float, K_A: float) -> dict:
    """K_A, K_B, beta of Eq. 3.5 for the classical non-dimensional Schnakenberg kinetics u' = a - u + u^2 v,
    v' = b - u^2 v (Murray 2003, Eq. 2.8; steady state u* = a + b, v* = b / (a + b)^2) on the time scale 1/(S K_A).
    Eq. 3.5 with S_A = S_B = S maps onto it by a = lambda u, b = mu v with lambda = sqrt(K_A / K_B),
    mu = sqrt(K_A K_B), tau = S K_A t, hence K_B = 1 / (b^2 K_A^3) and beta = a b K_A^3."""
    return dict(K_A=float(K_A), K_B=float(1.0 / (b_m * b_m * K_A ** 3)), beta=float(a_m * b_m * K_A ** 3))
