#!/usr/bin/env bash
# Set-up command 2: run the whole test suite (C++ unit tests, then the Python
# tests, which compare against Mitsuba 3 where ../shared/scenes is present).
# Expects scripts/setup.sh to have run.
set -euo pipefail
cd "$(dirname "$0")/.."
[ -x .venv/bin/python ] || { echo "run scripts/setup.sh first" >&2; exit 1; }
# Test-only dependencies (Mitsuba 3 is the independent reference renderer).
.venv/bin/pip install -q pytest scipy "mitsuba==3.9.1"
.venv/bin/pip install -q .
cmake -S . -B build/cpp-tests -G Ninja -DMVPT_BUILD_TESTS=ON >/dev/null
cmake --build build/cpp-tests
ctest --test-dir build/cpp-tests --output-on-failure
.venv/bin/python -m pytest tests/python -q -rs "$@"
