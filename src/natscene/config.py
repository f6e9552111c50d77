"""
Configuration
=============

Defines the configuration's loading and validation: load, validate against the JSON-schema
(``snakemake.utils.validate``, defaults filled in), and turn validation failures into one clear message naming
the key path and what was expected:

-   :func:`load_yaml_config`, :func:`validate_config`: read a config file, validate it in place.
-   :func:`bundle_schema`: a schema with every ``$ref`` inlined; :func:`canonical`: a config value's canonical form.
-   :func:`settings_from_section`, :func:`default_settings`, :func:`complete_section`: config sections as
    settings dataclasses, with the schema's defaults.
-   :func:`resolve_path`, :func:`relative_to_root`: config paths and the repository root.

Paths in the config are relative to the repository root (the directory holding the Snakefile) unless
absolute; :func:`resolve_path` applies that rule.
"""
from __future__ import annotations

import functools
import os
from pathlib import Path

import yaml

from natscene.errors import ConfigError

__all__ = ["load_yaml_config", "validate_config", "bundle_schema", "canonical", "settings_from_section",
           "default_settings", "complete_section", "schema_section", "section_defaults", "schema_defaults", "SCHEMA_DIR",
           "resolve_path", "relative_to_root"]


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


@functools.lru_cache(maxsize=None)
def _schema_file(path: Path, mtime_ns: int) -> dict:
    """One schema file as parsed (by libyaml where PyYAML has it: the workflow parses the schemas on every run)."""
    return yaml.load(path.read_text(), Loader=getattr(yaml, "CSafeLoader", yaml.SafeLoader))


def _load_schema(path: Path) -> dict:
    return _schema_file(path, path.stat().st_mtime_ns)


def bundle_schema(path: str | os.PathLike) -> dict:
    """Load a schema and inline every ``$ref`` (other files, relative to the referring file, and local
    ``#/...`` pointers) into one document.

    Needed because ``snakemake.utils.validate`` fills defaults only where its validator reaches without a
    ``$ref`` (a ``$ref`` descends with the plain validator, so defaults inside referenced files would be lost).
    """
    path = Path(path).resolve()

    def resolve(node, root, base):
        if isinstance(node, list):
            return [resolve(v, root, base) for v in node]
        if not isinstance(node, dict):
            return node
        if "$ref" in node:
            ref = node["$ref"]
            siblings = {k: v for k, v in node.items() if k != "$ref"}
            file_part, _, pointer = ref.partition("#")
            if file_part:
                target_path = (base / file_part).resolve()
                target_root = _load_schema(target_path)
                target_base = target_path.parent
            else:
                target_root, target_base = root, base
            target = target_root
            for part in [p for p in pointer.split("/") if p]:
                target = target[part]
            out = resolve(target, target_root, target_base)
            out = {k: v for k, v in out.items() if k not in ("$schema", "$id", "$defs")}
            out.update(resolve(siblings, root, base))
            return out
        return {k: resolve(v, root, base) for k, v in node.items() if k != "$defs" or node is root}

    root = _load_schema(path)
    bundled = resolve(root, root, path.parent)
    bundled.pop("$defs", None)
    return bundled


def validate_config(config: dict, schema: str | os.PathLike, source: str = "config") -> dict:
    """Validate ``config`` in place (defaults filled in) or raise :class:`ConfigError` naming the key."""
    return _validate_bundled(config, bundle_schema(schema), source)


def _validate_bundled(config: dict, bundled: dict, source: str) -> dict:
    """:func:`validate_config` against an already bundled schema (a dict)."""
    import json
    import tempfile

    import jsonschema
    from snakemake.utils import validate

    with tempfile.NamedTemporaryFile("w", suffix=".schema.json", delete=False) as f:
        json.dump(bundled, f)
        bundled_path = f.name
    try:
        validate(config, bundled_path, set_default=True)
    except Exception as e:  # noqa: BLE001 - snakemake wraps the ValidationError in its WorkflowError
        candidates = [e, *getattr(e, "args", ()), e.__cause__, e.__context__]
        errs = [a for a in candidates if isinstance(a, jsonschema.ValidationError)]
        if not errs:
            raise
        raise ConfigError(f"{source}: invalid configuration: {_describe(errs[0])}") from None
    finally:
        os.unlink(bundled_path)
    canon = canonical(config, bundled)
    config.clear()
    config.update(canon)
    return config


def _number_only(schema: dict) -> bool:
    t = schema.get("type")
    types = set(t) if isinstance(t, list) else {t}
    return "number" in types and "integer" not in types


def canonical(value, schema: dict | None = None):
    """The canonical form of a validated config value, so that equivalent configs give equal params (Snakemake
    compares a rule's params by their text): mappings with their keys sorted, sequences as lists, and a whole
    number written where the schema asks for a ``number`` as the float it means (``3`` and ``3.0`` alike).
    Defaults are already filled in by the validation, so a default written out equals one left out."""
    schema = schema if isinstance(schema, dict) else {}
    if isinstance(value, dict):
        props = schema.get("properties") or {}
        extra = schema.get("additionalProperties")
        extra = extra if isinstance(extra, dict) else {}
        patterns = list((schema.get("patternProperties") or {}).values())
        fallback = extra or (patterns[0] if len(patterns) == 1 else {})
        return {k: canonical(value[k], props.get(k, fallback)) for k in sorted(value, key=str)}
    if isinstance(value, (list, tuple)):
        items = schema.get("items")
        prefix = schema.get("prefixItems") or []
        return [canonical(v, prefix[i] if i < len(prefix) else (items if isinstance(items, dict) else {}))
                for i, v in enumerate(value)]
    if isinstance(value, int) and not isinstance(value, bool) and _number_only(schema):
        return float(value)
    return value


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


def relative_to_root(path: str | os.PathLike, root: str | os.PathLike) -> str:
    """The inverse of :func:`resolve_path` for metadata: an input path under the repository ``root`` as the config
    writes it (relative, POSIX), any other path absolute. Products that record their inputs so stay the same bytes
    in every checkout of the repository."""
    p = Path(os.path.abspath(os.path.expanduser(str(path))))
    try:
        return p.relative_to(Path(os.path.abspath(root))).as_posix()
    except ValueError:
        return str(p)


#: The workflow's JSON schemas: the one home of the config's defaults, which the library reads too
#: (:func:`schema_defaults`; natscene is installed editable, in its repository).
SCHEMA_DIR = Path(__file__).resolve().parents[2] / "workflow" / "schemas"


@functools.lru_cache(maxsize=None)
def _bundled(file: str) -> dict:
    path = SCHEMA_DIR / file
    if not path.is_file():
        raise ConfigError(f"schema {path} not found: natscene reads its settings' defaults from workflow/schemas "
                          f"of its repository (install it editable: pip install -e .)")
    return bundle_schema(path)


def schema_section(file: str, path=()) -> dict:
    """The schema of one config section: in ``workflow/schemas/<file>`` (bundled), the object at ``path``, a
    sequence of property names (``additionalProperties`` steps into the entries of a mapping)."""
    node = _bundled(file)
    for part in path:
        node = node[part] if part == "additionalProperties" else node["properties"][part]
    return node


def complete_section(section: dict | None, file: str, path=(), key: str = "config") -> dict:
    """A copy of the config section ``section`` validated through its schema (:func:`schema_section`): the
    schema's defaults filled in (nested objects' too) and :func:`canonical`; :class:`ConfigError` naming ``key``
    when it is invalid."""
    import copy

    bundled = {"$schema": _bundled(file).get("$schema"), **schema_section(file, path)}
    return _validate_bundled(copy.deepcopy(dict(section or {})), bundled, key)


def section_defaults(file: str, path=(), keys=None) -> dict:
    """The schema's defaults of a config section (:func:`schema_section`), of its properties named in ``keys``
    (None: all): an empty section validated through those properties alone (not the section's ``required``),
    defaults filled in (nested ones too), :func:`canonical`."""
    props = schema_section(file, path).get("properties") or {}
    mine = {k: v for k, v in props.items() if keys is None or k in keys}
    bundled = {"$schema": _bundled(file).get("$schema"), "type": "object", "properties": mine}
    return _validate_bundled({}, bundled, f"{file} {'.'.join(path)}")


@functools.lru_cache(maxsize=None)
def _schema_defaults(cls) -> dict:
    import dataclasses

    renames = getattr(cls, "CONFIG_NAMES", {})
    fields = {f.name for f in dataclasses.fields(cls) if f.init}
    out = {}
    for file, path in getattr(cls, "SCHEMA", ()):
        props = schema_section(file, path).get("properties") or {}
        keys = {k for k in props if renames.get(k, k) in fields and k not in out}
        out.update(section_defaults(file, path, keys))
    return out


def schema_defaults(cls) -> dict:
    """The schema's defaults of the fields of settings dataclass ``cls``, by config name: for each ``(file,
    path)`` of ``cls.SCHEMA`` (:func:`schema_section`; the first that has a key wins) an empty section validated
    through the properties that name a field (defaults filled in, nested ones too, canonical). A fresh copy."""
    import copy

    return copy.deepcopy(_schema_defaults(cls))


def default_settings(cls, **changes):
    """The settings dataclass ``cls`` of an empty config section (every field the schema's default,
    :func:`settings_from_section`), with ``changes`` (field names) replaced: the default instance for tests and
    library callers."""
    import dataclasses

    return dataclasses.replace(settings_from_section(cls, None, cls.__name__), **changes)


def settings_from_section(cls, section: dict | None, key: str):
    """A settings dataclass ``cls`` from a config section: the one way the library turns config into settings.

    - ``section`` holds the values (validated: the schema filled its defaults in); a key missing from it takes
      the schema's default (:func:`schema_defaults`: ``cls.SCHEMA`` names the schema sections the fields come
      from; the dataclass holds no default of its own for a configurable field);
    - a key that names no field raises :class:`ConfigError` naming ``<key>.<name>`` and the allowed names
      (the schema and the dataclass disagree, or an open section such as ``patterns.*.rd`` has a typo);
    - a list becomes a tuple where the field is a tuple (``tuple`` annotation or default);
    - ``cls.CONFIG_NAMES`` (optional) maps config names that are not Python identifiers to field names
      (``lambda`` -> ``lam``).
    """
    import dataclasses

    fields = {f.name: f for f in dataclasses.fields(cls) if f.init}
    renames = getattr(cls, "CONFIG_NAMES", {})
    kw = {}
    for name, value in {**schema_defaults(cls), **(section or {})}.items():
        field = renames.get(name, name)
        if field not in fields:
            allowed = sorted({v: k for k, v in renames.items()}.get(f, f) for f in fields)
            raise ConfigError(f"config key '{key}.{name}': unknown setting; allowed: {', '.join(allowed)}")
        f = fields[field]
        is_tuple = isinstance(f.default, tuple) or str(f.type).startswith("tuple")
        kw[field] = tuple(value) if is_tuple and isinstance(value, list) else value
    return cls(**kw)
