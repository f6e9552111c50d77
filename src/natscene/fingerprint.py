"""
Code fingerprints
=================

Defines the code fingerprints of the Snakemake rerun triggers, computed from the code itself:

-   :func:`script_fingerprint`: the hash of the meaning of a rule script and of its import closure.
-   :func:`import_closure`, :func:`closure_modules`: the ``natscene`` files (or module names) a script can execute.
-   :func:`meaning`: a source text's syntax tree without docstrings.

Snakemake tracks a rule's script but not the library it imports. Every rule passes
``code=script_fingerprint("<script>.py")`` as a ``param``: a hash of the *meaning* of every ``natscene``
module the script can execute, so changing the code of one of them makes Snakemake rerun exactly the rules that
depend on it, and no hand-kept list can drift from the imports. The meaning of a module is its syntax tree
without docstrings (:func:`meaning`: ``ast.dump`` without line numbers), so comments, docstrings and layout do
not count; the same code on another Python version may dump differently, and then reruns once.

The set of modules (the script's *import closure* inside ``natscene``) is found by parsing the source with
:mod:`ast`, never by importing it: every ``import natscene.x`` / ``from natscene.x import y`` / relative
import, at module level or inside a function (lazy imports count), and every
``importlib.import_module("natscene.x")`` with a literal name; then the same for each module found,
transitively. Importing ``natscene.a.b`` also executes the package ``__init__`` files on the way
(``natscene/__init__.py``, ``natscene/a/__init__.py``), so those are part of the closure too.

Parsing every file is most of a ``snakemake -n``'s own time, and Snakemake parses the workflow anew in every
process, so what the parse gives is kept on disk (:func:`cache_file`, under ``$XDG_CACHE_HOME/natscene`` or
``~/.cache/natscene``): a file's direct imports keyed by the sha256 of its bytes, a script's fingerprint keyed by
the sha256 of its bytes and of every file of its closure with their paths. The keys are the bytes themselves, so
an entry can never stand for other code; a missing, unreadable or corrupt cache is parsed afresh, and a cache that
cannot be written is left alone.
"""
from __future__ import annotations

import ast
import hashlib
import json
import os
import sys
import tempfile
from functools import lru_cache
from pathlib import Path

__all__ = ["script_fingerprint", "import_closure", "closure_modules", "meaning", "cache_file"]

PACKAGE = "natscene"
PACKAGE_DIR = Path(__file__).resolve().parent
CACHE_ENTRIES = 4096         # most entries of each kind the cache keeps (the newest)


def cache_file() -> Path:
    """Where the parse's results are kept: ``$XDG_CACHE_HOME/natscene/`` (``~/.cache/natscene/``), one file per
    Python version (the syntax tree's dump, hence the fingerprint, may differ between versions)."""
    base = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache")
    return base / PACKAGE / f"fingerprints-py{sys.version_info[0]}.{sys.version_info[1]}.json"


_CACHE: dict | None = None


def _cache() -> dict:
    global _CACHE
    if _CACHE is None:
        try:
            data = json.loads(cache_file().read_text())
            _CACHE = {k: dict(data[k]) for k in ("imports", "fingerprints")}
        except (OSError, ValueError, KeyError, TypeError):
            _CACHE = {"imports": {}, "fingerprints": {}}
    return _CACHE


def _remember(kind: str, key: str, value) -> None:
    """Add one entry to the cache in memory (:func:`_save` writes it)."""
    entries = _cache()[kind]
    entries[key] = value
    while len(entries) > CACHE_ENTRIES:
        del entries[next(iter(entries))]


def _save() -> None:
    """Write the cache (atomically: a concurrent reader sees the old file or the new)."""
    f = cache_file()
    try:
        f.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=f.parent, prefix=f.name, suffix=".tmp")
        with os.fdopen(fd, "w") as out:
            json.dump(_cache(), out)
        os.replace(tmp, f)
    except OSError:
        pass


@lru_cache(maxsize=None)
def _bytes(path: Path, mtime_ns: int, size: int) -> tuple[bytes, str]:
    data = path.read_bytes()
    return data, hashlib.sha256(data).hexdigest()


def _source(path: Path) -> tuple[bytes, str]:
    """A file's bytes and their sha256 (read once per process and version of the file)."""
    st = path.stat()
    return _bytes(path, st.st_mtime_ns, st.st_size)


def _module_file(dotted: str, package_dir: Path) -> Path | None:
    """The source file of ``natscene.<...>`` (module or package ``__init__``), or None."""
    parts = dotted.split(".")
    if parts[0] != PACKAGE:
        return None
    base = package_dir.joinpath(*parts[1:])
    if (base / "__init__.py").is_file():
        return base / "__init__.py"
    f = base.with_suffix(".py")
    return f if len(parts) > 1 and f.is_file() else None


def _with_parents(dotted: str) -> list[str]:
    """``a.b.c`` -> ``[a, a.b, a.b.c]``: importing a module runs its packages' ``__init__`` first."""
    parts = dotted.split(".")
    return [".".join(parts[:i]) for i in range(1, len(parts) + 1)]


def _module_name(path: Path, package_dir: Path) -> str | None:
    try:
        rel = path.resolve().relative_to(package_dir)
    except ValueError:
        return None  # a script outside the package
    parts = list(rel.with_suffix("").parts)
    if parts and parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join([PACKAGE, *parts])


def imported_names(source: str, module: str | None = None, is_package: bool = False) -> set[str]:
    """Dotted ``natscene`` names a source text can import (anywhere in the file), before resolution.

    ``module``: the dotted name of the file itself (for relative imports); None for a script.
    ``from pkg import name`` yields both ``pkg`` and ``pkg.name`` (the name may be a submodule; names
    that are not modules are dropped when resolved to files).
    """
    tree = ast.parse(source)
    names: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                if module is None:
                    continue  # a relative import in a script: not inside natscene
                pkg = module.split(".") if is_package else module.split(".")[:-1]
                pkg = pkg[:len(pkg) - (node.level - 1)] if node.level > 1 else pkg
                base = ".".join(pkg + ([node.module] if node.module else []))
            else:
                base = node.module or ""
            names.add(base)
            names.update(f"{base}.{a.name}" for a in node.names if a.name != "*")
        elif isinstance(node, ast.Call):
            f = node.func
            fname = f.attr if isinstance(f, ast.Attribute) else (f.id if isinstance(f, ast.Name) else "")
            if fname in ("import_module", "__import__") and node.args and isinstance(node.args[0], ast.Constant) \
                    and isinstance(node.args[0].value, str):
                names.add(node.args[0].value)
    return {n for n in names if n == PACKAGE or n.startswith(PACKAGE + ".")}


@lru_cache(maxsize=None)
def _direct(path: Path, package_dir: Path) -> tuple[Path, ...]:
    """natscene files imported directly by ``path`` (with their packages' ``__init__`` files)."""
    module = _module_name(path, package_dir)
    data, sha = _source(path)
    key = f"{sha}:{module}:{path.name == '__init__.py'}"
    names = _cache()["imports"].get(key)
    if names is None:
        names = sorted(imported_names(data.decode(), module, path.name == "__init__.py"))
        _remember("imports", key, names)
    files = set()
    for name in names:
        for dotted in _with_parents(name):
            f = _module_file(dotted, package_dir)
            if f is not None:
                files.add(f)
    if module is not None:  # a module's own packages run before it
        for dotted in _with_parents(module)[:-1]:
            f = _module_file(dotted, package_dir)
            if f is not None:
                files.add(f)
    return tuple(sorted(files))


def import_closure(path: str | Path, package_dir: str | Path = PACKAGE_DIR) -> tuple[Path, ...]:
    """Every ``natscene`` source file that ``path`` (a script or a module) can execute, sorted."""
    package_dir = Path(package_dir).resolve()
    start = Path(path).resolve()
    seen: set[Path] = set()
    todo = [start]
    while todo:
        cur = todo.pop()
        for f in _direct(cur, package_dir):
            if f not in seen:
                seen.add(f)
                todo.append(f)
    seen.discard(start)
    return tuple(sorted(seen))


def closure_modules(path: str | Path, package_dir: str | Path = PACKAGE_DIR) -> list[str]:
    """The import closure of ``path`` as dotted module names (for messages and tests)."""
    package_dir = Path(package_dir).resolve()
    return sorted(_module_name(f, package_dir) for f in import_closure(path, package_dir))


def _docstring(node) -> bool:
    body = getattr(node, "body", None)
    return bool(body) and isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant) \
        and isinstance(body[0].value.value, str)


def meaning(source: str) -> str:
    """The code of a source text without what does not run: its syntax tree with the docstrings of the module,
    its classes and functions removed, dumped without positions (comments and layout never reach the tree)."""
    tree = ast.parse(source)
    for node in ast.walk(tree):
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)) and _docstring(node):
            node.body = node.body[1:] or [ast.Pass()]
    return ast.dump(tree, include_attributes=False)


@lru_cache(maxsize=None)
def _file_meaning(path: Path, sha: str) -> bytes:
    """:func:`meaning` of a file whose bytes have the sha256 ``sha`` (:func:`_source`)."""
    return meaning(_source(path)[0].decode()).encode()


def script_fingerprint(script: str | Path, package_dir: str | Path = PACKAGE_DIR) -> str:
    """sha256 (16 hex digits) of the meaning of the rule script and of every natscene file in its import closure.

    The workflow profiles turn Snakemake's own code trigger off (it hashes the script's bytes, so a comment would
    rerun the rule): this fingerprint, a param of every rule, is what reruns a rule whose code changed.
    """
    package_dir = Path(package_dir).resolve()
    script = Path(script)
    closure = import_closure(script, package_dir)
    k = hashlib.sha256(_source(script.resolve())[1].encode())
    for f in closure:
        k.update(f"\0{f.relative_to(package_dir)}\0{_source(f)[1]}".encode())
    key = k.hexdigest()
    cached = _cache()["fingerprints"].get(key)
    if cached is not None:
        return cached
    h = hashlib.sha256()
    h.update(b"script\0")
    h.update(_file_meaning(script.resolve(), _source(script.resolve())[1]))
    for f in closure:
        h.update(str(f.relative_to(package_dir)).encode())
        h.update(b"\0")
        h.update(_file_meaning(f, _source(f)[1]))
    _remember("fingerprints", key, h.hexdigest()[:16])
    _save()
    return h.hexdigest()[:16]
