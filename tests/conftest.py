"""Shared test set-up: the library on the path (also without an editable install), a pinned Dr.Jit thread
count and a per-session kernel cache."""
import os
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))

import natscene  # noqa: E402,F401  (exports DRJIT_LIBLLVM_PATH before anything imports drjit)
