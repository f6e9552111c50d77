# Stage: volume generation (docs/stages/volume.md): procedural clouds (coarse shape + pyroclastic Perlin-Worley
# displacement + Nubis erosion) or an imported grid, in world metres; written as Mitsuba .vol and OpenVDB .vdb.

rule volume:
    output:
        density=f"{RESULTS}/volumes/{{volume}}/density.vol",
        vdb=f"{RESULTS}/volumes/{{volume}}/density.vdb",
        preview_exr=f"{RESULTS}/volumes/{{volume}}/preview.exr",
        preview_png=report(f"{RESULTS}/volumes/{{volume}}/preview.png", category="Volumes",
                           caption="../report/volume_preview.rst"),
        meta=f"{RESULTS}/volumes/{{volume}}/meta.yaml",
    input:
        lambda wc: [src(config["volumes"][wc.volume]["path"])] if config["volumes"][wc.volume]["kind"] == "file" else [],
    params:
        spec=lambda wc: config["volumes"][wc.volume],
        code=script_fingerprint("volume.py"),
    log:
        f"{RESULTS}/logs/volume/{{volume}}.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/volume/volume/{{volume}}.tsv",
    threads: 2
    resources:
        mem_mb=estimated_mem_mb("volume"),
    script:
        script_path("volume.py")


ALL_TARGETS.extend(expand(f"{RESULTS}/volumes/{{volume}}/preview.png", volume=config["volumes"]))
