# Stage: scattering precompute (Dobashi 2012 §4.3, Eqs. 5, 7, 9): per (volume, view) tables for the fit.

def _precompute_settings():
    return {k: v for k, v in config["precompute"].items() if k != "pairs"}


rule precompute:
    output:
        single=f"{RESULTS}/precompute/{{volume}}/{{view}}/single.exr",
        transmittance=f"{RESULTS}/precompute/{{volume}}/{{view}}/transmittance.exr",
        multiple=f"{RESULTS}/precompute/{{volume}}/{{view}}/multiple.exr",
        geometry=f"{RESULTS}/precompute/{{volume}}/{{view}}/geometry.exr",
        meta=f"{RESULTS}/precompute/{{volume}}/{{view}}/meta.yaml",
        contact_sheet=f"{RESULTS}/precompute/{{volume}}/{{view}}/contact_sheet.png",
    input:
        density=f"{RESULTS}/volumes/{{volume}}/density.vol",
        volume_meta=f"{RESULTS}/volumes/{{volume}}/meta.yaml",
    params:
        view=lambda wc: config["views"][wc.view],
        settings=_precompute_settings(),
        code=fingerprint("scatter", "volume", "geometry", "io", "variant"),
    log:
        f"{RESULTS}/logs/precompute/{{volume}}/{{view}}.log",
    threads: config["threads"]
    resources:
        mem_mb=6000,
    script:
        str(ROOT / "scripts" / "precompute.py")


ALL_TARGETS.extend(
    f"{RESULTS}/precompute/{p['volume']}/{p['view']}/contact_sheet.png" for p in config["precompute"]["pairs"]
)
