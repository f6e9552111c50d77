# Stage: sky extraction from a cloud photograph (Dobashi 2012 §4.1): cloud/sky classification by chroma,
# the sky behind the clouds by a Laplace solve, the sunlight colour c_in; resampled for the fit.

wildcard_constraints:
    photo="[^/]+",


def _photo(wc):
    return config["photos"][wc.photo]


def sky_fit_resolutions(photo):
    """[[W, H], ...] the products of `photo` are resampled to (per photo, else the sky section's)."""
    res = config["photos"][photo].get("fit_resolutions")
    return res if res is not None else config.get("sky", {}).get("fit_resolutions", [[320, 240]])


rule sky:
    output:
        photo=f"{RESULTS}/sky/{{photo}}/photo_linear.exr",
        mask=f"{RESULTS}/sky/{{photo}}/cloud_mask.exr",
        sky=f"{RESULTS}/sky/{{photo}}/sky.exr",
        sun=f"{RESULTS}/sky/{{photo}}/sun.yaml",
        preview=report(f"{RESULTS}/sky/{{photo}}/preview.png", category="Sky",
                       caption="../report/sky_preview.rst"),
    input:
        photo=lambda wc: src(_photo(wc)["path"]),
        mask=lambda wc: [src(_photo(wc)["mask"])] if _photo(wc).get("mask") else [],
    params:
        settings=lambda wc: {**{k: v for k, v in config.get("sky", {}).items() if k != "fit_resolutions"},
                             **({"threshold": _photo(wc)["threshold"]} if _photo(wc).get("threshold") is not None else {}),
                             "accept_unusual": bool(_photo(wc).get("accept_unusual", False))},
        name=lambda wc: wc.photo,
        code=script_fingerprint("sky.py"),
    log:
        f"{RESULTS}/logs/sky/{{photo}}.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/sky/sky/{{photo}}.tsv",
    threads: 1
    resources:
        mem_mb=estimated_mem_mb("sky"),
    script:
        script_path("sky.py")


rule sky_resample:
    output:
        photo=f"{RESULTS}/sky/{{photo}}/{{W}}x{{H}}/photo_linear.exr",
        mask=f"{RESULTS}/sky/{{photo}}/{{W}}x{{H}}/cloud_mask.exr",
        sky=f"{RESULTS}/sky/{{photo}}/{{W}}x{{H}}/sky.exr",
    input:
        photo=f"{RESULTS}/sky/{{photo}}/photo_linear.exr",
        mask=f"{RESULTS}/sky/{{photo}}/cloud_mask.exr",
        sky=f"{RESULTS}/sky/{{photo}}/sky.exr",
    wildcard_constraints:
        W=r"\d+",
        H=r"\d+",
    params:
        code=script_fingerprint("sky_resample.py"),
    log:
        f"{RESULTS}/logs/sky/{{photo}}_{{W}}x{{H}}.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/sky_resample/sky/{{photo}}_{{W}}x{{H}}.tsv",
    threads: 1
    resources:
        mem_mb=estimated_mem_mb("sky_resample"),
    script:
        script_path("sky_resample.py")


for _p in config.get("photos", {}):
    ALL_TARGETS.append(f"{RESULTS}/sky/{_p}/preview.png")
    for _w, _h in sky_fit_resolutions(_p):
        ALL_TARGETS.extend(f"{RESULTS}/sky/{_p}/{_w}x{_h}/{_f}.exr" for _f in ("photo_linear", "cloud_mask", "sky"))
