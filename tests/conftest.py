"""Shared test set-up: the library on the path (also without an editable install), a pinned Dr.Jit thread
count and a per-session kernel cache."""
import os
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))

import natscene  # noqa: E402,F401  (exports DRJIT_LIBLLVM_PATH before anything imports drjit)


@pytest.fixture(scope="session")
def smoke_run(tmp_path_factory):
    """(repo copy, workdir, process) of one finished run of the smoke workflow (tests/smoke.py), shared by the
    workflow and rerun tests; a test that edits the copy or the run restores them."""
    from smoke import start
    return start(tmp_path_factory.mktemp("smoke"))
