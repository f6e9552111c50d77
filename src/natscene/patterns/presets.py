"""
Presets of the pattern jobs
===========================

Defines the assembly of a pattern job from its config entry: petal shape, venation, reaction-diffusion parameters
(Dong 2007, Table 3.3 presets for the four patterns of Fig. 3.3) and pigments.

-   :func:`petal_shape`, :func:`venation`, :func:`rd_params`: the petal mask, the vein tree and the
    reaction-diffusion parameters of a config entry.
-   :func:`preset_state`: the constants of a Fig. 3.3 preset beyond Table 3.3 (:data:`FIG_3_3_STATE`) on a grid.
-   :data:`TABLE_3_3`: Table 3.3's rows for Fig. 3.3(b); :data:`REFERENCE_HEIGHT`: the grid height the
    presets' constants are set for.

References
----------
-   Dong, W. (2007). Rendering Algorithms for Natural Scenes. PhD thesis, Université Henri Poincaré - Nancy I.
"""
from __future__ import annotations

import numpy as np

from natscene.config import settings_from_section
from natscene.errors import InputError
from natscene.io import read_mask
from natscene.patterns.reaction_diffusion import RDParams, schnakenberg_constants
from natscene.patterns.venation import parametric_petal, radial_venation_spec, venation_from_nodes

__all__ = ["TABLE_3_3", "REFERENCE_HEIGHT", "FIG_3_3_STATE", "preset_state", "petal_shape", "venation", "rd_params"]

#: Table 3.3 rows for Fig. 3.3(b): S, D_A, D_B, t (the remaining constants are RDParams defaults)
TABLE_3_3 = {
    "centre_spot": dict(S=0.1, D_A=0.15, D_B=0.1, t=2.0),      # 3.3(b)-1
    "radial_stripes": dict(S=0.1, D_A=0.15, D_B=0.1, t=10.0),  # 3.3(b)-2
    "ring": dict(S=0.1, D_A=0.45, D_B=0.1, t=2.0),             # 3.3(b)-3
    "marginal_band": dict(S=0.1, D_A=0.15, D_B=0.5, t=2.0),    # 3.3(b)-4
    "daisy": dict(S=0.05, D_A=0.5, D_B=0.1, t=2.0),            # Figs. 3.5-3.7
    "maple": dict(S=0.1, D_A=0.15, D_B=0.1, t=20.0),           # Fig. 3.9
    "water_lily": dict(S=0.05, D_A=0.25, D_B=0.25, t=5.0),     # Fig. 3.10
}


#: Grid height the kinetics below are given for (Table 3.2: the petunia petal of Fig. 3.3(b) is 549x528).
REFERENCE_HEIGHT = 528

#: The constants Table 3.3 does not list ("determined from experience", §3.3.1), for the four Fig. 3.3 presets:
#: Schnakenberg kinetics in Murray's non-dimensional form (a_m, b_m; see ``schnakenberg_constants``), the rate
#: K_A at REFERENCE_HEIGHT (reaction lengths sqrt(D / (4 S K_A)) scale with the grid, so K_A scales as
#: (REFERENCE_HEIGHT / height)^2), the hormone state held at the vein root (multiples of the steady state a*, b*)
#: and the reach of the non-adjacent vein links of Eq. 3.1c (0 = adjacent cells only; 10 = every dyadic link
#: along a vein, i.e. the veins conduct like wires). Found by a search on a 1/3-scale petunia grid scored on the
#: radial profile and the vein/inter-vein contrast of the pigment A map (docs/stages/patterns.md, Limits): with the
#: Table 3.3 values alone (same constants for all four rows) the four shapes do not separate, because none of the
#: rows is Turing-unstable (Schnakenberg needs D_B / D_A > 3 + 2 sqrt(2) for any K_A, K_B, beta).
FIG_3_3_STATE = {
    "centre_spot": dict(a_m=0.2262, b_m=0.7501, K_A=1.0e-4 / 9, root_supply=(3.38, 1.86), n_dyadic=0),
    "radial_stripes": dict(a_m=0.0423, b_m=0.733, K_A=0.026 / 9, root_supply=(2.14, 2.24), n_dyadic=10),
    "ring": dict(a_m=0.2044, b_m=0.0576, K_A=0.0149 / 36, root_supply=(0.9467, 2.1242), n_dyadic=0),
    "marginal_band": dict(a_m=0.0129, b_m=1.7631, K_A=6.0e-4 / 9, root_supply=(0.69, 0.14), n_dyadic=0),
}


def preset_state(name: str, height: int) -> dict:
    """RDParams entries (beyond Table 3.3) of a Fig. 3.3 preset on a grid of ``height`` rows: K_A, K_B, beta
    from the non-dimensional kinetics with K_A rescaled to the grid, the root supply, the vein-link reach and the
    implicit scheme with dt = 0.5 / (S K_A), Anderson-accelerated over 5 steps."""
    st = FIG_3_3_STATE[name]
    K_A = st["K_A"] * (REFERENCE_HEIGHT / float(height)) ** 2
    S = TABLE_3_3[name]["S"]
    return dict(**schnakenberg_constants(st["a_m"], st["b_m"], K_A), root_supply=tuple(st["root_supply"]),
                n_dyadic=st["n_dyadic"], scheme="implicit", dt=0.5 / (S * K_A), anderson=5, noise=0.0,
                max_steps=400, tol=1e-5)


def petal_shape(spec: dict, size, root) -> np.ndarray:
    w, h = size
    kind = spec.get("kind", "parametric")
    if kind == "file":
        m = read_mask(root(spec["path"]))
        if m.shape != (h, w):
            from skimage.transform import resize
            m = resize(m, (h, w), order=0, anti_aliasing=False)
        return (m > 0.5).astype(np.float32)
    if kind != "parametric":
        raise InputError(f"petal shape kind '{kind}': use 'parametric' or 'file'")
    args = {k: v for k, v in spec.items() if k != "kind"}
    if "base" in args:
        args["base"] = tuple(args["base"])
    return parametric_petal(h, w, **args)


def venation(spec: dict, size):
    w, h = size
    kind = spec.get("kind", "radial")
    vein_px = float(spec.get("vein_px", max(1.0, min(w, h) / 100)))
    if kind == "none":
        return None
    if kind == "radial":
        args = {k: v for k, v in spec.items() if k not in ("kind", "vein_px")}
        if "base" in args:
            args["base"] = tuple(args["base"])
        return venation_from_nodes((h, w), radial_venation_spec(**args), vein_px)
    if kind == "nodes":
        return venation_from_nodes((h, w), spec, vein_px)
    raise InputError(f"venation kind '{kind}': use 'radial', 'nodes' or 'none'")


def rd_params(spec: dict, seed: int, height: int = REFERENCE_HEIGHT, key: str = "patterns.<name>.rd") -> RDParams:
    """RDParams from a config ``rd`` entry (config key ``key``): a preset's values (Table 3.3, plus
    ``preset_state`` for the four Fig. 3.3 presets on a grid of ``height`` rows), overridden by any key given
    explicitly; the keys neither sets take RDParams' defaults (Table 3.1)."""
    spec = dict(spec)
    preset = spec.pop("preset", None)
    base = {}
    if preset is not None:
        if preset not in TABLE_3_3:
            raise InputError(f"reaction-diffusion preset '{preset}': use one of {sorted(TABLE_3_3)}")
        base = dict(TABLE_3_3[preset])
        if preset in FIG_3_3_STATE:
            base.update(preset_state(preset, height))
    base.update(spec)
    base.setdefault("seed", seed)
    return settings_from_section(RDParams, base, key)
