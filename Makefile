# The two commands of the README. Each sets itself up first (tools/setup.sh is idempotent).
VENV ?= .venv
CORES ?= 2
CONFIG ?= config/config.yaml

.PHONY: setup setup-extras run smoke test bench clean

setup:
	@bash tools/setup.sh

# optional heavy tools (Blender for the OpenVDB client test)
setup-extras: setup
	@bash tools/setup-extras.sh

run: setup
	$(VENV)/bin/snakemake --cores $(CORES) --configfile $(CONFIG) --printshellcmds

smoke: setup
	$(VENV)/bin/snakemake --cores $(CORES) --configfile config/smoke.yaml --directory results/smoke

test: setup
	$(VENV)/bin/python -m pytest -q

bench: setup
	@for b in benchmarks/*.py; do echo "== $$b"; $(VENV)/bin/python $$b || exit 1; done

clean:
	rm -rf results .snakemake
