"""Configuration: load, validate against the JSON-schema (``snakemake.utils.validate``, defaults filled
in), and turn validation failures into one clear message naming the key path and what was expected.

Paths in the config are relative to the repository root (the directory holding the Snakefile) unless
absolute; :func:`resolve_path` applies that rule.
"""
from __future__ import annotations

import os
from pathlib import Path

import yaml


class ConfigError(ValueError):
    """The config is invalid; the message names the key path."""


def _key_path(path) -> str:
    out = ""
    for p in path:
        out += f"[{p}]" if isinstance(p, int) else (f".{p}" if out else str(p))
    return out or "(top level)"


def _describe(error) -> str:
    """One line for a jsonschema ValidationError: key path, offending value, what was expected."""
    # For anyOf/oneOf, the most specific sub-error says more than "is not valid under any of".
    if error.context:
        from jsonschema.exceptions import best_match
        error = best_match(error.context) or error
    where = _key_path(error.absolute_path)
    expected = ""
    schema = error.schema if isinstance(error.schema, dict) else {}
    if error.validator == "additionalProperties" and "properties" in schema:
        expected = f"; allowed keys here: {', '.join(sorted(schema['properties']))}"
    elif schema.get("description"):
        expected = f" (expected: {schema['description']})"
    return f"config key '{where}': {error.message}{expected}"


def validate_config(config: dict, schema: str | os.PathLike, source: str = "config") -> dict:
    """Validate ``config`` in place (defaults filled in) or raise :class:`ConfigError` naming the key."""
    import jsonschema
    from snakemake.exceptions import WorkflowError
    from snakemake.utils import validate

    try:
        validate(config, str(schema), set_default=True)
    except (WorkflowError, jsonschema.ValidationError) as e:
        errs = [a for a in getattr(e, "args", ()) if isinstance(a, jsonschema.ValidationError)]
        if isinstance(e, jsonschema.ValidationError):
            errs = [e]
        if not errs:
            raise
        raise ConfigError(f"{source}: invalid configuration: {_describe(errs[0])}") from None
    return config


def load_yaml_config(path: str | os.PathLike) -> dict:
    """Read a YAML config file with a clear error."""
    path = Path(path)
    if not path.is_file():
        raise ConfigError(f"config file {path} not found")
    try:
        data = yaml.safe_load(path.read_text()) or {}
    except yaml.YAMLError as e:
        raise ConfigError(f"config file {path} is not valid YAML: {e}") from None
    if not isinstance(data, dict):
        raise ConfigError(f"config file {path} must hold a mapping at the top level")
    return data


def resolve_path(path: str | os.PathLike, root: str | os.PathLike) -> str:
    """An input path from the config: absolute as given, else relative to the repository ``root``."""
    p = Path(os.path.expanduser(str(path)))
    return str(p if p.is_absolute() else Path(root) / p)
