"""Code fingerprints for Snakemake rerun triggers.

Snakemake tracks a rule's script but not the library it imports. Every rule passes
``fingerprint(<domains>)`` as a ``param``: a hash of the *content* of the library modules that rule uses,
so editing one of them (not merely touching its mtime) makes Snakemake rerun exactly the rules that
depend on it.
"""
from __future__ import annotations

import hashlib
from functools import lru_cache
from pathlib import Path

PACKAGE_DIR = Path(__file__).resolve().parent


@lru_cache(maxsize=None)
def _files(domain: str) -> tuple[Path, ...]:
    d = PACKAGE_DIR / domain.replace(".", "/")
    if d.is_dir():
        return tuple(sorted(d.rglob("*.py")))
    f = d.with_suffix(".py")
    if f.is_file():
        return (f,)
    raise ValueError(f"fingerprint: no module or package 'natscene.{domain}'")


def fingerprint(*domains: str) -> str:
    """sha256 (16 hex digits) of the source of ``natscene.<domain>`` for each domain (package or module)."""
    h = hashlib.sha256()
    for domain in sorted(set(domains)):
        for f in _files(domain):
            h.update(str(f.relative_to(PACKAGE_DIR)).encode())
            h.update(f.read_bytes())
    return h.hexdigest()[:16]
