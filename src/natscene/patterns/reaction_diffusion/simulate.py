"""
Reaction-diffusion on a petal
=============================

Defines the entry point of Dong's (2007) reaction-diffusion on a petal (§3.3.2, Eq. 3.5):

-   :func:`simulate`: check the parameters, then run the scheme they ask for:
    :func:`~natscene.patterns.reaction_diffusion.explicit.simulate_explicit` (the paper's per-iteration update,
    :func:`~natscene.patterns.reaction_diffusion.explicit.eq35_step`) or
    :func:`~natscene.patterns.reaction_diffusion.implicit.simulate_implicit` (Strang splitting).

References
----------
-   Dong, W. (2007). Rendering Algorithms for Natural Scenes. PhD thesis, Université Henri Poincaré - Nancy I.
"""
from __future__ import annotations

import numpy as np

from natscene.errors import InputError
from natscene.patterns.reaction_diffusion.explicit import simulate_explicit
from natscene.patterns.reaction_diffusion.implicit import simulate_implicit
from natscene.patterns.reaction_diffusion.parameters import RDParams
from natscene.patterns.reaction_diffusion.state import RDResult
from natscene.patterns.venation import Venation

__all__ = ["simulate"]


def simulate(mask: np.ndarray, venation: Venation | None, p: RDParams, init=None, logger=None,
             progress_every: int = 500) -> RDResult:
    """Run Eq. 3.5 on the petal ``mask`` until stable (or ``max_steps``). ``init``: optional (a, b) maps."""
    mask = np.asarray(mask, np.float32)
    if mask.ndim != 2 or (mask > 0.5).sum() < 4:
        raise InputError("petal mask must be a 2-D image with at least 4 petal pixels (white = petal)")
    for name in ("S", "D_A", "D_B", "K_A", "K_B", "dt"):
        if not getattr(p, name) > 0:
            raise InputError(f"reaction-diffusion parameter '{name}' must be > 0 (got {getattr(p, name)})")
    if p.scheme not in ("explicit", "implicit"):
        raise InputError(f"reaction-diffusion parameter 'scheme' must be 'explicit' or 'implicit' (got {p.scheme!r})")
    if p.scheme == "implicit":
        return simulate_implicit(mask, venation, p, init, logger, progress_every)
    return simulate_explicit(mask, venation, p, init, logger, progress_every)
