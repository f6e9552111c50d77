"""Rule `precompute`: Dobashi 2012 §4.3 tables for one (volume, view), for the configured transport."""
from pathlib import Path

from natscene.geometry import Camera, sun_direction
from natscene.io import write_png
from natscene.runner import run


def main(snakemake, log):
    from natscene.scatter.allorders import settings_from_config
    from natscene.scatter.contact import contact_sheet
    from natscene.scatter.tables import precompute, save_tables
    from natscene.scatter.transport import get as get_transport
    from natscene.variant import select_variant
    from natscene.volume.grid import load_volume

    cfg = snakemake.params.settings
    view = snakemake.params.view
    variant = select_variant(threads=snakemake.threads)
    volume = load_volume(Path(snakemake.input.density).parent)
    camera = Camera.from_view(view)
    sun = sun_direction(view["sun"]["azimuth"], view["sun"]["elevation"])
    transport = cfg["transport"]
    settings = settings_from_config(cfg)
    detail = get_transport(transport).describe(cfg)
    log.info(f"precompute {snakemake.wildcards.volume} x {snakemake.wildcards.view}: {camera.width}x{camera.height}, "
             f"{len(cfg['extinction'])} extinctions x {len(cfg['g'])} g, transport {transport}, {detail} ({variant})")
    tables = precompute(volume, camera, sun, extinctions=cfg["extinction"], gs=cfg["g"], n_m=cfg["n_m"], spp=cfg["spp"],
                        seed=cfg["seed"], step_voxels=cfg["step_voxels"], supersample=cfg["supersample"],
                        rho_threshold=cfg["rho_threshold"], batch_spp=cfg["batch_spp"], log=log.info,
                        transport=transport, all_orders=settings, skylight=cfg.get("skylight"))
    out = Path(snakemake.output[0]).parent   # multiext outputs (cacheable rule): all in one folder
    meta = save_tables(out, tables, {"volume": snakemake.wildcards.volume, "view_name": snakemake.wildcards.view,
                                     "view": view, "variant": variant})
    write_png(out / "contact_sheet.png", contact_sheet(tables), encoded=True)
    log.info(f"tables {meta['memory_bytes'] / 1e6:.1f} MB in memory, {sum(meta['files_bytes'].values()) / 1e6:.1f} MB "
             f"on disk; pixel relative standard error {meta.get('pixel_relative_standard_error')}")


run(snakemake, main)  # noqa: F821
