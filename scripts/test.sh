#!/usr/bin/env bash
# Set-up command 2: run the whole test suite (C++ unit tests, then the Python
# tests, which compare against Mitsuba 3 where ../shared/scenes is present).
# Expects scripts/setup.sh to have run.
set -euo pipefail
cd "$(dirname "$0")/.."
[ -x .venv/bin/python ] || { echo "run scripts/setup.sh first" >&2; exit 1; }
# Test-only dependencies (Mitsuba 3 is the independent reference renderer; the OpenEXR
# bindings read our multi-view EXRs independently; psutil finds Ray's worker processes),
# then mvpt with its report and Ray extras.
.venv/bin/pip install -q pytest scipy "mitsuba==3.9.1" "OpenEXR>=3.3" psutil
.venv/bin/pip install -q ".[reports,ray]"
# Headless Chromium (Debian) loads the HTML reports in tests/python/test_report.py; that
# test fails under CI without it and skips elsewhere.
if ! command -v chromium >/dev/null 2>&1; then
    SUDO=""
    [ "$(id -u)" = 0 ] || SUDO=sudo
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends chromium >/dev/null \
        || echo "warning: could not install chromium; the report's browser test will skip" >&2
fi
cmake -S . -B build/cpp-tests -G Ninja -DMVPT_BUILD_TESTS=ON >/dev/null
cmake --build build/cpp-tests
ctest --test-dir build/cpp-tests --output-on-failure
.venv/bin/python -m pytest tests/python -q -rs "$@"
