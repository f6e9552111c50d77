# Stage: final hybrid RGB + spectral compositing (Dong 2007 Ch. 2; thin films §1.1.6)
# Inputs are named per composite in config `composite.<name>`: background (e.g. the shot's cloud frames,
# {product: shots/<shot>/frames/{frame:04d}.exr}), the sun (optionally the shot's frame state), ground texture
# (tiles product), leaf/petal textures (patterns / leaves products), thin-film objects.
# `composite` writes the hybrid image, the final image and its PNG; `composite_reference` (entries with
# reference: true) the full-spectral render of the same rays, a comparison strip and the timings.
from natscene.composite.inputs import image_files as _composite_image_files
from natscene.composite.inputs import sun_files as _composite_sun_files


def _composite_inputs(wc):
    entry = config["composite"][wc.name]
    frame = int(wc.frame)
    files = _composite_image_files(entry["background"], frame, RESULTS, str(ROOT))
    files += _composite_image_files(entry["ground"]["texture"], frame, RESULTS, str(ROOT))
    for leaf in entry.get("leaves", []):
        files += _composite_image_files(leaf["texture"], frame, RESULTS, str(ROOT))
    files += _composite_sun_files(entry, frame, RESULTS)
    return files


rule composite:
    output:
        hybrid=f"{RESULTS}/composite/{{name}}/{{frame}}/hybrid.exr",
        final=f"{RESULTS}/composite/{{name}}/{{frame}}/final.exr",
        png=report(f"{RESULTS}/composite/{{name}}/{{frame}}/final.png", category="Composite",
                   subcategory="{name}", labels={"composite": "{name}", "frame": "{frame}", "image": "final"}),
    input:
        _composite_inputs,
    wildcard_constraints:
        frame=r"\d{4}",
    params:
        entry=lambda wc: config["composite"][wc.name],
        results=RESULTS,
        root=str(ROOT),
        code=script_fingerprint("composite.py"),
    log:
        f"{RESULTS}/logs/composite/{{name}}.{{frame}}.log",
    threads: 2
    resources:
        mem_mb=estimated_mem_mb("composite"),
    script:
        script_path("composite.py")


rule composite_reference:
    output:
        exr=f"{RESULTS}/composite/{{name}}/{{frame}}/reference.exr",
        png=report(f"{RESULTS}/composite/{{name}}/{{frame}}/compare.png", category="Composite",
                   subcategory="{name}",
                   labels={"composite": "{name}", "frame": "{frame}", "image": "hybrid | full-spectral | dE2000"}),
        yaml=f"{RESULTS}/composite/{{name}}/{{frame}}/compare.yaml",
    input:
        _composite_inputs,
    wildcard_constraints:
        frame=r"\d{4}",
    params:
        entry=lambda wc: config["composite"][wc.name],
        results=RESULTS,
        root=str(ROOT),
        code=script_fingerprint("composite_reference.py"),
    log:
        f"{RESULTS}/logs/composite_reference/{{name}}.{{frame}}.log",
    threads: 2
    resources:
        mem_mb=estimated_mem_mb("composite_reference"),
    script:
        script_path("composite_reference.py")


for _name, _entry in config["composite"].items():
    ALL_TARGETS.extend(f"{RESULTS}/composite/{_name}/{f:04d}/final.png" for f in _entry["frames"])
    if _entry.get("reference"):
        ALL_TARGETS.extend(f"{RESULTS}/composite/{_name}/{f:04d}/compare.png" for f in _entry["frames"])
