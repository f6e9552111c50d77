"""Plane-parallel slabs against adding-doubling (iadpython: van de Hulst's method in Prahl's implementation).

A homogeneous slab of optical thickness tau (g, albedo beta, index-matched boundaries). Adding-doubling gives
the azimuth-averaged reflection and transmission functions R(mu, mu0), T(mu, mu0) (symmetric: reciprocity) and
from them the reflectance and transmittance (fluxes) for a beam at mu0. Three comparisons, within 2 %:

- isotropic scattering (g = 0), radiance: where the view or the sun is along the normal the field has no
  azimuthal dependence, so the rendered radiance compares with E mu0 R(mu, mu0) / pi above and
  E mu0 T(mu, mu0) / pi below (the unscattered beam excluded): the sun at 0 deg seen 30 deg from the zenith /
  nadir, the sun at 60 deg seen along the normal;
- g = 0.85, the sun at 0 deg, reflectance and diffuse transmittance: the rendered radiance integrated over each
  hemisphere (12-point Gauss-Legendre in the view's zenith angle; the field is symmetric about the normal). The
  transmitted light's forward peak is a few degrees wide: 12 points in cos(zenith) take 2.1 % too little of the
  singly scattered transmittance at tau 1 (2.7 % at tau 10), 12 in the angle within 0.01 % (the closed form's
  integral by adaptive quadrature).
  Adding-doubling's radiances at g = 0.85 move by up to 8 % between 16, 20 and 24 quadrature angles (its
  delta-M phase function; the transmitted radiance at tau 1 by 60 %), its fluxes by 0.01 %: fluxes are the
  reference here;
- g = 0.85, the sun at 60 deg, by reciprocity: the reflectance (transmittance) for a beam at mu0 equals the
  radiance reflected (transmitted) toward mu0 under a uniform sky of unit radiance above the slab, which the
  transport's skylight renders.

The all-orders transport traces one photon run per (tau, g, light, view) and composes the three albedos in
closed form (orders >= 2 of the sun and >= 1 of the sky in bands; the sun's order 1 ray-marched), as the
precompute does (``natscene.scatter.reference_scene.slab_sun_radiance``). The slab is finite (12 times wider than
thick, or 5 transport mean free paths where that is more: ``slab_width``; voxel layers of at most 2 mean free
paths, as a real cloud's); the sun-lit views see 4.2 x 4.2 thicknesses of
its middle in 16 x 16 pixels (``SLAB_VIEW``: one run scatters by 0.4 % at tau 10, against 1 % in 8 x 8 pixels over
2.1 thicknesses; ``experiments/camera_depth/run.py``), the skylit ones 2.1 x 2.1 in 8 x 8 (their footprint at 60
degrees from the normal is twice as long) with four runs. Values below 1e-3 of the incident scale are compared in
absolute terms (2e-5): the photons cannot resolve a relative 2 % there.
"""
from dataclasses import replace

import numpy as np
import pytest

import natscene  # noqa: F401
from natscene.config import default_settings
from natscene.scatter.allorders import AllOrdersSettings, Lighting, Scene, view_images
from natscene.scatter.bands import channel_weights
from natscene.scatter.reference_scene import (adding_doubling, adding_doubling_flux, comparison_slab, slab_camera,
                                              slab_sun, slab_sun_radiance, slab_width)
from natscene.scatter.skylight import uniform_dome

TAUS = (1.0, 10.0, 100.0, 300.0)
GS = (0.0, 0.85)
BETAS = (0.99, 0.9999, 1.0)
SUNS = {0: (1.0, np.cos(np.radians(30))), 60: (0.5, 1.0)}          # sun zenith -> (mu0, mu of the view)
SETTINGS = default_settings(AllOrdersSettings, sun_collisions=4_000_000, sky_collisions=0, fine_voxels=1,
                            coarse_voxels=1, camera_lobe=0.0, importance=False)
FLUX = default_settings(AllOrdersSettings, sun_collisions=1_500_000, sky_collisions=0, fine_voxels=1, coarse_voxels=1,
                        camera_lobe=0.0, importance=False)     # 12 views per flux: fewer photons per view
DOME = default_settings(AllOrdersSettings, sun_collisions=20_000, sky_collisions=4_000_000, fine_voxels=1,
                        coarse_voxels=1, camera_lobe=0.0, importance=False, sky_lobe_share=0.0)
_X, _W = np.polynomial.legendre.leggauss(12)
_THETA = (_X + 1) * np.pi / 4                       # Gauss-Legendre in the view's zenith angle, on [0, 90 deg]:
GL_MU, GL_W = np.cos(_THETA), _W * np.pi / 4 * np.sin(_THETA)     # int f dmu = int f sin(theta) dtheta
#: the flux views' field (degrees) and pixels: at the grazing ones (mu down to 0.014) the footprint is the slab's
#: whole width, and a wider view sees its side faces (tau 1 in a slab 12 wide, 12 points in cos(zenith): 0.885 of
#: adding-doubling at 0.6 degrees, 0.97 at 0.3)
FLUX_VIEW = (0.3, 8)
ABS_FLOOR = 1e-3


def flux_settings(tau: float):
    """FLUX, with up to 4 times the collisions where the slab is wider than 12 (``slab_width``: tau 1 at g 0.85,
    33 wide, spreads the photons over 7.7 times the area)."""
    area = (slab_width(tau, 0.85) / 12.0) ** 2
    return FLUX if area <= 1 else replace(FLUX, sun_collisions=int(FLUX.sun_collisions * min(area, 4.0)))


def dome_radiance(tau: float, g: float, mu: float, above: bool, seeds) -> dict:
    """L / L_sky of the transport's skylight (orders >= 1) under a uniform sky above the slab, per beta: the mean
    of runs with ``seeds``. The 8 x 8 pixels see a small patch of the slab, where one run of the higher orders'
    photons scatters by about 3 % (eight runs at tau 10: 0.97-1.05 of adding-doubling). The slab stays 12 wide
    (``slab_width`` would make it 33 at tau 1): there the sky's photons spread over 7.7 times the area, and four runs
    of the reflectance at tau 1 read 0.973-0.977 of adding-doubling with seeds 31-34, 0.999-1.004 with 35-38
    (0.9995-1.0065 at 12 wide)."""
    vol = comparison_slab(tau)
    cam = slab_camera(mu, above, res=8)
    scene = Scene(vol, Lighting(slab_sun(0.0), uniform_dome(1.0)), DOME)
    out = {b: 0.0 for b in BETAS}
    for seed in seeds:
        vi = view_images(scene, cam, 1.0, g, seed=seed)
        for b in BETAS:
            out[b] += float(np.tensordot(channel_weights(DOME.sky_bands, vi.sky_orders, b)[0, 0], vi.sky[0], 1).mean()
                            ) / len(seeds)
    return out


def _close(a: float, b: float) -> bool:
    if b < ABS_FLOOR:
        return abs(a - b) <= 2e-5
    return abs(a / b - 1) <= 0.02


def _check(got: dict, refs: dict, label: str):
    bad = {}
    for beta in BETAS:
        print(f"{label} beta {beta}: ours {got[beta]:.5g} adding-doubling {refs[beta]:.5g} "
              f"ratio {got[beta] / max(refs[beta], 1e-30):.4f}")
        if not _close(got[beta], refs[beta]):
            bad[beta] = (round(got[beta], 6), round(refs[beta], 6))
    assert not bad, bad


# What the all-orders transport misses today (issue 39; the measured ratios are in docs/stages/precompute.md,
# "Thick clouds against independent references"): strict xfail, so a change that makes a case pass fails here until
# its entry goes; marked `gaps` (a fifth of the suite's time): `make test` leaves them out, `make test-gaps` runs them.
NOISE = ("the light that crosses the slab comes from few photons at this budget (131,072: at tau 100 about one in 60 "
         "crosses, at 300 one in 150, a seventh of them under the view): one run scatters by 10-20 %")
BAND_MIX = ("beta < 1: one order distribution per band for the whole view, where the grazing views of the flux "
            "integral see the finite slab's ends beside its middle, whose transmitted light walks far longer")
FACE = ("the cache's interpolation holds a face cell's mean over the half cell at the face (a field rising linearly "
        "from the face: +0.8 % in layers of 0.625 mean free paths, +3 % in layers of 2; test_scatter)")
SKY_NOISE = ("the sky-lit transmitted light comes from few photons in the 8 x 8 pixels' patch: one run scatters by 7 % "
             "at tau 10 (0.91-1.12 over six seeds) and by 20-30 % at tau 100 (0.72-1.45)")
GAPS = {
    ("radiance", 10.0, 60, False): "2.3-2.8 % high (the sun at 0 degrees: 0.995): " + FACE + ", and 2 % not located",
    ("radiance", 100.0, 0, True): "2.3-2.5 % high at beta >= 0.9999: " + FACE,
    ("radiance", 100.0, 0, False): "1.06 at beta >= 0.9999: " + NOISE,
    ("radiance", 100.0, 60, False): "0.88-0.89 at beta >= 0.9999: " + NOISE,
    ("radiance", 300.0, 0, False): "1.16 at beta 1, 1.11 at 0.9999: " + NOISE,
    ("radiance", 300.0, 60, False): "1.06 at beta 1, 1.33 at 0.9999: " + NOISE + " (the orders' tail, where beta^k "
                                    "falls, too)",
    ("normal", 100.0, False): "1.31 times at beta 0.99 (beta >= 0.9999: 0.977-0.980): " + BAND_MIX,
    ("normal", 300.0, True): "2.4 % low at beta 0.99 (0.992 at beta >= 0.9999): not located",
    ("normal", 300.0, False): "1.20-1.25 at beta >= 0.9999: " + NOISE + "; beta 0.99: 5e-5 for 1e-9: " + BAND_MIX,
    ("oblique", 10.0, False): "6.1-6.3 % high: " + SKY_NOISE,
    ("oblique", 100.0, False): "1.12 at beta >= 0.9999: " + SKY_NOISE + "; beta 0.99: 0.964 (2.3e-5 below, the "
                               "floor 2e-5)",
    ("oblique", 300.0, True): "2.3-2.4 % high (1.001-1.009 with the walks cut at 4096 orders): " + FACE,
    ("oblique", 300.0, False): "0.88 at beta 1, 0.84 at 0.9999: " + SKY_NOISE,
}


@pytest.mark.parametrize("g", GS)
def test_adding_doubling_conserves_energy(g):
    """The reference itself: at albedo 1 the slab's reflectance, diffuse transmittance and unscattered beam add up
    to 1 (iadpython at 32 quadrature angles lost 0.8 % at tau 100 and 1.6 % at 300, all of it from the
    transmittance, which read 0.84 and 0.28 of the true one: ``QUADRATURE_ANGLES``)."""
    for tau in TAUS:
        for mu0 in (1.0, 0.5):
            r, t = adding_doubling_flux(tau, g, 1.0, mu0)
            assert abs(r + t + np.exp(-tau / mu0) - 1.0) < 1e-5, (tau, mu0, r, t)


def _cases(kind: str, keys) -> list:
    return [pytest.param(*k, marks=[pytest.mark.xfail(strict=True, reason=GAPS[(kind, *k)]), pytest.mark.gaps])
            if (kind, *k) in GAPS else k for k in keys]


@pytest.mark.parametrize("tau, zenith, above",
                         _cases("radiance", [(t, z, a) for t in TAUS for z in SUNS for a in (True, False)]))
def test_isotropic_slab_radiance(tau, zenith, above):
    mu0, mu = SUNS[zenith]
    got = slab_sun_radiance(tau, 0.0, zenith, mu, above, 11, SETTINGS, BETAS)
    refs = {b: adding_doubling(tau, 0.0, b, mu0, mu)[0 if above else 1] for b in BETAS}
    _check(got, refs, f"g 0 tau {tau:g} sun {zenith} {'R' if above else 'T'}")


@pytest.mark.parametrize("tau, above", _cases("normal", [(t, a) for t in TAUS for a in (True, False)]))
def test_forward_scattering_slab_flux_normal_sun(tau, above):
    got = {b: 0.0 for b in BETAS}
    for k, (mu, w) in enumerate(zip(GL_MU, GL_W)):
        L = slab_sun_radiance(tau, 0.85, 0.0, float(mu), above, 21 + k, flux_settings(tau), BETAS, FLUX_VIEW)
        for b in BETAS:
            got[b] += 2 * w * mu * L[b]
    refs = {b: adding_doubling_flux(tau, 0.85, b, 1.0)[0 if above else 1] for b in BETAS}
    _check(got, refs, f"g 0.85 tau {tau:g} sun 0 {'R' if above else 'T_diffuse'} flux")


@pytest.mark.parametrize("tau, above", _cases("oblique", [(t, a) for t in TAUS for a in (True, False)]))
def test_forward_scattering_slab_flux_oblique_sun(tau, above):
    got = dome_radiance(tau, 0.85, 0.5, above, seeds=(31, 32, 33, 34))
    refs = {b: adding_doubling_flux(tau, 0.85, b, 0.5)[0 if above else 1] for b in BETAS}
    _check(got, refs, f"g 0.85 tau {tau:g} sun 60 {'R' if above else 'T_diffuse'} flux (reciprocity)")
