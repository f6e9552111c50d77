# Stage: pigment pattern maps (Dong 2007 Ch. 3): reaction-diffusion maps, colour expression, photo recolouring

rule pigment_maps:
    output:
        maps=[f"{RESULTS}/patterns/{{pattern}}/pigment_{p}.exr" for p in (0, 1)],
        preview=f"{RESULTS}/patterns/{{pattern}}/maps.png",
    params:
        spec=lambda wc: only(config["patterns"][wc.pattern], "size", "shape", "venation", "rd", "normalise"),
        seed=config["seed"],
        root=str(ROOT),
        code=script_fingerprint("pigment_maps.py"),
    log:
        f"{RESULTS}/logs/pigment_maps/{{pattern}}.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/pigment_maps/pigment_maps/{{pattern}}.tsv",
    threads: 2
    resources:
        mem_mb=estimated_mem_mb("pigment_maps"),
    script:
        script_path("pigment_maps.py")


rule pattern_color:
    input:
        maps=[f"{RESULTS}/patterns/{{pattern}}/pigment_{p}.exr" for p in (0, 1)],
    output:
        color=f"{RESULTS}/patterns/{{pattern}}/color.exr",
        preview=f"{RESULTS}/patterns/{{pattern}}/preview.png",
    params:
        spec=lambda wc: only(config["patterns"][wc.pattern], "concentration", "pigments", "illuminant"),
        code=script_fingerprint("pattern_color.py"),
    log:
        f"{RESULTS}/logs/pattern_color/{{pattern}}.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/pattern_color/pattern_color/{{pattern}}.tsv",
    threads: 1
    resources:
        mem_mb=estimated_mem_mb("pattern_color"),
    script:
        script_path("pattern_color.py")


rule recolour:
    input:
        photo=lambda wc: src(config["recolour"][wc.photo]["photo"]),
    output:
        exr=f"{RESULTS}/patterns/recolour/{{photo}}/recoloured.exr",
        png=f"{RESULTS}/patterns/recolour/{{photo}}/recoloured.png",
    params:
        spec=lambda wc: config["recolour"][wc.photo],
        seed=config["seed"],
        code=script_fingerprint("recolour.py"),
    log:
        f"{RESULTS}/logs/recolour/{{photo}}.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/recolour/recolour/{{photo}}.tsv",
    threads: 2
    resources:
        mem_mb=estimated_mem_mb("recolour"),
    script:
        script_path("recolour.py")


rule pattern_sheet:
    input:
        maps=[f"{RESULTS}/patterns/{n}/pigment_{p}.exr" for n in config["patterns"] for p in (0, 1)],
        colors=[f"{RESULTS}/patterns/{n}/color.exr" for n in config["patterns"]],
    output:
        f"{RESULTS}/patterns/sheet.png",
    params:
        names=list(config["patterns"]),
        code=script_fingerprint("pattern_sheet.py"),
    log:
        f"{RESULTS}/logs/pattern_sheet.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/pattern_sheet/pattern_sheet.tsv",
    threads: 1
    resources:
        mem_mb=estimated_mem_mb("pattern_sheet"),
    script:
        script_path("pattern_sheet.py")


ALL_TARGETS.extend(expand(f"{RESULTS}/patterns/{{pattern}}/preview.png", pattern=config["patterns"]))
if config["patterns"]:
    ALL_TARGETS.append(f"{RESULTS}/patterns/sheet.png")
ALL_TARGETS.extend(expand(f"{RESULTS}/patterns/recolour/{{photo}}/recoloured.png", photo=config["recolour"]))
