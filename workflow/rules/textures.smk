# Stage: feature-aware texture analysis and synthesis (Dong 2007 Ch. 6): the feature maps of an example photo
# (`texture_features`: scale, type, colour), a texture whose feature maps follow the output's
# (`feature_synthesis`), and the completion of a hole (`texture_completion`, entries with `complete`).

wildcard_constraints:
    name="[^/]+",


def _texture(wc):
    return config["textures"][wc.name]


def _texture_inputs(wc):
    t = _texture(wc)
    ins = {"photo": src(t["path"])}
    if t["scale"]["from"] == "mask" and t["scale"]["mask"]:
        ins["mask"] = src(t["scale"]["mask"])
    if t["types"]["labels"]:
        ins["labels"] = src(t["types"]["labels"])
    return ins


def _synthesis_inputs(wc):
    t = _texture(wc)
    ins = {"features": f"{RESULTS}/textures/{wc.name}/features.exr",
           "colour": f"{RESULTS}/textures/{wc.name}/colour.yaml"}
    out = t["output"]
    if out["scale"]["kind"] == "image":
        ins["scale_image"] = src(out["scale"]["image"])
    if out["types"]:
        ins["types_image"] = src(out["types"])
    if out["colour"]:
        ins["colour_image"] = src(out["colour"])
    return ins


rule texture_features:
    output:
        exr=f"{RESULTS}/textures/{{name}}/features.exr",
        colour=f"{RESULTS}/textures/{{name}}/colour.yaml",
        preview=report(f"{RESULTS}/textures/{{name}}/features.png", category="Textures", subcategory="{name}",
                       labels={"texture": "{name}", "image": "example | scale | type | colour"}),
    input:
        unpack(_texture_inputs),
    params:
        entry=lambda wc: only(_texture(wc), "working_size", "scale", "types", "colour"),
        code=script_fingerprint("texture_features.py"),
    log:
        f"{RESULTS}/logs/texture_features/{{name}}.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/texture_features/textures/{{name}}.tsv",
    threads: 1
    resources:
        mem_mb=estimated_mem_mb("texture_features"),
    script:
        script_path("texture_features.py")


rule feature_synthesis:
    output:
        exr=f"{RESULTS}/textures/{{name}}/synth.exr",
        png=f"{RESULTS}/textures/{{name}}/synth.png",
        compare=report(f"{RESULTS}/textures/{{name}}/compare.png", category="Textures", subcategory="{name}",
                       labels={"texture": "{name}", "image": "example | target scale, colour map | output | lambda 0"}),
    input:
        unpack(_synthesis_inputs),
    params:
        entry=lambda wc: only(_texture(wc), "output", "method", "optimisation", "quilting", "types", "colour"),
        code=script_fingerprint("feature_synthesis.py"),
    log:
        f"{RESULTS}/logs/feature_synthesis/{{name}}.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/feature_synthesis/textures/{{name}}.tsv",
    threads: 2
    resources:
        mem_mb=estimated_mem_mb("feature_synthesis"),
    script:
        script_path("feature_synthesis.py")


rule texture_completion:
    output:
        exr=f"{RESULTS}/textures/{{name}}/completed.exr",
        png=f"{RESULTS}/textures/{{name}}/completed.png",
        compare=report(f"{RESULTS}/textures/{{name}}/completion_compare.png", category="Textures",
                       subcategory="{name}", labels={"texture": "{name}", "image": "hole | ours | inpainting"}),
    input:
        features=f"{RESULTS}/textures/{{name}}/features.exr",
    params:
        entry=lambda wc: only(_texture(wc), "complete", "optimisation", "types"),
        code=script_fingerprint("texture_completion.py"),
    log:
        f"{RESULTS}/logs/texture_completion/{{name}}.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/texture_completion/textures/{{name}}.tsv",
    threads: 2
    resources:
        mem_mb=estimated_mem_mb("texture_completion"),
    script:
        script_path("texture_completion.py")


for _name, _t in config.get("textures", {}).items():
    ALL_TARGETS.extend([f"{RESULTS}/textures/{_name}/features.png", f"{RESULTS}/textures/{_name}/compare.png"])
    if _t.get("complete"):
        ALL_TARGETS.append(f"{RESULTS}/textures/{_name}/completion_compare.png")
