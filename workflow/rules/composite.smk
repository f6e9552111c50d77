# Stage: final hybrid RGB + spectral compositing (Dong 2007 Ch. 2; thin films §1.1.6)
# A composite names a shot (`composite.<name>.shot`): frame k is seen by frame k's camera in front of frame k's
# cloud plate, lit by its sun and sky (the frame state shots/<shot>/params/<frame>.yaml, the shot's sky and
# resolution, the shot volume's meta.yaml for the haze distance). The meadow reads the ground texture (tiles
# product), the petal pattern maps (patterns/<pattern>/color.exr) and the season leaves (leaves products).
# `composite` writes the hybrid image, the final image and its PNG; `composite_reference` (entries with
# reference: true) the full-spectral render of the same rays, a comparison strip and the timings.
from natscene.composite.files import input_files as _composite_input_files


def _composite_shot(wc):
    """The keys of the composite's shot that the set reads (its volume, resolution and sky), or None."""
    shot = config["composite"][wc.name].get("shot")
    if shot and shot not in config.get("shots", {}):
        raise ValueError(f"config composite.{wc.name}.shot: {shot!r} is not in 'shots'")
    return only(config["shots"][shot], "volume", "resolution", "sky") if shot else None


def _composite_entry(wc):
    """The composite entry without the keys that only choose which jobs run (`frames`, `reference`): adding a
    frame or the reference render reruns no existing frame."""
    entry = config["composite"][wc.name]
    return only(entry, *(k for k in entry if k not in ("frames", "reference")))


def _composite_exposure(wc):
    """The exposure of the composite's PNGs: its shot's, else "auto"."""
    shot = config["composite"][wc.name].get("shot")
    return config["shots"][shot]["exposure"] if shot else "auto"


def _composite_inputs(wc):
    return _composite_input_files(config["composite"][wc.name], int(wc.frame), RESULTS, str(ROOT), _composite_shot(wc))


rule composite:
    output:
        hybrid=f"{RESULTS}/composite/{{name}}/{{frame}}/hybrid.exr",
        final=f"{RESULTS}/composite/{{name}}/{{frame}}/final.exr",
    input:
        _composite_inputs,
    wildcard_constraints:
        frame=r"\d{4}",
    params:
        entry=_composite_entry,
        shot=_composite_shot,
        results=RESULTS,
        root=str(ROOT),
        code=script_fingerprint("composite.py"),
    log:
        f"{RESULTS}/logs/composite/{{name}}.{{frame}}.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/composite/composite/{{name}}.{{frame}}.tsv",
    threads: 2
    resources:
        mem_mb=estimated_mem_mb("composite"),
    script:
        script_path("composite.py")


# The final image's PNG at the shot's exposure (auto without a shot): its own rule, so a new exposure redraws it.
rule composite_preview:
    output:
        png=report(f"{RESULTS}/composite/{{name}}/{{frame}}/final.png", category="Composite",
                   subcategory="{name}", labels={"composite": "{name}", "frame": "{frame}", "image": "final"}),
    input:
        exr=f"{RESULTS}/composite/{{name}}/{{frame}}/final.exr",
    wildcard_constraints:
        frame=r"\d{4}",
    params:
        exposure=_composite_exposure,
        code=script_fingerprint("exr_preview.py"),
    log:
        f"{RESULTS}/logs/composite_preview/{{name}}.{{frame}}.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/composite_preview/composite/{{name}}.{{frame}}.tsv",
    threads: 1
    resources:
        mem_mb=estimated_mem_mb("composite_preview"),
    script:
        script_path("exr_preview.py")


rule composite_reference:
    output:
        exr=f"{RESULTS}/composite/{{name}}/{{frame}}/reference.exr",
        yaml=f"{RESULTS}/composite/{{name}}/{{frame}}/compare.yaml",
    input:
        _composite_inputs,
    wildcard_constraints:
        frame=r"\d{4}",
    params:
        entry=_composite_entry,
        shot=_composite_shot,
        results=RESULTS,
        root=str(ROOT),
        code=script_fingerprint("composite_reference.py"),
    log:
        f"{RESULTS}/logs/composite_reference/{{name}}.{{frame}}.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/composite_reference/composite_reference/{{name}}.{{frame}}.tsv",
    threads: 2
    resources:
        mem_mb=estimated_mem_mb("composite_reference"),
    script:
        script_path("composite_reference.py")


# compare.png (hybrid | full-spectral | dE2000) at the composite's exposure: its own rule, so a new exposure
# redraws it and renders nothing.
rule composite_compare:
    output:
        png=report(f"{RESULTS}/composite/{{name}}/{{frame}}/compare.png", category="Composite",
                   subcategory="{name}",
                   labels={"composite": "{name}", "frame": "{frame}", "image": "hybrid | full-spectral | dE2000"}),
    input:
        final=f"{RESULTS}/composite/{{name}}/{{frame}}/final.exr",
        reference=f"{RESULTS}/composite/{{name}}/{{frame}}/reference.exr",
    wildcard_constraints:
        frame=r"\d{4}",
    params:
        exposure=_composite_exposure,
        code=script_fingerprint("composite_compare.py"),
    log:
        f"{RESULTS}/logs/composite_compare/{{name}}.{{frame}}.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/composite_compare/composite/{{name}}.{{frame}}.tsv",
    threads: 1
    resources:
        mem_mb=estimated_mem_mb("composite_compare"),
    script:
        script_path("composite_compare.py")


for _name, _entry in config["composite"].items():
    ALL_TARGETS.extend(f"{RESULTS}/composite/{_name}/{f:04d}/final.png" for f in _entry["frames"])
    if _entry.get("reference"):
        ALL_TARGETS.extend(f"{RESULTS}/composite/{_name}/{f:04d}/compare.png" for f in _entry["frames"])
