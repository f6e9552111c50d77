"""A white-furnace control variate for the sky's light of the all-orders transport: the noise it removes.

Under a uniform dome of unit radiance over the whole sphere, a cloud of albedo 1 has unit radiance everywhere, so
the cache's in-scattered light seen at a pixel is the view integral of S = 1: E1 = 1 - T (the gather of a field
of ones, :func:`natscene.scatter.inscatter.gather`). The sky photons can carry a fifth channel, that uniform
dome's weight (1 over the photon's sampling pdf on the upper hemisphere; the ground channel is already a unit
lower hemisphere), at no extra tracing: X = upper + ground, summed over the orders, has the known mean E1, and
Y_c - k_c (X - E1) is an unbiased estimate of channel c's sky light for any k_c (k_c here from the other half of
the photons, a least-squares fit over the cloud pixels). Traces the main job's sky (cumulus x kite, the
precompute's dome, sky lobe and weight window) at the given (extinction 1/m, g) nodes, one cache of the fine
cells for every order:

    .venv/bin/python experiments/sky_control_variate/run.py 0.005,0.9 0.02,0.85 0.08,0.85 after `make run`

Printed per node and channel (R, G, B, the ground, Rec. 709 luminance): k of the two halves, the median / p95
of the two-halves relative standard error without and with the control variate, and the mean of X over E1 (the
identity's check: the cache's bias and the walks cut at max_order show in it).
"""
import argparse
import time
from pathlib import Path

import numpy as np

from natscene.config import load_yaml_config, validate_config
from natscene.geometry import Camera, sun_direction
from natscene.scatter.allorders import Lighting, Scene, photons_for, settings_from_config, standard_error, weight_window
from natscene.scatter.inscatter import cache_fields, gather, weighted_voxel_integrals
from natscene.scatter.photons import SkySource, trace
from natscene.scatter.transport.all_orders import skylight_dome
from natscene.variant import select_variant
from natscene.volume.grid import load_volume

ROOT = Path(__file__).resolve().parents[2]


def uniform_sky(dome, bounds, p_ground):
    """The dome's sky source with a fifth channel: a unit radiance on the upper hemisphere."""
    import drjit as dr

    class Furnace(SkySource):
        channels = 5

        def _pdf_radiance(self, om):
            pdf, rad = super()._pdf_radiance(om)
            return pdf, rad + [dr.select(om.y > 0, 1.0, 0.0)]

    return Furnace(dome, *bounds, p_ground=p_ground)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("nodes", nargs="+", help="extinction,g (1/m, HG g)")
    ap.add_argument("--results", default=str(ROOT / "results"))
    ap.add_argument("--scale", type=float, default=1.0, help="collisions as a multiple of the precompute's budget")
    a = ap.parse_args()
    select_variant(threads=2)
    cfg = load_yaml_config(ROOT / "config/config.yaml")
    validate_config(cfg, ROOT / "workflow/schemas/config.schema.yaml")
    pc, view = cfg["precompute"], cfg["views"]["kite"]
    cam = Camera.from_view(view)
    sun = sun_direction(view["sun"]["azimuth"], view["sun"]["elevation"])
    vol = load_volume(Path(a.results) / "volumes/cumulus")
    st = settings_from_config(pc)
    dome = skylight_dome(sun, pc.get("skylight"))
    scene = Scene(vol, Lighting(np.asarray(sun), dome), st)
    sky = uniform_sky(dome, scene.bounds, st.p_ground)
    if st.sky_lobe_share > 0:
        sky = sky.toward(cam.position, st.sky_lobe_g, st.sky_lobe_share)
    depth = scene.camera_depth_voxels(cam)
    f = scene.factors[0]
    luma = np.array([0.2126, 0.7152, 0.0722])
    for node in a.nodes:
        ext, g = (float(x) for x in node.split(","))
        sigma = ext / vol.extinction_scale
        vint = weighted_voxel_integrals(scene.med, depth, cam.position, sigma * vol.extinction_scale)
        q = scene.weighted_integrals(vint, sigma, f)
        win = weight_window(scene, sky, sigma, g, cam, 7919) if st.importance else None
        n = photons_for(scene, sky, sigma, g, cam, int(st.sky_collisions * a.scale), 10 ** 9, 7919,
                        most=int(st.sky_photons_max * a.scale), window=win)
        t0 = time.perf_counter()
        halves = [trace(scene.med, scene.grid, sky, sigma, g, cam.position, n // 2, st.sky_bands, caches=((f, None),),
                        seed=2 * 7919 + h, max_order=st.max_order, k_min=1, camera_depth=depth,
                        tally_rate=st.tally_rate, window=win, split_max=st.split_max,
                        similarity_order=st.similarity_order) for h in range(2)]
        # every order at beta 1: the channels' sums over the bands, per half
        fields = [cache_fields(h.numerators[0].sum(1), q) for h in halves]
        Y = np.stack([gather(scene.med, cam, sigma, c, d, f, st.step_voxels, st.supersample, scene.bounds)
                      for c, d in fields]).astype(np.float64)                       # (2, 5, H, W)
        ones, den = cache_fields(q[None], q)
        E1 = gather(scene.med, cam, sigma, ones, den, f, st.step_voxels, st.supersample, scene.bounds)[0]
        print(f"extinction {ext:g} /m g {g:g}: {n} photons, {sum(h.collisions for h in halves)} collisions, "
              f"{time.perf_counter() - t0:.1f} s", flush=True)
        X = Y[:, 3] + Y[:, 4]
        foot = E1 > 0.05
        print(f"  mean X / E1 over the cloud {X.mean(0)[foot].sum() / E1[foot].sum():.4f}")
        for name, y in (("R", Y[:, 0]), ("G", Y[:, 1]), ("B", Y[:, 2]), ("ground", Y[:, 3]),
                        ("luminance", np.tensordot(luma, Y[:, :3], (0, 1)))):
            d = X - E1
            k = [float((y[1 - h] * d[1 - h])[foot].sum() / (d[1 - h] ** 2)[foot].sum()) for h in range(2)]
            cv = np.stack([y[h] - k[h] * d[h] for h in range(2)])
            row = []
            for z in (y, cv):
                m = z.mean(0)
                ok = foot & (m > 0)
                r = standard_error(z[0], z[1])[ok] / m[ok]
                row.append(f"{np.median(r):.3f} / {np.percentile(r, 95):.3f}")
            print(f"  {name:9s} k {k[0]:.3f} {k[1]:.3f}: plain {row[0]}, control variate {row[1]}")


if __name__ == "__main__":
    main()
