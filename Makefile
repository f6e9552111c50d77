# The two commands of the README. Each sets itself up first (tools/setup.sh is idempotent).
VENV ?= .venv
CORES ?= 2
CONFIG ?= config/config.yaml

.PHONY: setup run smoke test bench clean cluster-setup cluster-smoke

setup:
	@bash tools/setup.sh

run: setup
	$(VENV)/bin/snakemake --cores $(CORES) --configfile $(CONFIG) --printshellcmds

smoke: setup
	$(VENV)/bin/snakemake --cores $(CORES) --configfile config/smoke.yaml --directory results/smoke

test: setup
	$(VENV)/bin/python -m pytest -q

bench: setup
	@for b in benchmarks/*.py; do echo "== $$b"; $(VENV)/bin/python $$b || exit 1; done

# SLURM (docs/cluster.md): the executor plugin (pyproject extra `cluster`) and, for a one-node cluster on
# this machine, Debian's slurm-wlm/slurmdbd/mariadb-server/munge (root, apt-get; tools/slurm-local.sh).
cluster-setup: setup
	@$(VENV)/bin/python -c 'import importlib.metadata as m, sys; v = m.version("snakemake-executor-plugin-slurm"); \
	  sys.exit(not (2, 8) <= tuple(map(int, v.split(".")[:2])) < (3, 0))' 2>/dev/null \
	  || { echo "natscene setup: installing the SLURM executor plugin (extra 'cluster')"; \
	       $(VENV)/bin/python -m pip install -q -e ".[test,cluster]"; }
	@bash tools/slurm-local.sh install

# The smoke workflow through the SLURM profile on a local one-node cluster, checked against a local run.
cluster-smoke: cluster-setup
	$(VENV)/bin/python tools/cluster_smoke.py

clean:
	rm -rf results .snakemake
