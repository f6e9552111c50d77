#!/usr/bin/env bash
# Idempotent set-up for natscene: a virtual environment in .venv with the package (editable) and its
# pinned-range dependencies, plus a libLLVM that Dr.Jit can load. Safe to run every time: it only
# reinstalls when pyproject.toml changed. Used by `make run` and `make test`.
set -euo pipefail
cd "$(dirname "$0")/.."
VENV=${NATSCENE_VENV:-.venv}

pick_python() {
  for p in python3.12 python3.11 python3.10 python3; do
    if command -v "$p" >/dev/null 2>&1 && "$p" -c 'import sys; sys.exit(sys.version_info < (3, 10))'; then
      echo "$p"; return 0
    fi
  done
  return 1
}

as_root() { if [ "$(id -u)" = 0 ]; then "$@"; elif command -v sudo >/dev/null; then sudo "$@"; else return 1; fi; }

if [ ! -x "$VENV/bin/python" ]; then
  PY=$(pick_python) || { echo "natscene setup: Python >= 3.10 is required (python3 not found)" >&2; exit 1; }
  echo "natscene setup: creating $VENV with $PY"
  if ! "$PY" -m venv "$VENV" 2>/dev/null; then
    echo "natscene setup: python venv module missing; installing python3-venv with apt-get"
    rm -rf "$VENV"
    as_root apt-get update -qq && as_root apt-get install -y -qq python3-venv
    "$PY" -m venv "$VENV"
  fi
fi

STAMP="$VENV/.natscene-installed"
WANT=$(sha256sum pyproject.toml | cut -d' ' -f1)
if [ ! -f "$STAMP" ] || [ "$(cat "$STAMP")" != "$WANT" ]; then
  echo "natscene setup: installing Python packages into $VENV (first run takes a minute or two)"
  "$VENV/bin/python" -m pip install -q --upgrade pip
  "$VENV/bin/python" -m pip install -q -e ".[test]"
  echo "$WANT" > "$STAMP"
fi

# Dr.Jit needs a libLLVM it can load; natscene finds it by itself (natscene/llvm.py). If the wheel
# could not be installed on this platform, fall back to Debian's libllvm19.
if ! "$VENV/bin/python" -c 'import sys, natscene.llvm as l; sys.exit(l.find_libllvm() is None)'; then
  echo "natscene setup: no usable libLLVM found; installing libllvm19 with apt-get"
  as_root apt-get update -qq && as_root apt-get install -y -qq libllvm19
fi
"$VENV/bin/python" -W ignore::RuntimeWarning -m natscene.llvm --check

# OpenVDB in and out (density.vdb): the OpenVDB library's own Python binding. Debian's python3-openvdb runs
# under the system Python (natscene.volume.vdb calls it as a separate program: the binding is built against
# Debian's NumPy 1.x and cannot load beside the venv's NumPy 2). Skipped when a binding is already usable.
if ! "$VENV/bin/python" -c 'import natscene.volume.vdb as v; v.backend()' >/dev/null 2>&1; then
  echo "natscene setup: installing Debian's python3-openvdb (OpenVDB 10) with apt-get"
  as_root apt-get update -qq && DEBIAN_FRONTEND=noninteractive as_root apt-get install -y -qq python3-openvdb \
    || echo "natscene setup: WARNING: could not install python3-openvdb; the volume stage cannot write density.vdb" >&2
fi
