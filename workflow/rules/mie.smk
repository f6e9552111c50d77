# Stage: Mie cloud shading (Reimschuessel 2011, Ch. 3): Mie phase table, point-to-point scattering passes
# with the per-point Mie/isotropic ratio (solved once per volume + sun, reused for any view and light
# colour), and a demo (glory, fogbow, silver lining) beside the same views shaded with Henyey-Greenstein.

wildcard_constraints:
    sun="az-?[0-9.]+_el-?[0-9.]+",
    phase="mie|hg",
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
        code=fingerprint("mie", "io"),
    log:
        f"{RESULTS}/logs/mie/table.log",
    threads: 1
    resources:
        mem_mb=1000,
    script:
        script_path("mie_table.py")


rule point_scatter:
    output:
        solution=f"{RESULTS}/mie/pointcloud/{{volume}}/{{sun}}/{{phase}}/solution.npz",
        ratio=f"{RESULTS}/mie/pointcloud/{{volume}}/{{sun}}/{{phase}}/ratio.png",
        summary=f"{RESULTS}/mie/pointcloud/{{volume}}/{{sun}}/{{phase}}/summary.yaml",
    input:
        density=f"{RESULTS}/volumes/{{volume}}/density.vol",
        meta=f"{RESULTS}/volumes/{{volume}}/meta.yaml",
        table=f"{RESULTS}/mie/table.exr",
    params:
        settings=lambda wc: config["mie"]["solver"],
        sun=_mie_sun,
        code=fingerprint("mie", "io", "volume", "geometry"),
    log:
        f"{RESULTS}/logs/mie/point_scatter/{{volume}}_{{sun}}_{{phase}}.log",
    threads: 2
    resources:
        mem_mb=6000,
    script:
        script_path("point_scatter.py")


rule mie_render:
    output:
        exr=f"{RESULTS}/mie/demo/{{volume}}/{{shot}}.exr",
        png=f"{RESULTS}/mie/demo/{{volume}}/{{shot}}.png",
    input:
        density=f"{RESULTS}/volumes/{{volume}}/density.vol",
        meta=f"{RESULTS}/volumes/{{volume}}/meta.yaml",
        table=f"{RESULTS}/mie/table.exr",
        mie=lambda wc: f"{RESULTS}/mie/pointcloud/{wc.volume}/{mie_sun_key(config['mie']['demo']['sun'])}/mie/solution.npz",
        hg=lambda wc: f"{RESULTS}/mie/pointcloud/{wc.volume}/{mie_sun_key(config['mie']['demo']['sun'])}/hg/solution.npz",
    params:
        demo=lambda wc: config["mie"]["demo"],
        render=lambda wc: config["mie"]["render"],
        code=fingerprint("mie", "io", "volume", "geometry"),
    log:
        f"{RESULTS}/logs/mie/render/{{volume}}_{{shot}}.log",
    threads: 2
    resources:
        mem_mb=3000,
    script:
        script_path("mie_render.py")


ALL_TARGETS.append(f"{RESULTS}/mie/table_cartesian.png")
if config.get("mie", {}).get("demo", {}).get("volume"):
    ALL_TARGETS.extend(expand(f"{RESULTS}/mie/demo/{{volume}}/{{shot}}.png",
                              volume=[config["mie"]["demo"]["volume"]], shot=["glory", "fogbow", "silver_lining"]))
