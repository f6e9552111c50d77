"""Rule `mie_deck`: the thin stratocumulus / fog deck of the glory and fogbow demo shots."""
from natscene.io import write_yaml
from natscene.mie.demo import stratocumulus_deck
from natscene.runner import run
from natscene.volume.grid import write_vol


def main(snakemake, log):
    d = dict(snakemake.params.deck)
    deck = stratocumulus_deck(d["size"], d["resolution"], d["thickness"], d["relief"], d["relief_scale"],
                              d["optical_depth"], float(snakemake.params.sigma_t), d["seed"])
    log.info(f"deck {deck.resolution} voxels, box {deck.bbox_min.tolist()} .. {deck.bbox_max.tolist()}, "
             f"extinction scale {deck.extinction_scale:.4g} (mean vertical optical depth {d['optical_depth']})")
    write_vol(snakemake.output.density, deck.density, deck.bbox_min, deck.bbox_max)
    write_yaml(snakemake.output.meta, {
        "volume": "mie_deck", "kind": "stratocumulus deck (natscene.mie.demo.stratocumulus_deck)",
        "resolution": list(deck.resolution), "bbox_min": deck.bbox_min, "bbox_max": deck.bbox_max,
        "voxel_size": float(deck.voxel_size[0]), "extinction_scale": deck.extinction_scale, "settings": d})


run(snakemake, main)  # noqa: F821
