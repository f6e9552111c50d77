"""The package's import structure, read from the source with ast (nothing is imported): no import cycles, no arrow
from the shared lower layer up into a stage package, no private name imported across packages, the error classes
imported from their one home, no importlib loads.

Layers (CONTRIBUTING.md, "Layout"):

- the lower layer: modules every stage may use, which import only each other (and third-party libraries):
  ``errors``, ``io``, ``config``, ``color``, ``geometry``, ``phase``, ``preview``, ``variant``, ``llvm``,
  ``fingerprint``, ``runner`` and the package root;
- the stage packages (``natscene.<stage>``: volume, sky, scatter, fit, keyframes, mie, patterns, leaves, tiles,
  spectral, composite, denoise), which may import the lower layer and each other (never in a cycle);
- the workflow layer: ``config_checks`` and ``resources`` (the checks and memory model of a whole config), which
  may import anything; nothing in the package imports them.

The folders around the package (``benchmarks/``, ``tools/``, ``experiments/``: flat scripts that put each other on
``sys.path``) import no private name of the package or of a script in another folder, and nothing outside
``tests/`` imports a module of ``tests/`` (shared scenes live in the package, e.g.
``natscene.scatter.reference_scene``). Every module declares its public names in ``__all__``, and what the
repository imports from a module is among them.
"""
from __future__ import annotations

import ast
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGE_DIR = ROOT / "src" / "natscene"
SCRIPTS = sorted((ROOT / "scripts").glob("*.py"))
OUTSIDE = ("benchmarks", "tools", "experiments")  # folders of flat scripts around the package

LOWER = {"natscene", "natscene.errors", "natscene.io", "natscene.config", "natscene.color", "natscene.geometry",
         "natscene.phase", "natscene.preview", "natscene.variant", "natscene.llvm", "natscene.fingerprint",
         "natscene.runner"}
WORKFLOW = {"natscene.config_checks", "natscene.resources"}
ERRORS = {"InputError": "natscene.errors", "ConfigError": "natscene.errors"}


def rel(path: Path) -> str:
    try:
        return str(path.relative_to(ROOT))
    except ValueError:
        return str(path)


def module_name(path: Path) -> str:
    parts = list(path.relative_to(PACKAGE_DIR).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(["natscene", *parts])


MODULES = {module_name(p): p for p in sorted(PACKAGE_DIR.rglob("*.py"))}


def layer(module: str) -> str:
    """'lower', 'workflow', or the stage package's name."""
    if module in LOWER:
        return "lower"
    if module in WORKFLOW:
        return "workflow"
    return module.split(".")[1]


def imports(path: Path, module: str | None) -> list[tuple[str, str | None, int]]:
    """(imported natscene module, imported name or None, line) for every import statement of a file, at any depth
    (lazy imports inside functions count). ``from a.b import c`` gives module ``a.b.c`` when that is a module."""
    tree = ast.parse(path.read_text())
    out = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out += [(a.name, None, node.lineno) for a in node.names if a.name.split(".")[0] == "natscene"]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                pkg = module.split(".") if path.name == "__init__.py" else module.split(".")[:-1]
                pkg = pkg[:len(pkg) - (node.level - 1)]
                base = ".".join(pkg + ([node.module] if node.module else []))
            else:
                base = node.module or ""
            if base.split(".")[0] != "natscene":
                continue
            for a in node.names:
                sub = f"{base}.{a.name}"
                out.append((sub, None, node.lineno) if sub in MODULES else (base, a.name, node.lineno))
    return out


EDGES = {m: sorted({t for t, _, _ in imports(p, m) if t in MODULES and t != m}) for m, p in MODULES.items()}


def test_the_walk_sees_the_package():
    # guards the test itself: the package is where we look, and known arrows are found
    assert len(MODULES) > 100
    assert "natscene.errors" in EDGES["natscene.io"]
    assert "natscene.patterns.reaction_diffusion.explicit" in EDGES["natscene.patterns.reaction_diffusion.simulate"]


def test_no_import_cycles():
    """Tarjan's strongly connected components of the module graph: every component is a single module."""
    index, low, stack, on, cycles = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in EDGES[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                cycles.append(sorted(comp))

    for v in MODULES:
        if v not in index:
            visit(v)
    assert not cycles, f"import cycles: {cycles}"


def test_no_cycles_between_stage_packages():
    graph = {}
    for m, targets in EDGES.items():
        for t in targets:
            a, b = layer(m), layer(t)
            if a != b and "lower" not in (a, b) and "workflow" not in (a, b):
                graph.setdefault(a, set()).add(b)

    def reaches(a, b, seen=()):
        return any(n == b or (n not in seen and reaches(n, b, (*seen, n))) for n in graph.get(a, ()))

    cycles = sorted((a, b) for a in graph for b in graph[a] if reaches(b, a))
    assert not cycles, f"stage packages importing each other in a cycle: {cycles}"


def test_lower_layer_imports_no_stage_package():
    bad = [f"{m} imports {t}" for m, targets in EDGES.items() if layer(m) == "lower"
           for t in targets if layer(t) != "lower"]
    assert not bad, "arrows from the lower layer up into stage packages:\n" + "\n".join(bad)


def test_nothing_imports_the_workflow_layer():
    bad = [f"{m} imports {t}" for m, targets in EDGES.items() if layer(m) != "workflow"
           for t in targets if layer(t) == "workflow"]
    assert not bad, "\n".join(bad)


@pytest.mark.parametrize("kind", ["package", "scripts"])
def test_no_private_names_across_packages(kind):
    files = MODULES.items() if kind == "package" else [(None, p) for p in SCRIPTS]
    bad = []
    for m, p in files:
        for target, name, line in imports(p, m):
            if name is None:
                private = any(part.startswith("_") and not part.startswith("__") for part in target.split("."))
            else:
                private = name.startswith("_") and not name.startswith("__")
            if private and (m is None or layer(target) != layer(m)):
                bad.append(f"{rel(p)}:{line}: {target}{'.' + name if name else ''}")
    assert not bad, "private names imported across packages:\n" + "\n".join(bad)


@pytest.mark.parametrize("kind", ["package", "scripts"])
def test_error_classes_come_from_natscene_errors(kind):
    files = MODULES.items() if kind == "package" else [(None, p) for p in SCRIPTS]
    bad = [f"{rel(p)}:{line}: {name} from {target}" for m, p in files
           for target, name, line in imports(p, m) if name in ERRORS and target != ERRORS[name]]
    assert not bad, "import InputError / ConfigError from natscene.errors:\n" + "\n".join(bad)


@pytest.mark.parametrize("kind", ["package", "scripts"])
def test_plain_imports_only(kind):
    """No importlib.import_module / __import__ / spec_from_file_location: the import graph is what the
    import statements say (natscene.fingerprint reads the same statements)."""
    files = list(MODULES.values()) if kind == "package" else SCRIPTS
    bad = []
    for p in files:
        for node in ast.walk(ast.parse(p.read_text())):
            if isinstance(node, ast.Call):
                f = node.func
                name = f.attr if isinstance(f, ast.Attribute) else (f.id if isinstance(f, ast.Name) else "")
                if name in ("import_module", "__import__", "spec_from_file_location"):
                    bad.append(f"{rel(p)}:{node.lineno}: {name}")
    assert not bad, "\n".join(bad)


def declared_all(path: Path) -> list[str] | None:
    """The names of a module's ``__all__`` (a literal list or tuple at module level), or None without one."""
    for node in ast.parse(path.read_text()).body:
        targets = node.targets if isinstance(node, ast.Assign) else [node.target] if isinstance(node, ast.AnnAssign) \
            else []
        if any(isinstance(t, ast.Name) and t.id == "__all__" for t in targets) and node.value is not None:
            return [e.value for e in node.value.elts]
    return None


def defined_names(path: Path) -> set[str]:
    """Names a module binds at its top level (definitions, assignments, imports)."""
    out = set()
    for node in ast.parse(path.read_text()).body:
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            out.add(node.name)
        elif isinstance(node, (ast.Assign, ast.AnnAssign)):
            for t in node.targets if isinstance(node, ast.Assign) else [node.target]:
                out |= {n.id for n in ast.walk(t) if isinstance(n, ast.Name)}
        elif isinstance(node, (ast.Import, ast.ImportFrom)):
            out |= {(a.asname or a.name).split(".")[0] for a in node.names}
    return out


def test_every_module_declares_its_public_names():
    """Each module has an ``__all__`` whose names it defines, and every name that code of the repository imports
    from a module (the package, scripts, benchmarks, tools, experiments, tests) is in that module's ``__all__``."""
    problems = []
    for m, p in MODULES.items():
        names = declared_all(p)
        if names is None:
            problems.append(f"{rel(p)}: no __all__")
        else:
            problems += [f"{rel(p)}: __all__ names {n!r}, which it does not define"
                         for n in names if n not in defined_names(p)]
    users = list(MODULES.items()) + [(None, p) for folder in ("scripts", "tests", *OUTSIDE)
                                     for p in sorted((ROOT / folder).rglob("*.py"))]
    for m, p in users:
        for target, name, line in imports(p, m):
            if name is None or target not in MODULES or name.startswith("_"):
                continue
            names = declared_all(MODULES[target]) or []
            if name not in names and name != "*":
                problems.append(f"{rel(p)}:{line}: imports {name} from {target}, not in its __all__")
    assert not problems, "\n".join(problems)


def outside_problems(root: Path = ROOT) -> list[str]:
    """Imports of a private name from another folder or the package, and imports of tests/, in the scripts of
    ``benchmarks/``, ``tools/`` and ``experiments/`` under ``root``."""
    tests = {p.stem for p in (root / "tests").glob("*.py")}
    homes = {p.stem: p.parent for folder in ("scripts", *OUTSIDE) for p in (root / folder).rglob("*.py")}
    bad = []
    for folder in OUTSIDE:
        for p in sorted((root / folder).rglob("*.py")):
            where = f"{p.relative_to(root)}"
            for node in ast.walk(ast.parse(p.read_text())):
                if isinstance(node, ast.Import):
                    pairs = [(a.name, None) for a in node.names]
                elif isinstance(node, ast.ImportFrom) and not node.level:
                    pairs = [(node.module or "", a.name) for a in node.names]
                else:
                    continue
                for module, name in pairs:
                    top = module.split(".")[0]
                    if top in tests and top not in homes:
                        bad.append(f"{where}:{node.lineno}: imports tests/{top}.py")
                    parts = module.split(".") + ([name] if name else [])
                    private = [x for x in parts if x.startswith("_") and not x.startswith("__")]
                    foreign = top == "natscene" or (top in homes and homes[top] != p.parent)
                    if private and foreign:
                        bad.append(f"{where}:{node.lineno}: private {module}{'.' + name if name else ''}")
            if "\"tests\")" in p.read_text() and "sys.path.insert" in p.read_text():
                bad.append(f"{where}: puts tests/ on sys.path")
    return bad


def test_benchmarks_tools_and_experiments_import_no_private_name_and_no_test():
    assert len([p for f in OUTSIDE for p in (ROOT / f).rglob("*.py")]) > 20  # the walk sees the folders
    bad = outside_problems()
    assert not bad, "\n".join(bad)


def test_the_outside_check_fails_on_planted_imports(tmp_path):
    for folder in ("tests", "scripts", *OUTSIDE):
        (tmp_path / folder).mkdir()
    (tmp_path / "tests" / "test_thing.py").write_text("X = 1\n")
    (tmp_path / "benchmarks" / "_common.py").write_text("def f(): pass\n")
    (tmp_path / "benchmarks" / "ok.py").write_text("from _common import f\n")                  # same folder: fine
    (tmp_path / "tools" / "a.py").write_text("from natscene.scatter.tables import _node_noise\n")
    (tmp_path / "tools" / "b.py").write_text("from _common import f\n")                        # another folder
    (tmp_path / "experiments" / "c.py").write_text("def g():\n    from test_thing import X\n")
    assert sorted(outside_problems(tmp_path)) == [
        "experiments/c.py:2: imports tests/test_thing.py",
        "tools/a.py:1: private natscene.scatter.tables._node_noise",
        "tools/b.py:1: private _common.f"]


def test_the_checks_can_fail(tmp_path, monkeypatch):
    """The walk on a planted package: a cycle, an upward arrow and a private import are found."""
    pkg = tmp_path / "natscene"
    (pkg / "sky").mkdir(parents=True)
    (pkg / "__init__.py").write_text("")
    (pkg / "sky" / "__init__.py").write_text("")
    (pkg / "io.py").write_text("from natscene.sky.a import f\n")                      # lower -> stage
    (pkg / "sky" / "a.py").write_text("from natscene.sky.b import g\ndef f(): pass\n")
    (pkg / "sky" / "b.py").write_text("def g():\n    from natscene.sky.a import f\n")  # a <-> b (lazy)
    (pkg / "geometry.py").write_text("from natscene.sky.a import _h\n")                # private, across
    this = sys.modules[__name__]
    monkeypatch.setattr(this, "PACKAGE_DIR", pkg)
    mods = {module_name(p): p for p in sorted(pkg.rglob("*.py"))}
    monkeypatch.setattr(this, "MODULES", mods)
    edges = {m: sorted({t for t, _, _ in imports(p, m) if t in mods and t != m}) for m, p in mods.items()}
    monkeypatch.setattr(this, "EDGES", edges)
    with pytest.raises(AssertionError, match=r"import cycles: \[\['natscene.sky.a', 'natscene.sky.b'\]\]"):
        test_no_import_cycles()
    with pytest.raises(AssertionError, match="natscene.io imports natscene.sky.a"):
        test_lower_layer_imports_no_stage_package()
    with pytest.raises(AssertionError, match=r"geometry.py:1: natscene.sky.a._h"):
        test_no_private_names_across_packages("package")
