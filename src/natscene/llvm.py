"""
libLLVM for Dr.Jit
==================

Finds and exports a libLLVM that Dr.Jit's LLVM backend can load (DESIGN §3, "Mitsuba and Dr.Jit"):

-   :func:`configure`: set ``DRJIT_LIBLLVM_PATH`` (run by ``import natscene``).
-   :func:`find_libllvm`: the best usable libLLVM found, or None.
-   :func:`check`: render a tiny scene in a subprocess (``python -m natscene.llvm --check``).

Dr.Jit 1.5 refuses LLVM < 15 and aborts at render time with Debian 12's LLVM 15 ("Cannot select
fminimum"). LLVM 19 (Debian's ``libllvm19``) and the PyPI wheel ``karellen-llvm-core`` (which puts
``lib/libLLVM.so.23.1`` inside the virtual environment) both work. :func:`configure` sets
``DRJIT_LIBLLVM_PATH`` to the best library found unless the user already pointed it at a good one;
it must run before ``drjit`` is imported, which ``import natscene`` guarantees.

``python -m natscene.llvm --check`` renders a tiny scene in a subprocess and reports the result.
"""
from __future__ import annotations

import glob
import os
import re
import subprocess
import sys
from pathlib import Path

__all__ = ["configure", "find_libllvm", "check"]

MIN_GOOD_VERSION = 16  # 15 aborts at render time, < 15 is refused by Dr.Jit 1.5


def _version_of(path: str) -> int | None:
    """LLVM major version from a library file name (libLLVM-19.so, libLLVM.so.23.1, llvm-19/lib/...)."""
    name = os.path.realpath(path)
    for pattern in (r"libLLVM-(\d+)", r"libLLVM\.so\.(\d+)", r"llvm-(\d+)/"):
        m = re.search(pattern, name)
        if m:
            return int(m.group(1))
    return None


def candidates() -> list[str]:
    """Library paths to try, best first: the virtual environment's wheel, then system LLVMs, newest first."""
    found: list[str] = []
    prefixes = {sys.prefix, os.path.dirname(os.path.dirname(os.path.realpath(sys.executable)))}
    for prefix in prefixes:
        found += sorted(glob.glob(os.path.join(prefix, "lib", "libLLVM.so.*")), reverse=True)
        found += sorted(glob.glob(os.path.join(prefix, "lib", "libLLVM-*.so")), reverse=True)
    system = glob.glob("/usr/lib/llvm-*/lib/libLLVM*.so*") + glob.glob("/usr/lib/*-linux-gnu/libLLVM-*.so*")
    system.sort(key=lambda p: _version_of(p) or 0, reverse=True)
    found += system
    seen, out = set(), []
    for p in found:
        if p not in seen and os.path.isfile(p):
            seen.add(p)
            out.append(p)
    return out


def find_libllvm() -> str | None:
    """Return the path of a libLLVM with major version >= 16, or None."""
    for path in candidates():
        v = _version_of(path)
        if v is not None and v >= MIN_GOOD_VERSION:
            return path
    return None


def configure() -> str | None:
    """Export ``DRJIT_LIBLLVM_PATH`` (and a project-local kernel cache) unless already set to a usable library."""
    current = os.environ.get("DRJIT_LIBLLVM_PATH")
    if current and os.path.isfile(current) and (_version_of(current) or MIN_GOOD_VERSION) >= MIN_GOOD_VERSION:
        return current
    path = find_libllvm()
    if path:
        os.environ["DRJIT_LIBLLVM_PATH"] = path
    return path


def check() -> int:
    """Render a tiny Mitsuba scene with the LLVM variant in a subprocess; return its exit code."""
    path = configure()
    if path is None:
        print("natscene.llvm: no libLLVM >= 16 found. Install the wheel 'karellen-llvm-core' "
              "or Debian's 'libllvm19' (apt-get install libllvm19).", file=sys.stderr)
        return 1
    code = ("import mitsuba as mi; mi.set_variant('llvm_ad_rgb'); "
            "s = mi.load_dict({'type': 'scene', 'sensor': {'type': 'perspective', 'film': "
            "{'type': 'hdrfilm', 'width': 4, 'height': 4}}, 'integrator': {'type': 'path'}, 'e': {'type': 'constant'}}); "
            "import numpy as np; img = np.array(mi.render(s, spp=1)); assert np.isfinite(img).all()")
    proc = subprocess.run([sys.executable, "-c", code], env=dict(os.environ, DRJIT_LIBLLVM_PATH=path),
                          capture_output=True, text=True)
    if proc.returncode != 0:
        print(f"natscene.llvm: Dr.Jit could not render with {path}:\n{proc.stderr[-2000:]}", file=sys.stderr)
        return 1
    print(f"natscene: Dr.Jit LLVM backend OK ({path})")
    return 0


if __name__ == "__main__":
    sys.exit(check() if "--check" in sys.argv else (0 if find_libllvm() else 1))
