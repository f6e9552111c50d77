# Stage: GA fitting of the cloud rendering parameters to a photograph (Dobashi 2012 §3, §4.2, §5, §5.1).
# One job per keyframe (photo + volume + view): the sky products at the view's resolution, the sunlight
# colour c_in and the precomputed tables in; ranked parameter sets, contact sheet and convergence out.

wildcard_constraints:
    keyframe="[^/]+",


def _keyframe(wc):
    kf = config["keyframes"][wc.keyframe]
    for key, section in (("photo", "photos"), ("volume", "volumes"), ("view", "views")):
        if kf[key] not in config.get(section, {}):
            raise ValueError(f"config key 'keyframes.{wc.keyframe}.{key}': {kf[key]!r} is not in '{section}'")
    return kf


def _fit_sky(wc, name):
    kf = _keyframe(wc)
    w, h = config["views"][kf["view"]].get("resolution", [320, 240])
    return f"{RESULTS}/sky/{kf['photo']}/{w}x{h}/{name}.exr"


def _pre(wc, name):
    kf = _keyframe(wc)
    return f"{RESULTS}/precompute/{kf['volume']}/{kf['view']}/{name}"


rule fit:
    output:
        params=f"{RESULTS}/fit/{{keyframe}}/params.yaml",
        ranked=f"{RESULTS}/fit/{{keyframe}}/ranked.exr",
        csv=f"{RESULTS}/fit/{{keyframe}}/convergence.csv",
        plot=report(f"{RESULTS}/fit/{{keyframe}}/convergence.png", category="Fit"),
    input:
        photo=lambda wc: _fit_sky(wc, "photo_linear"),
        mask=lambda wc: _fit_sky(wc, "cloud_mask"),
        sky=lambda wc: _fit_sky(wc, "sky"),
        sun=lambda wc: f"{RESULTS}/sky/{_keyframe(wc)['photo']}/sun.yaml",
        single=lambda wc: _pre(wc, "single.exr"),
        multiple=lambda wc: _pre(wc, _precompute_files()[2]),   # allorders.exr or multiple.exr (transport)
        transmittance=lambda wc: _pre(wc, "transmittance.exr"),
        geometry=lambda wc: _pre(wc, "geometry.exr"),
        meta=lambda wc: _pre(wc, "meta.yaml"),
    params:
        name=lambda wc: wc.keyframe,
        keyframe=lambda wc: _keyframe(wc),
        settings=only(config["fit"], *(k for k in config["fit"] if k != "contact_columns")),
        code=script_fingerprint("fit.py"),
    log:
        f"{RESULTS}/logs/fit/{{keyframe}}.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/fit/fit/{{keyframe}}.tsv",
    threads: 1
    resources:
        mem_mb=estimated_mem_mb("fit"),
    script:
        script_path("fit.py")


# The contact sheet: its own rule, so its layout (`fit.contact_columns`) redraws the sheet and fits nothing.
rule fit_sheet:
    output:
        sheet=report(f"{RESULTS}/fit/{{keyframe}}/contact_sheet.png", category="Fit",
                     caption="../report/fit_contact_sheet.rst"),
    input:
        photo=lambda wc: _fit_sky(wc, "photo_linear"),
        ranked=f"{RESULTS}/fit/{{keyframe}}/ranked.exr",
    params:
        columns=config["fit"]["contact_columns"],
        code=script_fingerprint("fit_sheet.py"),
    log:
        f"{RESULTS}/logs/fit/{{keyframe}}.sheet.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/fit_sheet/fit/{{keyframe}}.tsv",
    threads: 1
    resources:
        mem_mb=estimated_mem_mb("fit_sheet"),
    script:
        script_path("fit_sheet.py")


ALL_TARGETS.extend(expand(f"{RESULTS}/fit/{{keyframe}}/contact_sheet.png", keyframe=config.get("keyframes", {})))
