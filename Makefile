# The two commands of the README. Each sets itself up first (tools/setup.sh is idempotent).
VENV ?= .venv
CORES ?= 2
CONFIG ?= config/config.yaml

.PHONY: setup setup-extras run smoke test test-gaps bench clean cluster-setup cluster-smoke

setup:
	@bash tools/setup.sh

# optional heavy tools (Blender for the OpenVDB client test)
setup-extras: setup
	@bash tools/setup-extras.sh

# CACHE=precompute: Snakemake's between-workflow cache for those rules, in $SNAKEMAKE_OUTPUT_CACHE (default
# .cache/snakemake here). A killed run is picked up where it stopped: natscene.recover clears the lock it left
# (when no Snakemake process holds it) and --rerun-incomplete redoes the jobs it interrupted.
CACHE ?=
export SNAKEMAKE_OUTPUT_CACHE ?= $(CURDIR)/.cache/snakemake

run: setup
	$(VENV)/bin/python -m natscene.recover
	$(if $(CACHE),mkdir -p "$(SNAKEMAKE_OUTPUT_CACHE)")
	$(VENV)/bin/snakemake --cores $(CORES) --configfile $(CONFIG) --printshellcmds --rerun-incomplete \
	  $(if $(CACHE),--cache $(CACHE))

smoke: setup
	$(VENV)/bin/python -m natscene.recover --directory results/smoke
	$(VENV)/bin/snakemake --cores $(CORES) --configfile config/smoke.yaml --directory results/smoke --rerun-incomplete

# the tests on TEST_WORKERS processes (pytest-xdist; tests/conftest.py says who shares what), without the SLURM
# tests (minutes each; docs/cluster.md): `pytest -m cluster` runs them, and without the transport's known gaps
# (strict xfails against independent references, 9 min of one core): `make test-gaps` runs them, after a change
# to the transport
TEST_WORKERS ?= 2
test: setup
	$(VENV)/bin/python -m pytest -q -m "not cluster and not gaps" -n $(TEST_WORKERS)

test-gaps: setup
	$(VENV)/bin/python -m pytest -q -m gaps -n $(TEST_WORKERS)

bench: setup
	@for b in benchmarks/*.py; do echo "== $$b"; $(VENV)/bin/python $$b || exit 1; done

# SLURM (docs/cluster.md). cluster-setup: the Snakemake SLURM executor (pyproject extra `cluster`), all a
# login node of a real cluster needs. cluster-smoke: also a one-node SLURM on this machine (tools/slurm-local.sh
# installs Debian's slurm-wlm, slurmdbd, mariadb-server, munge with apt-get; root), the smoke workflow through
# the profile, checked against a local run.
cluster-setup: setup
	@$(VENV)/bin/python -c 'import importlib.metadata as m, sys; v = m.version("snakemake-executor-plugin-slurm"); \
	  sys.exit(not (2, 8) <= tuple(map(int, v.split(".")[:2])) < (3, 0))' 2>/dev/null \
	  || { echo "natscene setup: installing the SLURM executor plugin (extra 'cluster')"; \
	       $(VENV)/bin/python -m pip install -q -e ".[test,cluster]"; }

cluster-smoke: cluster-setup
	$(VENV)/bin/python tools/cluster_smoke.py

clean:
	rm -rf results .snakemake
