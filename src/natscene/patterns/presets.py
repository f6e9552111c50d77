"""Assembling a pattern job from its config entry: petal shape, venation, reaction-diffusion parameters
(Dong 2007 Table 3.3 presets for the four patterns of Fig. 3.3) and pigments."""
from __future__ import annotations

import numpy as np

from natscene.io import InputError, read_mask
from natscene.patterns.reaction_diffusion import RDParams
from natscene.patterns.venation import parametric_petal, radial_venation_spec, venation_from_nodes

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


def rd_params(spec: dict, seed: int) -> RDParams:
    spec = dict(spec)
    preset = spec.pop("preset", None)
    base = {}
    if preset is not None:
        if preset not in TABLE_3_3:
            raise InputError(f"reaction-diffusion preset '{preset}': use one of {sorted(TABLE_3_3)}")
        base = dict(TABLE_3_3[preset])
    base.update(spec)
    base.setdefault("seed", seed)
    return RDParams.from_dict(base)
