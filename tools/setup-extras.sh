#!/usr/bin/env bash
# Optional heavy tools (not needed by `make run` / `make test`): Debian's Blender 3.4, the OpenVDB client that
# tests/test_blender_vdb.py opens natscene's density.vdb with (headless, Cycles). Idempotent.
set -euo pipefail
as_root() { if [ "$(id -u)" = 0 ]; then "$@"; elif command -v sudo >/dev/null; then sudo "$@"; else return 1; fi; }
if ! command -v blender >/dev/null 2>&1; then
  echo "natscene setup-extras: installing Debian's blender with apt-get (a few hundred MB)"
  as_root apt-get update -qq
  DEBIAN_FRONTEND=noninteractive as_root apt-get install -y -qq --no-install-recommends blender
fi
blender --version | head -1
