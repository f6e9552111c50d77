"""The documentation (README.md, CONTRIBUTING.md, config/README.md, docs/): checks that need no rendering.

- the README is a front page: under 20 KB and at most 200 lines;
- every relative link and image resolves to a file, and every #anchor to a heading of its target (GitHub's
  heading ids);
- config/README.md lists every key of workflow/schemas with the schema's default (tools/config_reference.py
  --check regenerates its tables and compares);
- every stage has its page, every rule is named in a stage page and in the README's table;
- every ``natscene.x.y`` name the docs mention exists in the source (read with ast, nothing imported);
- the "DESIGN §n" citations of docstrings, rules and schemas resolve to docs/architecture.md;
- no development history ("this session", "the issue's", ...) in the docs.
"""
from __future__ import annotations

import ast
import re
import subprocess
import sys
import unicodedata
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = sorted([ROOT / "README.md", ROOT / "CONTRIBUTING.md", ROOT / "config" / "README.md",
               *(ROOT / "docs").rglob("*.md")])
STAGES = ("volume", "sky", "precompute", "fit", "shots", "mie", "patterns", "leaves", "tiles", "textures",
          "composite")
HISTORY = ("this session", "the issue's", "follow-up)", "honestly", "artefact fixes", "first version of",
           "before the fix", "after the fix", "previous generator", "of today")


def _rel(p: Path) -> str:
    return str(p.relative_to(ROOT))


def _strip_code(text: str) -> str:
    """Markdown without fenced code blocks (their contents are not links)."""
    return re.sub(r"^```.*?^```", "", text, flags=re.S | re.M)


def slug(heading: str) -> str:
    """GitHub's id of a heading: markup dropped, lower case, punctuation removed, spaces to hyphens."""
    h = re.sub(r"\[([^\]]*)\]\([^)]*\)", r"\1", heading)          # [text](link) -> text
    h = h.replace("`", "").replace("*", "").strip().lower()
    keep = []
    for c in h:
        cat = unicodedata.category(c)
        if c in " -_" or cat[0] in "LNM":
            keep.append(c)
    return "".join(keep).replace(" ", "-")


def anchors(path: Path) -> set[str]:
    out, seen = set(), {}
    for line in _strip_code(path.read_text()).splitlines():
        m = re.match(r"#{1,6}\s+(.*?)\s*#*\s*$", line)
        if m:
            s = slug(m.group(1))
            n = seen.get(s, 0)
            out.add(s if n == 0 else f"{s}-{n}")
            seen[s] = n + 1
    return out


def links(path: Path) -> list[str]:
    """Targets of the Markdown links and images of a file (inline ``[..](target)`` form)."""
    text = _strip_code(path.read_text())
    text = re.sub(r"`[^`\n]*`", "", text)                          # code spans are not links
    return re.findall(r"!?\[[^\]]*\]\(([^)\s]+)(?:\s+\"[^\"]*\")?\)", text)


def test_readme_is_a_front_page():
    readme = ROOT / "README.md"
    size, lines = readme.stat().st_size, readme.read_text().count("\n")
    assert size < 20 * 1024, f"README.md is {size} bytes; move detail into docs/ (limit 20 KB)"
    assert lines <= 200, f"README.md has {lines} lines; a front page has at most 200"


@pytest.mark.parametrize("doc", DOCS, ids=_rel)
def test_links_resolve(doc):
    bad = []
    for target in links(doc):
        if re.match(r"[a-z][a-z0-9+.-]*:", target):                 # http:, https:, mailto:
            continue
        file_part, _, anchor = target.partition("#")
        dest = (doc.parent / file_part).resolve() if file_part else doc
        if not dest.exists():
            bad.append(f"{target}: no such file")
        elif anchor and dest.suffix == ".md" and anchor not in anchors(dest):
            bad.append(f"{target}: no heading #{anchor} in {_rel(dest)}")
    assert not bad, f"{_rel(doc)}: broken links:\n  " + "\n  ".join(bad)


def test_slug_follows_github():
    assert slug("The cloud rendering model (Dobashi 2012 Eqs. 3–9)") == "the-cloud-rendering-model-dobashi-2012-eqs-39"
    assert slug("Mie shading per shot: `phase: mie_blend`") == "mie-shading-per-shot-phase-mie_blend"
    assert slug("2. Layout and layers") == "2-layout-and-layers"


def test_config_reference_is_up_to_date():
    r = subprocess.run([sys.executable, str(ROOT / "tools" / "config_reference.py"), "--check"],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr


def test_config_reference_lists_every_schema_key():
    """Independent of the generator: every property name of every schema appears as a key in config/README.md."""
    import yaml
    text = (ROOT / "config" / "README.md").read_text()
    keys = set(re.findall(r"^\| `([^`]+)` \|", text, flags=re.M))
    leaves = {k.split(".")[-1].split("[]")[-1].lstrip(".") for k in keys}

    def names(node):
        if isinstance(node, dict):
            for k, v in (node.get("properties") or {}).items():
                yield k
                yield from names(v)
            for k in ("additionalProperties", "items"):
                if isinstance(node.get(k), dict):
                    yield from names(node[k])
            for d in (node.get("$defs") or {}).values():
                yield from names(d)

    missing = set()
    for schema in (ROOT / "workflow" / "schemas").glob("*.schema.yaml"):
        s = yaml.safe_load(schema.read_text())
        refs = {k for k, v in (s.get("properties") or {}).items() if "$ref" in v}
        missing |= {f"{schema.name}: {n}" for n in names(s) if n not in leaves and n not in refs}
    assert not missing, f"schema keys missing from config/README.md: {sorted(missing)}"


def test_every_stage_has_a_page_and_every_rule_is_documented():
    pages = {s: ROOT / "docs" / "stages" / f"{s}.md" for s in STAGES}
    assert all(p.exists() for p in pages.values()), [s for s, p in pages.items() if not p.exists()]
    rules = set()
    for smk in (ROOT / "workflow" / "rules").glob("*.smk"):
        rules |= set(re.findall(r"^rule (\w+):", smk.read_text(), flags=re.M))
    stage_text = "\n".join(p.read_text() for p in pages.values())
    readme = (ROOT / "README.md").read_text()
    table = "\n".join(line for line in readme.splitlines() if line.startswith("| "))
    assert not [r for r in rules if f"`{r}`" not in stage_text], "rules missing from docs/stages"
    assert not [r for r in rules if f"`{r}`" not in table], "rules missing from the README's table"
    for s in STAGES:
        assert f"docs/stages/{s}.md" in table, f"the README's table has no link to docs/stages/{s}.md"


def _module_file(parts: list[str]) -> Path | None:
    base = ROOT / "src" / Path(*parts)
    for p in (base.with_suffix(".py"), base / "__init__.py"):
        if p.exists():
            return p
    return None


def _defines(tree: ast.AST, name: str) -> ast.AST | None:
    """The top-level statement of ``tree`` that binds ``name`` (def, class, assignment, import), or None."""
    for node in getattr(tree, "body", []):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)) and node.name == name:
            return node
        if isinstance(node, (ast.Assign, ast.AnnAssign)):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            for t in targets:
                for n in ast.walk(t):
                    if isinstance(n, ast.Name) and n.id == name:
                        return node
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            for a in node.names:
                if (a.asname or a.name.split(".")[0]) == name:
                    return node
    return None


def resolve(dotted: str) -> bool:
    """Whether ``natscene.a.b.name[.attr]`` names a module or a top-level name (and a class member) in src/."""
    parts = dotted.split(".")
    i = len(parts)
    while i > 0 and _module_file(parts[:i]) is None:
        i -= 1
    if i == 0:
        return False
    node: ast.AST = ast.parse(_module_file(parts[:i]).read_text())
    for name in parts[i:]:
        found = _defines(node, name)
        if found is None:
            return False
        if isinstance(found, ast.ImportFrom):                       # re-exported: look in the source module
            src = found.module.split(".") if found.module else []
            f = _module_file(src)
            node = ast.parse(f.read_text()) if f else found
            found = _defines(node, name) or found
        node = found
    return True


def test_named_code_exists():
    bad = []
    for doc in DOCS:
        for dotted in sorted(set(re.findall(r"\bnatscene(?:\.[A-Za-z_]\w*)+", doc.read_text()))):
            if any(len(p) == 1 or p == "foo" for p in dotted.split(".")):   # placeholders: natscene.a.b
                continue
            if not resolve(dotted):
                bad.append(f"{_rel(doc)}: {dotted}")
    assert not bad, "names in the docs that the source does not define:\n  " + "\n  ".join(bad)


def test_design_citations_resolve_to_architecture():
    arch = (ROOT / "docs" / "architecture.md").read_text()
    sections = set(re.findall(r"^## (\d+)\. ", arch, flags=re.M))
    titles = re.findall(r"^###+ (.+)$", arch, flags=re.M)
    bad = []
    files = [*(ROOT / "src").rglob("*.py"), *(ROOT / "scripts").glob("*.py"), *(ROOT / "tools").glob("*.py"),
             *(ROOT / "workflow").rglob("*.smk"), *(ROOT / "workflow").rglob("*.yaml"), *DOCS]
    for f in files:
        if f.name == "architecture.md":
            continue
        for m in re.finditer(r"DESIGN(?:\.md)?[^)\n]*", f.read_text()):
            cite = m.group(0)
            for a, b in re.findall(r"§(\d)(?:[-–](\d))?", cite):
                bad += [f"{_rel(f)}: {cite} (no §{n})" for n in (a, b) if n and n not in sections]
            for name in re.findall(r"(?:§\d(?:[-–]\d)?,?\s*|DESIGN(?:\.md)?,\s*)\"?([A-Z][A-Za-z .]+?)\"?$", cite):
                if not any(t.startswith(name.strip()) for t in titles):
                    bad.append(f"{_rel(f)}: {cite} (no subsection {name!r})")
    assert not bad, "citations of the design that docs/architecture.md does not hold:\n  " + "\n  ".join(bad)


@pytest.mark.parametrize("doc", DOCS, ids=_rel)
def test_docs_describe_the_product_not_its_history(doc):
    text = doc.read_text().lower()
    found = [p for p in HISTORY if p in text]
    assert not found, f"{_rel(doc)}: development history ({found}); it belongs in commit messages"


def test_no_commit_of_this_repository_is_named():
    """The docs describe today's pipeline; history (and commit hashes) goes to CHANGELOG.md. Every token of 7 or
    more hex digits in README.md and docs/ is checked against this repository's objects."""
    if not (ROOT / ".git").exists():
        pytest.skip("not a git checkout")
    bad = []
    for doc in [ROOT / "README.md", *(ROOT / "docs").rglob("*.md")]:
        for token in sorted(set(re.findall(r"\b[0-9a-f]{7,40}\b", doc.read_text()))):
            if subprocess.run(["git", "-C", str(ROOT), "cat-file", "-e", f"{token}^{{commit}}"],
                              capture_output=True).returncode == 0:
                bad.append(f"{_rel(doc)}: {token}")
    assert not bad, "commits named in the docs:\n  " + "\n  ".join(bad)


def test_docs_img_holds_only_images_the_docs_show():
    shown = {(d.parent / t).resolve() for d in DOCS for t in links(d) if not re.match(r"[a-z]+:", t)}
    unused = [_rel(p) for p in sorted((ROOT / "docs" / "img").iterdir()) if p.resolve() not in shown]
    assert not unused, f"images no doc shows (delete them or show them): {unused}"
