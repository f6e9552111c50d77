"""
One frame of a shot
===================

Defines one frame of a shot: the forward renderer at the frame's camera, sun and parameters, the denoiser, and
the ``mie_blend`` shading mode (Reimschuessel 2011, Ch. 3, on top of the project's cloud transport):

-   :func:`render_shot_frame`: render one frame of a shot.
-   :func:`mie_terms`: the thesis' final pass for the Mie and the HG solution of the frame's sun.
-   :func:`mie_ratio`, :data:`EPS_REL`, :func:`unscattered`, :func:`apply_ratio`: the Mie blend below.

Order of work (:func:`render_shot_frame`):

1. the frame camera at the shot's resolution (vertical field of view kept, :func:`~natscene.keyframes.shot.frame_camera`),
   the sky behind it (:mod:`natscene.keyframes.sky`);
2. the raw frame ``L`` = :func:`natscene.scatter.render.render` (HG phase function, the renderer's transport),
   with its components;
3. the cloud's feature images (:mod:`natscene.denoise.features`) and, with ``denoise: oidn``, the denoised
   frame (:func:`natscene.denoise.oidn.denoise_frame`);
4. ``phase: mie_blend``: the Mie/HG ratio of the thesis' final pass for this sun, applied to the light the
   cloud scatters (below), to the raw and to the denoised frame.

**The Mie blend.** Rule ``point_scatter`` solves the point-to-point passes once per volume and sun, with the
droplet population's Mie table (``mie``) and with a Henyey-Greenstein table of the same asymmetry (``hg``): the
thesis' like-for-like pair. Marching both (:func:`natscene.mie.march.march_terms`, Eqs. 6-8) at the frame's
camera gives the cloud radiance per unit sunlight M_mie and M_hg; their ratio

    r = (M_mie + eps) / (M_hg + eps)         (per channel; eps = ``EPS_REL`` x the median M_hg of the cloud)

is what changing the droplets' phase function from HG to Mie does to every pixel: the diffraction peak (the
silver lining around a sun behind a cloud edge, r >> 1), the glory and the fogbow, and little elsewhere
(r ~ 1). The frame keeps its own transport and level (fitted parameters, all the renderer's orders, its sky
light) and takes the Mie angular structure from the ratio:

    L_mie = B + r (L - B),   B = T L_sky e^{-kappa_a t_c} + (1 - e^{-kappa_a t_c}) L_sky,

B the part of the frame that the cloud did not scatter (the sky through and around the cloud, Eqs. 3 and 9),
from the renderer's components ``L_b`` = T L_sky and ``t_c``. eps keeps r -> 1 where neither marcher sees
cloud (the cloud's faint fringe) instead of dividing noise by noise. The frame's unscattered part and the
HG frame (``hg.*`` channels) are kept, so every mie_blend frame carries its HG twin.

Limits: the solution is solved at ``mie.solver.sigma_t`` and the Mie table's asymmetry, not at the frame's
sigma_t and g; the ratio is a relative correction, so it is exact in the frame's level but its angular
structure is that of a cloud of the solver's optical thickness. The ratio multiplies the cloud's skylight /
ambient share too (the marcher's sun-only ratio is ~1 where that share matters, away from the sun).

References
----------
-   Dobashi, Y., Iwasaki, W., Ono, A., Yamamoto, T., Yue, Y., & Nishita, T. (2012). An inverse problem approach
    for automatically adjusting the parameters for rendering clouds using photographs. ACM Transactions on
    Graphics, 31(6).
-   Reimschuessel, C. A. (2011). Rendering Realistic Cloud Effects for Computer Generated Films. MSc thesis,
    Brigham Young University.
"""
from __future__ import annotations

import numpy as np

from natscene.errors import InputError

__all__ = ["EPS_REL", "mie_ratio", "unscattered", "apply_ratio", "mie_terms", "render_shot_frame"]

#: eps of the Mie/HG ratio relative to the median M_hg over the cloud (:func:`mie_ratio`): not a config key (no
#: schema holds it); this is its one home.
EPS_REL = 0.02


def mie_ratio(m_mie: np.ndarray, m_hg: np.ndarray, transmittance: np.ndarray | None = None,
              eps_rel: float = EPS_REL) -> np.ndarray:
    """r = (M_mie + eps) / (M_hg + eps) per channel (H, W, 3); eps = eps_rel x the median of M_hg over the
    cloud (marcher transmittance < 0.5, else over all pixels with M_hg > 0)."""
    m_mie = np.asarray(m_mie, np.float64)
    m_hg = np.asarray(m_hg, np.float64)
    if m_mie.shape != m_hg.shape:
        raise ValueError(f"mie_ratio: shapes {m_mie.shape} and {m_hg.shape} differ")
    cloud = (np.asarray(transmittance) < 0.5) if transmittance is not None else None
    eps = np.zeros(m_hg.shape[-1])
    for c in range(m_hg.shape[-1]):
        ch = m_hg[..., c]
        sel = ch[cloud] if cloud is not None and cloud.any() else ch[ch > 0]
        eps[c] = eps_rel * float(np.median(sel)) if sel.size else 1.0
        eps[c] = max(eps[c], 1e-12)
    return ((m_mie + eps) / (m_hg + eps)).astype(np.float32)


def unscattered(L_b: np.ndarray, t_c: np.ndarray, kappa_a, sky: np.ndarray) -> np.ndarray:
    """B = L_b e^{-kappa_a t_c} + (1 - e^{-kappa_a t_c}) L_sky (Eq. 3 with the cloud's own light removed)."""
    e_a = np.exp(-np.asarray(kappa_a, np.float64).reshape(1, 1, -1) * np.asarray(t_c, np.float64)[..., None])
    return (np.asarray(L_b, np.float64) * e_a + (1.0 - e_a) * np.asarray(sky, np.float64)).astype(np.float32)


def apply_ratio(frame: np.ndarray, background: np.ndarray, ratio: np.ndarray) -> np.ndarray:
    """B + r (L - B), clipped at 0."""
    f = np.asarray(frame, np.float64)
    b = np.asarray(background, np.float64)
    return np.clip(b + np.asarray(ratio, np.float64) * (f - b), 0.0, None).astype(np.float32)


def mie_terms(volume, camera, mie: dict) -> dict:
    """The thesis' final pass (Eqs. 6-8) for the Mie and the HG solution of this sun at ``camera``:
    {M_mie, M_hg (H, W, 3) cloud radiance per unit sun, T (H, W), ratio}. ``mie``: {solution_mie,
    solution_hg, table_mie, table_hg, render (the `mie.render` settings, or its march keys)}; the ratio's eps is
    :data:`EPS_REL`."""
    from natscene.mie.march import march_terms, mie_render

    r = mie_render(mie.get("render"))
    s_m, s_h = mie["solution_mie"], mie["solution_hg"]
    if float(np.dot(s_m.points.sun_dir, s_h.points.sun_dir)) < 1 - 1e-9:
        raise InputError("mie_blend: the Mie and HG point-to-point solutions were solved for different suns")
    m_mie, T = march_terms(volume, camera, s_m, mie["table_mie"], r)
    m_hg, _ = march_terms(volume, camera, s_h, mie["table_hg"], r)
    return {"M_mie": m_mie, "M_hg": m_hg, "T": T,
            "ratio": mie_ratio(m_mie, m_hg, T)}


def render_shot_frame(volume, state: dict, shot: dict, mie: dict | None = None, denoiser=None,
                      log=None) -> dict:
    """Render one frame of a shot.

    ``state``: the frame's state (rule ``interpolate``: params, sun, camera); ``shot``: the validated
    ``shots.<name>`` entry (resolution, render, sky, denoise, denoiser, phase); ``mie``: for ``phase:
    mie_blend``, see :func:`mie_terms`; ``denoiser``: a callable (color, albedo, normal) -> color
    (:class:`natscene.denoise.oidn.OIDN`) when ``denoise: oidn``.

    Returns {final, raw (H, W, 3): the frame after / before the denoiser; hg_final, hg_raw (mie_blend: the
    HG twin); features {opacity, coverage, albedo, normal}; ratio (mie_blend); camera; timings; photons (the
    all-orders photon and collision counts, None for dobashi)}.
    """
    import time

    from natscene.denoise.features import frame_features
    from natscene.denoise.oidn import denoise_frame
    from natscene.keyframes.shot import frame_camera
    from natscene.keyframes.sky import sky_image
    from natscene.scatter.render import render
    from natscene.sky.daylight import skylight

    log = log or (lambda msg: None)
    timings = {}
    camera = frame_camera(state["camera"], shot["resolution"])
    sun = np.asarray(state["sun"]["direction"], np.float64)
    p = {k: np.asarray(v, np.float64) for k, v in state["params"].items()}
    t = time.perf_counter()
    sky_settings = skylight(shot["sky"])
    sky = sky_image(camera, sun, sky_settings)
    timings["sky_s"] = time.perf_counter() - t
    t = time.perf_counter()
    raw, comp = render(volume, camera, sun, p, sky, shot["render"], return_components=True, sky_settings=sky_settings)
    timings["render_s"] = time.perf_counter() - t
    t = time.perf_counter()
    feats = frame_features(volume, camera, p, sky, shot["denoiser"])
    timings["features_s"] = time.perf_counter() - t
    final = raw
    if shot["denoise"] == "oidn":
        if denoiser is None:
            raise ValueError("render_shot_frame: denoise is 'oidn' but no denoiser was given")
        t = time.perf_counter()
        final = denoise_frame(raw, feats, denoiser)
        timings["denoise_s"] = time.perf_counter() - t
    out = {"raw": raw, "final": final, "features": feats, "camera": camera, "timings": timings,
           "photons": comp.get("photons")}
    if shot["phase"] == "mie_blend":
        if mie is None:
            raise ValueError("render_shot_frame: phase is 'mie_blend' but no Mie solutions were given")
        t = time.perf_counter()
        terms = mie_terms(volume, camera, mie)
        B = unscattered(comp["L_b"], comp["t_c"], p["kappa_a"], sky)
        out.update(hg_raw=raw, hg_final=final, ratio=terms["ratio"],
                   raw=apply_ratio(raw, B, terms["ratio"]), final=apply_ratio(final, B, terms["ratio"]))
        timings["mie_s"] = time.perf_counter() - t
        cloud = terms["T"] < 0.5
        if cloud.any():
            log(f"mie_blend: Mie/HG ratio over the cloud: median {float(np.median(terms['ratio'][cloud])):.3f}, "
                f"p99 {float(np.percentile(terms['ratio'][cloud], 99)):.2f}")
    return out
