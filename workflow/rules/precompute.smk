# Stage: scattering precompute (Dobashi 2012 §4.3, Eqs. 5, 7, 9): per (volume, view) tables for the fit.

def _precompute_settings():
    return {k: v for k, v in config["precompute"].items() if k != "pairs"}


def _precompute_files():
    from natscene.scatter.tables import table_files
    return table_files(config["precompute"]["transport"])


# Between-workflow cache (DESIGN §4): `snakemake --cache precompute` with $SNAKEMAKE_OUTPUT_CACHE set reuses
# the tables of another project with the same volume, view, settings and code; "omit-software" because the
# code is already part of the hash through params.code. Snakemake's cache needs the outputs as one multiext.
rule precompute:
    output:
        multiext(f"{RESULTS}/precompute/{{volume}}/{{view}}/", *_precompute_files(), "contact_sheet.png"),
    input:
        density=f"{RESULTS}/volumes/{{volume}}/density.vol",
        volume_meta=f"{RESULTS}/volumes/{{volume}}/meta.yaml",
    params:
        view=lambda wc: config["views"][wc.view],
        settings=_precompute_settings(),
        code=script_fingerprint("precompute.py"),
    log:
        f"{RESULTS}/logs/precompute/{{volume}}/{{view}}.log",
    threads: config["threads"]
    resources:
        mem_mb=estimated_mem_mb("precompute"),
    cache: "omit-software"
    script:
        script_path("precompute.py")


ALL_TARGETS.extend(
    f"{RESULTS}/precompute/{p['volume']}/{p['view']}/contact_sheet.png" for p in config["precompute"]["pairs"]
)
