# natscene: the workflow. Loads and validates the config, then includes one rule file per stage.
# Run:  make run            (main job, config/config.yaml)
#       make smoke          (tiny inputs)
import os
import sys
from pathlib import Path

ROOT = Path(workflow.basedir).resolve()
sys.path.insert(0, str(ROOT / "src"))  # the library, also when the package is not pip-installed

from natscene.config import load_yaml_config, resolve_path, validate_config
from natscene.errors import ConfigError
from natscene.config_checks import check_config
from natscene.fingerprint import script_fingerprint as _script_fingerprint
from natscene.resources import mem_mb as _mem_mb
from natscene.resources import memory_problems as _memory_problems

if not config:  # no --configfile given: the main job on the bundled example
    config.update(load_yaml_config(ROOT / "config" / "config.yaml"))
_CONFIG_SOURCE = ", ".join(map(str, workflow.configfiles)) or "config/config.yaml"
validate_config(config, ROOT / "workflow" / "schemas" / "config.schema.yaml", source=_CONFIG_SOURCE)
check_config(config, ROOT, source=_CONFIG_SOURCE)  # cross-references, input files, geometry: before any job
_too_big = _memory_problems(config, ROOT, workflow.global_resources)  # jobs that cannot fit in memory
if _too_big:
    raise ConfigError(f"{_CONFIG_SOURCE}: {len(_too_big)} job(s) cannot fit in memory:\n  " + "\n  ".join(_too_big))

# Snakemake's between-workflow cache (`--cache precompute`, DESIGN §4) keeps its entries in $SNAKEMAKE_OUTPUT_CACHE;
# without it Snakemake fails deep inside with a traceback. `make run CACHE=precompute` sets a default folder.
if getattr(workflow.workflow_settings, "cache", None) is not None and not os.environ.get("SNAKEMAKE_OUTPUT_CACHE"):
    raise ConfigError("--cache needs the environment variable SNAKEMAKE_OUTPUT_CACHE, the folder the projects that "
                      "share tables use (e.g. export SNAKEMAKE_OUTPUT_CACHE=~/.cache/natscene); "
                      "`make run CACHE=precompute` sets it to .cache/snakemake in this repository")

RESULTS = config["results"]
ALL_TARGETS = []  # each rule file appends the final products it wants built by `rule all`


def src(path):
    """An input path from the config, resolved against the repository root."""
    return resolve_path(path, ROOT)


def only(section, *keys):
    """The keys of a config section that a rule's script reads (PyPSA-Eur's habit): its params hold nothing else,
    so a setting the script does not read reruns nothing."""
    return {k: section[k] for k in keys if k in section}


def script_path(name):
    return str(ROOT / "scripts" / name)


def estimated_mem_mb(rule):
    """`resources: mem_mb=` of a rule: estimated from the job's inputs (natscene.resources), refused if too big."""
    return lambda wc: _mem_mb(rule, config, dict(wc.items()), ROOT, workflow.global_resources)


def script_fingerprint(name):
    """Hash of every natscene module the rule script `name` can import (natscene.fingerprint)."""
    return _script_fingerprint(ROOT / "scripts" / name)


for _rules in sorted((ROOT / "workflow" / "rules").glob("*.smk")):
    include: str(_rules)


rule all:
    default_target: True
    input:
        ALL_TARGETS,
