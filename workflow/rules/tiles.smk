# Stage: ground tiles (Dong 2007 Ch. 5): GA-optimised ω-tile set, then scan-line tiling of any size.

rule tileset:
    output:
        atlas=f"{RESULTS}/tiles/{{texture}}/tileset.exr",
        meta=f"{RESULTS}/tiles/{{texture}}/tileset.yaml",
        png=f"{RESULTS}/tiles/{{texture}}/tileset.png",
    input:
        example=lambda wc: src(config["tiles"][wc.texture]["path"]) if config["tiles"][wc.texture]["path"]
        else f"{RESULTS}/{config['tiles'][wc.texture]['product']}",
        embed=lambda wc: [src(e["path"]) for e in config["tiles"][wc.texture]["embed"]],
    params:
        spec=lambda wc: only(config["tiles"][wc.texture], "tile_size", "set", "ga", "seams", "seed", "margin", "embed"),
        code=script_fingerprint("tileset.py"),
    log:
        f"{RESULTS}/logs/tileset/{{texture}}.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/tileset/tileset/{{texture}}.tsv",
    threads: 1
    resources:
        mem_mb=estimated_mem_mb("tileset"),
    script:
        script_path("tileset.py")


rule tile_texture:
    output:
        exr=f"{RESULTS}/tiles/{{texture}}/synth_{{w}}x{{h}}.exr",
        png=f"{RESULTS}/tiles/{{texture}}/synth_{{w}}x{{h}}.png",
    input:
        atlas=f"{RESULTS}/tiles/{{texture}}/tileset.exr",
        meta=f"{RESULTS}/tiles/{{texture}}/tileset.yaml",
    wildcard_constraints:
        w=r"\d+",
        h=r"\d+",
    params:
        seed=lambda wc: config["tiles"][wc.texture]["seed"],
        code=script_fingerprint("tile_texture.py"),
    log:
        f"{RESULTS}/logs/tile_texture/{{texture}}_{{w}}x{{h}}.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/tile_texture/tile_texture/{{texture}}_{{w}}x{{h}}.tsv",
    threads: 1
    resources:
        mem_mb=estimated_mem_mb("tile_texture"),
    script:
        script_path("tile_texture.py")


ALL_TARGETS.extend(
    f"{RESULTS}/tiles/{name}/synth_{w}x{h}.png"
    for name, spec in config.get("tiles", {}).items()
    for (w, h) in spec["sizes"]
)
ALL_TARGETS.extend(f"{RESULTS}/tiles/{name}/tileset.png" for name in config.get("tiles", {}))
