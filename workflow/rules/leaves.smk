# Stage: seasonal leaf colour (Dong 2007 Ch. 4): pigment concentrations from a climate series, PROSPECT-D colour

rule leaf_season:
    output:
        leaves=expand(f"{RESULTS}/leaves/{config['leaves']['name']}/{{{{climate}}}}/{{date}}.exr",
                      date=config["leaves"]["dates"]),
        strip=f"{RESULTS}/leaves/{config['leaves']['name']}/{{climate}}/strip.png",
        csv=f"{RESULTS}/leaves/{config['leaves']['name']}/{{climate}}/concentrations.csv",
    params:
        spec=only(config["leaves"], "climate", "season", "size", "optics"),
        case=lambda wc: config["leaves"]["cases"][wc.climate],
        dates=config["leaves"]["dates"],
        seed=config["seed"],
        code=script_fingerprint("leaf_season.py"),
    log:
        f"{RESULTS}/logs/leaf_season/{{climate}}.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/leaf_season/leaf_season/{{climate}}.tsv",
    threads: 1
    resources:
        mem_mb=estimated_mem_mb("leaf_season"),
    script:
        script_path("leaf_season.py")


ALL_TARGETS.extend(expand(f"{RESULTS}/leaves/{config['leaves']['name']}/{{climate}}/strip.png",
                          climate=config["leaves"]["cases"]))
