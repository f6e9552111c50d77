# Stage: Mie cloud shading (Reimschuessel 2011, Ch. 3): Mie phase table, point-to-point scattering passes
# with the per-point Mie/isotropic ratio (solved once per volume + sun, reused for any view and light
# colour), and a demo (glory, fogbow, silver lining) beside the same views shaded with Henyey-Greenstein.

wildcard_constraints:
    sun="az-?[0-9.]+_el-?[0-9.]+",
    phase="(mie|hg)(-[A-Za-z0-9_]+)?",
    droplets="[A-Za-z0-9_]+",
    shot="glory|fogbow|silver_lining",


def mie_sun_key(sun):
    """Wildcard of a sun {azimuth, elevation}: 'az130_el35'."""
    return f"az{sun['azimuth']:g}_el{sun['elevation']:g}"


def _mie_sun(wc):
    import re
    m = re.fullmatch(r"az(-?[0-9.]+)_el(-?[0-9.]+)", wc.sun)
    return {"azimuth": float(m.group(1)), "elevation": float(m.group(2))}


rule mie_table:
    output:
        table=f"{RESULTS}/mie/table.exr",
        summary=f"{RESULTS}/mie/table.yaml",
        cartesian=f"{RESULTS}/mie/table_cartesian.png",
        polar=f"{RESULTS}/mie/table_polar.png",
    params:
        settings=lambda wc: config["mie"]["table"],
        code=script_fingerprint("mie_table.py"),
    log:
        f"{RESULTS}/logs/mie/table.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/mie_table/mie/table.tsv",
    threads: 1
    resources:
        mem_mb=estimated_mem_mb("mie_table"),
    script:
        script_path("mie_table.py")


def _mie_table_path(droplets):
    """The Mie table of a droplet population: the default (section `table`) or a named one (`droplets`)."""
    return f"{RESULTS}/mie/table.exr" if not droplets else f"{RESULTS}/mie/tables/{droplets}/table.exr"


def _mie_volume_dir(volume):
    """A volume of the volume stage (the demo volume, or the stratocumulus deck of the glory and fogbow)."""
    if volume not in config["volumes"]:
        raise ValueError(f"config: Mie volume {volume!r} is not a key of 'volumes'")
    return f"{RESULTS}/volumes/{volume}"


def _mie_phase_droplets(phase):
    return phase.split("-", 1)[1] if "-" in phase else None


rule mie_table_droplets:
    output:
        table=f"{RESULTS}/mie/tables/{{droplets}}/table.exr",
        summary=f"{RESULTS}/mie/tables/{{droplets}}/table.yaml",
        cartesian=f"{RESULTS}/mie/tables/{{droplets}}/table_cartesian.png",
        polar=f"{RESULTS}/mie/tables/{{droplets}}/table_polar.png",
    params:
        # RGB only (the renderer's channels): the population's r_eff, v_eff over the default settings
        settings=lambda wc: {**config["mie"]["table"], **config["mie"]["droplets"][wc.droplets], "spectral_nm": []},
        code=script_fingerprint("mie_table.py"),
    log:
        f"{RESULTS}/logs/mie/table_{{droplets}}.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/mie_table_droplets/mie/table_{{droplets}}.tsv",
    threads: 1
    resources:
        mem_mb=estimated_mem_mb("mie_table_droplets"),
    script:
        script_path("mie_table.py")


rule point_scatter:
    output:
        solution=f"{RESULTS}/mie/pointcloud/{{volume}}/{{sun}}/{{phase}}/solution.npz",
        ratio=f"{RESULTS}/mie/pointcloud/{{volume}}/{{sun}}/{{phase}}/ratio.png",
        summary=f"{RESULTS}/mie/pointcloud/{{volume}}/{{sun}}/{{phase}}/summary.yaml",
    input:
        density=lambda wc: f"{_mie_volume_dir(wc.volume)}/density.vol",
        meta=lambda wc: f"{_mie_volume_dir(wc.volume)}/meta.yaml",
        table=lambda wc: _mie_table_path(_mie_phase_droplets(wc.phase)),
    params:
        settings=lambda wc: config["mie"]["solver"],
        sun=_mie_sun,
        code=script_fingerprint("point_scatter.py"),
    log:
        f"{RESULTS}/logs/mie/point_scatter/{{volume}}_{{sun}}_{{phase}}.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/point_scatter/mie/point_scatter/{{volume}}_{{sun}}_{{phase}}.tsv",
    threads: 2
    resources:
        mem_mb=estimated_mem_mb("point_scatter"),
    script:
        script_path("point_scatter.py")


def _mie_shot_inputs(wc):
    demo = config["mie"]["demo"]
    shot = demo[wc.shot]
    vol = wc.volume
    if shot["cloud"] == "deck":
        vol = demo["deck"]
        if not vol:
            raise ValueError(f"config key 'mie.demo.{wc.shot}.cloud' is 'deck' but 'mie.demo.deck' names no volume")
    sun = mie_sun_key(demo["sun"])
    sfx = f"-{shot['droplets']}" if shot["droplets"] else ""
    return {"density": f"{_mie_volume_dir(vol)}/density.vol", "meta": f"{_mie_volume_dir(vol)}/meta.yaml",
            "table": _mie_table_path(shot["droplets"]),
            "mie": f"{RESULTS}/mie/pointcloud/{vol}/{sun}/mie{sfx}/solution.npz",
            "hg": f"{RESULTS}/mie/pointcloud/{vol}/{sun}/hg{sfx}/solution.npz"}


rule mie_render:
    output:
        exr=f"{RESULTS}/mie/demo/{{volume}}/{{shot}}.exr",
        png=f"{RESULTS}/mie/demo/{{volume}}/{{shot}}.png",
        summary=f"{RESULTS}/mie/demo/{{volume}}/{{shot}}.yaml",
    input:
        unpack(_mie_shot_inputs),
    params:
        demo=lambda wc: only(config["mie"]["demo"], "sun", "resolution", wc.shot),
        render=lambda wc: config["mie"]["render"],
        code=script_fingerprint("mie_render.py"),
    log:
        f"{RESULTS}/logs/mie/render/{{volume}}_{{shot}}.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/mie_render/mie/render/{{volume}}_{{shot}}.tsv",
    threads: 2
    resources:
        mem_mb=estimated_mem_mb("mie_render"),
    script:
        script_path("mie_render.py")


ALL_TARGETS.append(f"{RESULTS}/mie/table_cartesian.png")
if config.get("mie", {}).get("demo", {}).get("volume"):
    ALL_TARGETS.extend(expand(f"{RESULTS}/mie/demo/{{volume}}/{{shot}}.png",
                              volume=[config["mie"]["demo"]["volume"]], shot=["glory", "fogbow", "silver_lining"]))
