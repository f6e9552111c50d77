"""Code fingerprints computed from the code (natscene.fingerprint): each rule's fingerprint covers its script's
whole import closure inside natscene, checked against the standard library's modulefinder (an independent
bytecode scan), including lazy imports inside functions and importlib.import_module with a literal name; it
follows the code's meaning (comments, docstrings and layout do not count)."""
import modulefinder
import re
import shutil
from pathlib import Path

import pytest

from natscene.fingerprint import closure_modules, import_closure, script_fingerprint

ROOT = Path(__file__).resolve().parents[1]
SCRIPTS = sorted((ROOT / "scripts").glob("*.py"))


def _modulefinder_closure(script: Path, src: Path) -> set[str]:
    mf = modulefinder.ModuleFinder(path=[str(src)])
    mf.run_script(str(script))
    return {m for m in mf.modules if m == "natscene" or m.startswith("natscene.")}


@pytest.mark.parametrize("script", SCRIPTS, ids=[s.name for s in SCRIPTS])
def test_closure_matches_modulefinder(script):
    assert set(closure_modules(script)) == _modulefinder_closure(script, ROOT / "src")


def test_every_rule_fingerprints_its_own_script():
    """No hand-kept lists: every rule with a script passes code=script_fingerprint(<that script>)."""
    for smk in sorted((ROOT / "workflow" / "rules").glob("*.smk")):
        text = smk.read_text()
        assert "fingerprint(" not in text.replace("script_fingerprint(", ""), smk
        for block in re.split(r"(?m)^(?=rule )", text)[1:]:
            rule = re.match(r"rule (\w+):", block).group(1)
            script = re.search(r'script_path\("([^"]+)"\)', block)
            if script is None:
                continue
            assert f'code=script_fingerprint("{script.group(1)}")' in block, f"{smk.name}: rule {rule}"
            assert "mem_mb=estimated_mem_mb(" in block, f"{smk.name}: rule {rule} declares no computed mem_mb"


def _package(tmp_path: Path) -> tuple[Path, Path]:
    pkg = tmp_path / "src" / "natscene"
    (pkg / "sub").mkdir(parents=True)
    (pkg / "__init__.py").write_text("")
    (pkg / "sub" / "__init__.py").write_text("from . import leaf  # noqa\n")
    (pkg / "sub" / "leaf.py").write_text("X = 1\n")
    (pkg / "lazy.py").write_text("def f():\n    from natscene.deep import y\n    return y\n")
    (pkg / "deep.py").write_text("import importlib\ny = importlib.import_module('natscene.dyn')\n")
    (pkg / "dyn.py").write_text("Z = 2\n")
    (pkg / "unused.py").write_text("W = 3\n")
    script = tmp_path / "scripts" / "s.py"
    script.parent.mkdir()
    script.write_text("import numpy\nfrom natscene.sub import leaf\n\ndef main():\n    import natscene.lazy\n")
    return pkg, script


def test_lazy_relative_and_importlib_imports_are_followed(tmp_path):
    pkg, script = _package(tmp_path)
    names = {p.relative_to(pkg).as_posix() for p in import_closure(script, pkg)}
    assert names == {"__init__.py", "sub/__init__.py", "sub/leaf.py", "lazy.py", "deep.py", "dyn.py"}


def test_fingerprint_changes_exactly_with_the_closure(tmp_path):
    pkg, script = _package(tmp_path)
    before = script_fingerprint(script, pkg)
    (pkg / "unused.py").write_text("W = 4\n")
    import natscene.fingerprint as fp
    fp._direct.cache_clear()
    assert script_fingerprint(script, pkg) == before  # not imported: no rerun
    (pkg / "dyn.py").write_text("Z = 3\n")  # reached only through a lazy import, then importlib
    assert script_fingerprint(script, pkg) != before


def test_comments_docstrings_and_layout_do_not_count(tmp_path):
    """A comment, a docstring or a reformatting leaves the fingerprint alone; a changed constant does not."""
    pkg, script = _package(tmp_path)
    import natscene.fingerprint as fp
    before = script_fingerprint(script, pkg)
    (pkg / "dyn.py").write_text('"""The dynamic module."""\n# a comment\nZ   =   2  # two\n')
    (pkg / "lazy.py").write_text('def f():\n    """Docs."""\n    from natscene.deep import (y)\n\n    return y\n')
    fp._direct.cache_clear()
    assert script_fingerprint(script, pkg) == before
    (pkg / "dyn.py").write_text('"""The dynamic module."""\nZ = 3\n')
    assert script_fingerprint(script, pkg) != before
    (pkg / "dyn.py").write_text("Z = 2\n")
    (pkg / "lazy.py").write_text("def f():\n    from natscene.deep import y\n    return y + 0\n")
    assert script_fingerprint(script, pkg) != before


def test_the_cache_on_disk_changes_nothing(tmp_path, monkeypatch):
    """What the parse gives is kept on disk (natscene.fingerprint.cache_file), keyed by the files' bytes: a cold,
    a warm (no file parsed: the parse raises) and a corrupt cache give the same fingerprint; an edit to the code
    changes it though the cache holds the old one, to what a cold cache gives; an unwritable cache is no error."""
    import json

    import natscene.fingerprint as fp
    pkg, script = _package(tmp_path)

    def fresh(cache: Path) -> str:                       # as a new Snakemake process with this cache
        monkeypatch.setenv("XDG_CACHE_HOME", str(cache))
        monkeypatch.setattr(fp, "_CACHE", None)
        fp._direct.cache_clear()
        return script_fingerprint(script, pkg)

    def boom(*args, **kwargs):
        raise AssertionError("parsed although the cache holds the answer")

    cold = fresh(tmp_path / "cache")
    assert fp.cache_file() == tmp_path / "cache" / "natscene" / fp.cache_file().name and fp.cache_file().is_file()
    with monkeypatch.context() as m:
        m.setattr(fp, "imported_names", boom)
        m.setattr(fp, "meaning", boom)
        fp._file_meaning.cache_clear()
        assert fresh(tmp_path / "cache") == cold
    fp.cache_file().write_text('{"imports": [1, 2')
    assert fresh(tmp_path / "cache") == cold
    assert set(json.loads(fp.cache_file().read_text())) == {"imports", "fingerprints"}
    (pkg / "dyn.py").write_text("Z = 3\n")              # reached through a lazy import, then importlib
    edited = fresh(tmp_path / "cache")
    assert edited != cold and edited == fresh(tmp_path / "cold")
    (tmp_path / "a_file").write_text("")
    assert fresh(tmp_path / "a_file" / "cache") == edited


def test_every_module_of_the_package_has_a_meaning():
    """meaning() parses every natscene module; a trailing comment does not change it."""
    from natscene.fingerprint import meaning
    for f in sorted((ROOT / "src" / "natscene").rglob("*.py")):
        text = f.read_text()
        m = meaning(text)
        assert m.startswith("Module(")
        assert meaning(text + "\n# trailing comment\n") == m


def test_ground_floor_module_reaches_every_script_that_imports_it(tmp_path):
    """Editing natscene/color.py changes the fingerprint of exactly the scripts whose closure holds it."""
    src = tmp_path / "src"
    shutil.copytree(ROOT / "src" / "natscene", src / "natscene", ignore=shutil.ignore_patterns("__pycache__"))
    pkg = src / "natscene"
    for module in ("color.py", "geometry.py"):
        before = {s.name: script_fingerprint(s, pkg) for s in SCRIPTS}
        users = {s.name for s in SCRIPTS if f"natscene.{module[:-3]}" in _modulefinder_closure(s, src)}
        f = pkg / module
        f.write_text(f.read_text() + "\n_AN_EDIT = 1\n")
        after = {s.name: script_fingerprint(s, pkg) for s in SCRIPTS}
        changed = {n for n in before if before[n] != after[n]}
        assert changed == users, (module, changed ^ users)
        assert users, module
    assert "sky.py" not in {s.name for s in SCRIPTS if "natscene.geometry" in _modulefinder_closure(s, src)}
