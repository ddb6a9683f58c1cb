#!/usr/bin/env bash
# Incremental developer build: the native module and the C++ tests into
# build/dev, plus an importable package at build/dev/site. Use it as
#   eval "$(scripts/dev-build.sh)"   # exports PYTHONPATH
#   python -m pytest tests/python ; build/dev/mvpt_tests
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
py=${PYTHON:-$root/.venv/bin/python}
b=$root/build/dev
cmake -S "$root" -B "$b" -G Ninja -DSKBUILD=ON -DMVPT_BUILD_TESTS=ON -DPython_EXECUTABLE="$py" >/dev/null
cmake --build "$b" >&2
mkdir -p "$b/site/mvpt"
find "$b/site/mvpt" -maxdepth 1 -type l -delete
ln -sf "$root"/python/mvpt/* "$b/site/mvpt/"
ln -sf "$b"/_core*.so "$b"/_probes*.so "$b/site/mvpt/"
echo "export PYTHONPATH=$b/site"
