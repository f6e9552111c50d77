"""The key tables of config/README.md, generated from the schemas in workflow/schemas/ (their one home).

config/README.md holds hand-written prose and, between the markers

    <!-- config-reference: <section> -->
    ...
    <!-- /config-reference -->

one table per config section (``top`` = the top-level keys): every key with its default, its allowed values and
its meaning, read from the schema. This script rewrites the tables in place; ``--check`` only reports whether
they are up to date (exit status 1 if not; ``tests/test_docs.py`` runs it).

    .venv/bin/python tools/config_reference.py            # rewrite the tables after changing a schema
    .venv/bin/python tools/config_reference.py --check
"""
from __future__ import annotations

import re
import sys
from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parents[1]
SCHEMAS = ROOT / "workflow" / "schemas"
README = ROOT / "config" / "README.md"
BLOCK = re.compile(r"(<!-- config-reference: (?P<name>[\w.$-]+) -->\n)(?P<body>.*?)(<!-- /config-reference -->)", re.S)


def _load(name: str) -> dict:
    return yaml.safe_load((SCHEMAS / name).read_text())


def _resolve(node: dict, root: dict) -> tuple[dict, str | None]:
    """(node with a $ref merged in, name of a referenced object type that is documented once, or None)."""
    ref = node.get("$ref")
    if not ref:
        return node, None
    file_part, _, pointer = ref.partition("#")
    target_root = _load(file_part) if file_part else root
    target = target_root
    for part in [p for p in pointer.split("/") if p]:
        target = target[part]
    merged = {**target, **{k: v for k, v in node.items() if k != "$ref"}}
    if "properties" in target and not file_part:
        return merged, pointer.split("/")[-1]
    return merged, None


def _flow(value) -> str:
    text = yaml.safe_dump(value, default_flow_style=True, width=10_000, sort_keys=False, allow_unicode=True)
    return text.strip().removesuffix("...").strip()


def _num(x) -> str:
    return f"{x:g}" if isinstance(x, float) else str(x)


def _scalar(node: dict) -> str:
    """Allowed values of a scalar node: enum, type and range."""
    if "enum" in node:
        return "one of " + ", ".join(f"`{_flow(v)}`" for v in node["enum"])
    types = node.get("type", [])
    types = [types] if isinstance(types, str) else list(types)
    nullable = "null" in types
    types = [t for t in types if t != "null"]
    lo = ("≥", node["minimum"]) if "minimum" in node else ((">", node["exclusiveMinimum"])
                                                            if "exclusiveMinimum" in node else None)
    hi = ("≤", node["maximum"]) if "maximum" in node else (("<", node["exclusiveMaximum"])
                                                            if "exclusiveMaximum" in node else None)
    base = " or ".join(types) if types else ("any" if "oneOf" not in node else "")
    if lo and hi:
        left = "[" if lo[0] == "≥" else "("
        right = "]" if hi[0] == "≤" else ")"
        base += f" in {left}{_num(lo[1])}, {_num(hi[1])}{right}"
    elif lo:
        base += f" {lo[0]} {_num(lo[1])}"
    elif hi:
        base += f" {hi[0]} {_num(hi[1])}"
    if "multipleOf" in node:
        base += f", multiple of {_num(node['multipleOf'])}"
    if "pattern" in node:
        base += f" matching `{node['pattern']}`"
    return base + (" or null" if nullable else "")


def allowed(node: dict, root: dict, type_name: str | None = None) -> str:
    if type_name:
        return f"{type_name} (see below)" if type_name == "image" else type_name
    if "oneOf" in node:
        return " or ".join(allowed(_resolve(o, root)[0], root) for o in node["oneOf"])
    types = node.get("type", [])
    types = [types] if isinstance(types, str) else list(types)
    if "array" in types:
        items, item_type = _resolve(node.get("items", {}), root)
        inner = allowed(items, root, item_type) if items else "any"
        inner = f"({inner})" if "×" in inner else inner
        n0, n1 = node.get("minItems"), node.get("maxItems")
        if n0 is not None and n0 == n1:
            text = f"{n0} × {inner}"
        elif n0:
            text = f"list of {inner} (≥ {n0} item{'s' if n0 > 1 else ''})"
        else:
            text = f"list of {inner}"
        return text + (" or null" if "null" in types else "")
    if "object" in types or ("properties" in node and not types):
        return "mapping"
    return _scalar(node)


def _cell(text: str) -> str:
    """One table cell: one line, pipes escaped, and <...> outside code spans kept visible (not taken as HTML)."""
    parts = " ".join(str(text).split()).replace("|", "\\|").split("`")
    parts[::2] = [p.replace("<", "&lt;") for p in parts[::2]]
    return "`".join(parts)


def rows(node: dict, root: dict, path: str, required=()) -> list[tuple[str, str, str, str]]:
    """(key, default, allowed, meaning) for every key under ``node``, depth first."""
    out = []
    for name, child in (node.get("properties") or {}).items():
        child, type_name = _resolve(child, root)
        key = f"{path}.{name}" if path else name
        if "default" in child:
            default = f"`{_flow(child['default'])}`"
        else:
            default = "required" if name in required else "—"
        out.append((f"`{key}`", default, _cell(allowed(child, root, type_name)),
                    _cell(child.get("description", ""))))
        if type_name is None:
            out.extend(_children(child, root, key))
    return out


def _children(node: dict, root: dict, key: str) -> list:
    out = []
    if node.get("properties"):
        out.extend(rows(node, root, key, node.get("required", ())))
    ap = node.get("additionalProperties")
    if isinstance(ap, dict):
        ap, _ = _resolve(ap, root)
        out.extend(rows(ap, root, f"{key}.<name>" if key else "<name>", ap.get("required", ())))
    items = node.get("items")
    if isinstance(items, dict):
        items, type_name = _resolve(items, root)
        if type_name is None and items.get("properties"):
            out.extend(rows(items, root, f"{key}[]", items.get("required", ())))
    return out


def table(section: str) -> str:
    if section == "top":
        root = _load("config.schema.yaml")
        props = {k: v for k, v in root["properties"].items() if "$ref" not in v}
        body = rows({"properties": props}, root, "")
    elif section.startswith("$defs."):                 # a shared type, e.g. $defs.composite.image
        _, file, name = section.split(".")
        root = _load(f"{file}.schema.yaml")
        d = root["$defs"][name]
        body = rows(d, root, "", d.get("required", ()))
    else:
        root = _load(f"{section}.schema.yaml")
        body = _children(root, root, "")
    lines = ["| key | default | allowed | meaning |", "|---|---|---|---|"]
    lines += [f"| {k} | {d} | {a} | {m} |" for k, d, a, m in body]
    return "\n".join(lines) + "\n"


def render(text: str) -> str:
    return BLOCK.sub(lambda m: m.group(1) + table(m.group("name")) + m.group(4), text)


def sections_in_config_schema() -> list[str]:
    """The config sections that have a schema file of their own."""
    return [k for k, v in _load("config.schema.yaml")["properties"].items() if "$ref" in v]


def main(argv: list[str]) -> int:
    text = README.read_text()
    new = render(text)
    if "--check" in argv:
        if new != text:
            print(f"{README.relative_to(ROOT)} is out of date with workflow/schemas: run "
                  f"python tools/config_reference.py", file=sys.stderr)
            return 1
        return 0
    if new != text:
        README.write_text(new)
        print(f"updated {README.relative_to(ROOT)}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
