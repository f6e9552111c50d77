"""How far a diffusion jump could carry a photon in the main job's clouds: the spheres that fit inside them.

A route weighed for issue 39's thick clouds: shell tracing (Moon, Walter & Marschner 2007; Müller et al. 2016)
moves a photon deep inside a homogeneous region to the surface of the largest sphere around it in one step, with a
precomputed distribution of the collisions it would have made; in the similar medium of first-order similarity
(extinction (1 - g) mu_t, isotropic) a sphere of radius R* transport mean free paths saves about R*^2 / 2
collisions per jump, so the route pays where R* is several. For every voxel of the main job's volumes
(results/volumes/<name>, after ``make run``) the radius of the largest sphere around it that stays inside the
cloud (density >= a threshold everywhere; the sphere's density then still varies) or inside one density band of
+-5 % or +-10 % (nearly homogeneous), in transport mean free paths at an extinction and g:

    .venv/bin/python experiments/shell_radius/run.py

Printed and written to results/experiments/shell_radius.json, per volume, sphere kind, extinction and g: the
median and p90 of R* over the cloud's voxels (density > 0.2) and the share of the collisions (density-weighted
voxels) where R* >= 2 and >= 4.
"""
import json
from pathlib import Path

import numpy as np
from scipy import ndimage

from natscene.volume.grid import load_volume

ROOT = Path(__file__).resolve().parents[2]
CASES = [(0.0244, 0.7), (0.0244, 0.85), (0.08, 0.7), (0.08, 0.85)]     # extinction /m (the kite fit's; thick), g


def inside_radius(density: np.ndarray, voxel: float, threshold: float) -> tuple[np.ndarray, np.ndarray]:
    """(radius in metres of the largest sphere around each voxel with density >= threshold, the density the sphere
    is taken at: the voxel's own)."""
    return ndimage.distance_transform_edt(density >= threshold) * voxel, density


def band_radius(density: np.ndarray, voxel: float, delta: float) -> tuple[np.ndarray, np.ndarray]:
    """(radius in metres of the largest sphere around each voxel inside one density band [L, L (1 + delta)), two
    band sets offset by half a band, the larger sphere kept; the band's geometric middle density)."""
    best, level = np.zeros_like(density), np.zeros_like(density)
    for offset in (0.0, 0.5):
        band = np.floor(-np.log(np.maximum(density, 1e-6)) / np.log1p(delta) + offset)
        for b in np.unique(band[density > 0.2]):
            m = band == b
            r = ndimage.distance_transform_edt(m) * voxel
            better = m & (r > best)
            best[better] = r[better]
            level[better] = (1 + delta) ** (offset - b) / np.sqrt(1 + delta)
    return best, level


def main():
    out = {}
    for name in ("cumulus", "cumulonimbus"):
        vol = load_volume(ROOT / "results" / "volumes" / name)
        d = vol.density.astype(np.float32)
        voxel = float(np.asarray(vol.voxel_size).ravel()[0])
        cloud = d > 0.2
        weight = d[cloud] / d[cloud].sum()
        kinds = {"inside density 0.1": inside_radius(d, voxel, 0.1), "inside density 0.3": inside_radius(d, voxel, 0.3),
                 "band 5 %": band_radius(d, voxel, 0.1), "band 10 %": band_radius(d, voxel, 0.2)}
        for kind, (radius, rho) in kinds.items():
            for ext, g in CASES:
                r = (radius * ext * rho * (1 - g))[cloud]
                row = {"median": round(float(np.median(r)), 2), "p90": round(float(np.percentile(r, 90)), 2),
                       "collisions_R_ge_2": round(float((weight * (r >= 2)).sum()), 3),
                       "collisions_R_ge_4": round(float((weight * (r >= 4)).sum()), 3)}
                out[f"{name}, {kind}, {ext:g}/m, g {g:g}"] = row
                print(f"{name}, {kind}, {ext:g}/m, g {g:g}: {row}", flush=True)
    dest = ROOT / "results" / "experiments" / "shell_radius.json"
    dest.parent.mkdir(parents=True, exist_ok=True)
    dest.write_text(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
