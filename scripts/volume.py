"""Rule `volume`: generate or import a cloud density grid; write density.vol, previews and meta.yaml."""
from natscene.io import write_exr, write_png, write_yaml
from natscene.runner import run
from natscene.volume.build import build_volume
from natscene.volume.grid import write_vol
from natscene.volume.preview import lit_side_by_side, optical_depth_projections, side_by_side


def main(snakemake, log):
    name = snakemake.wildcards.volume
    spec = dict(snakemake.params.spec)
    log.info(f"volume '{name}': {spec.get('kind')} {spec.get('resolution') if spec.get('kind') != 'file' else spec.get('path')}")
    vol, stats = build_volume(spec, name, snakemake.input[0] if len(snakemake.input) else None)
    nx, ny, nz = vol.resolution
    log.info(f"grid {nx}x{ny}x{nz}, fill {stats['fill_fraction']:.1%}, extinction_scale {vol.extinction_scale:.4g}")
    write_vol(snakemake.output.density, vol.density, vol.bbox_min, vol.bbox_max)
    front, top = optical_depth_projections(vol.density, float(vol.voxel_size[0]), vol.extinction_scale)
    tau = side_by_side(front, top)
    write_exr(snakemake.output.preview_exr, tau, ["tau"], stage="volume",
              attrs={"volume": name, "layout": "front (along z) | top (along y), optical depth at sigma_t = 1",
                     "spec": spec})
    write_png(snakemake.output.preview_png, lit_side_by_side(vol.density, float(vol.voxel_size[0]), vol.extinction_scale),
              exposure=1.0)
    write_yaml(snakemake.output.meta, {
        "volume": name, "kind": spec.get("kind"), "resolution": [nx, ny, nz],
        "bbox_min": vol.bbox_min, "bbox_max": vol.bbox_max, "voxel_size": float(vol.voxel_size[0]),
        "extinction_scale": vol.extinction_scale, "stats": stats, "spec": spec,
    })


run(snakemake, main)  # noqa: F821 (snakemake is injected by the script directive)
