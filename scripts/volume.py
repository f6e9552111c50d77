"""Rule `volume`: generate or import a cloud density grid; write density.vol, density.vdb, previews, meta.yaml."""
from natscene.io import write_exr, write_png, write_yaml
from natscene.runner import run
from natscene.volume.build import build_volume
from natscene.volume.grid import write_vol
from natscene.volume.preview import optical_depth_projections, preview_sheet, rendered_look, side_by_side
from natscene.volume.vdb import write_vdb


def main(snakemake, log):
    name = snakemake.wildcards.volume
    spec = dict(snakemake.params.spec)
    log.info(f"volume '{name}': {spec.get('kind')} {spec.get('resolution') if spec.get('kind') != 'file' else spec.get('path')}")
    vol, stats = build_volume(spec, name, snakemake.input[0] if len(snakemake.input) else None,
                              threads=snakemake.threads,
                              progress=lambda done, n: log.info(f"  slices {done}/{n}") if n >= 256 else None)
    nx, ny, nz = vol.resolution
    log.info(f"grid {nx}x{ny}x{nz}, box {vol.bbox_min.tolist()} .. {vol.bbox_max.tolist()} m, "
             f"fill {stats['fill_fraction']:.1%}, thin edge {stats['thin_edge_fraction']:.1%}, "
             f"extinction_scale {vol.extinction_scale:.4g} /m")
    write_vol(snakemake.output.density, vol.density, vol.bbox_min, vol.bbox_max)
    write_vdb(snakemake.output.vdb, vol.density, vol.bbox_min, vol.bbox_max, metadata={
        "natscene:volume": name, "natscene:kind": str(spec.get("kind")),
        "natscene:extinction_scale": float(vol.extinction_scale)})
    voxel = float(vol.voxel_size[0])
    front, top = optical_depth_projections(vol.density, voxel, vol.extinction_scale)
    write_exr(snakemake.output.preview_exr, side_by_side(front, top), ["tau"], stage="volume",
              attrs={"volume": name, "layout": "front (along z) | top (along y), optical depth at sigma_t = 1",
                     "spec": spec})
    img = rendered_look(vol)
    write_png(snakemake.output.preview_png, preview_sheet(img, front, top), encoded=True)
    write_yaml(snakemake.output.meta, {
        "volume": name, "kind": spec.get("kind"), "resolution": [nx, ny, nz], "units": "m",
        "bbox_min": vol.bbox_min, "bbox_max": vol.bbox_max, "voxel_size": voxel,
        "extinction_scale": vol.extinction_scale, "stats": stats, "spec": spec,
    })


run(snakemake, main)  # noqa: F821 (snakemake is injected by the script directive)
