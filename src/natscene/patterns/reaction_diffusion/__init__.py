"""Venation-aware reaction-diffusion of Dong 2007 §3.3.2 (Eqs. 3.1, 3.3, 3.4', 3.5): pigment concentrations a, b
on a petal, Schnakenberg kinetics with diffusion along a modified Laplacian that carries the hormones along the
veins from the vein root.

One module per concept:

- :mod:`~natscene.patterns.reaction_diffusion.parameters`: :class:`RDParams` (Tables 3.1-3.3 names), the steady
  state and Jacobian, :func:`schnakenberg_constants` (Murray's non-dimensional kinetics);
- :mod:`~natscene.patterns.reaction_diffusion.laplacian`: the transport I of Eq. 3.1 and the modified Laplacian
  of Eq. 3.4' (a conservative graph Laplacian, mesophyll and vascular parts);
- :mod:`~natscene.patterns.reaction_diffusion.explicit`: **Dong's Eq. 3.5 update**, :func:`eq35_step` (one step),
  and :func:`simulate_explicit` (the paper's per-iteration scheme to a stable pattern);
- :mod:`~natscene.patterns.reaction_diffusion.implicit`: Strang splitting with Anderson acceleration for slow
  kinetics (``scheme: implicit``);
- :mod:`~natscene.patterns.reaction_diffusion.stability`: the explicit update's stable time step;
- :mod:`~natscene.patterns.reaction_diffusion.state`: the initial state, the vein-root hormone supply, the result;
- :mod:`~natscene.patterns.reaction_diffusion.simulate`: :func:`simulate`, the entry point (checks, scheme);
- :mod:`~natscene.patterns.reaction_diffusion.maps`: :func:`normalise`, concentrations to pigment maps;
- :mod:`~natscene.patterns.reaction_diffusion.linear_theory`: Turing analysis (growth rate, fastest wavelength).

The names below are importable from the package itself.
"""
from natscene.patterns.reaction_diffusion.explicit import eq35_step, simulate_explicit
from natscene.patterns.reaction_diffusion.implicit import simulate_implicit
from natscene.patterns.reaction_diffusion.laplacian import laplacian, transport
from natscene.patterns.reaction_diffusion.linear_theory import dominant_wavelength, fastest_wavelength, growth_rate
from natscene.patterns.reaction_diffusion.maps import normalise
from natscene.patterns.reaction_diffusion.parameters import P_MM, P_MV, P_VV, RDParams, schnakenberg_constants
from natscene.patterns.reaction_diffusion.simulate import simulate
from natscene.patterns.reaction_diffusion.stability import amplification, stable_dt
from natscene.patterns.reaction_diffusion.state import RDResult

__all__ = ["P_MM", "P_MV", "P_VV", "RDParams", "RDResult", "amplification", "dominant_wavelength", "eq35_step",
           "fastest_wavelength", "growth_rate", "laplacian", "normalise", "schnakenberg_constants", "simulate",
           "simulate_explicit", "simulate_implicit", "stable_dt", "transport"]
