#!/usr/bin/env bash
# Set-up command 2: run the whole test suite (C++ unit tests, then the Python
# tests, which compare against Mitsuba 3 where ../shared/scenes is present).
# Expects scripts/setup.sh to have run.
set -euo pipefail
cd "$(dirname "$0")/.."
[ -x .venv/bin/python ] || { echo "run scripts/setup.sh first" >&2; exit 1; }
# Test-only dependencies (Mitsuba 3 is the independent reference renderer; the OpenEXR
# bindings read our multi-view EXRs independently; psutil finds Ray's worker processes;
# pytest-xdist runs the tests on every core), then mvpt with its report, Ray and Blender
# extras (Blender's bpy, with Cycles, exists for Python 3.11 only: elsewhere its tests skip)
# and, in the same build directory as scripts/setup.sh's build, the C++ unit tests.
.venv/bin/pip install -q pytest pytest-xdist scipy "mitsuba==3.9.1" "OpenEXR>=3.3" psutil \
    "scikit-build-core>=0.10" "nanobind>=2.0"
extras="reports,ray"
.venv/bin/python -c 'import sys; sys.exit(sys.version_info[:2] != (3, 11))' && extras="$extras,blender"
.venv/bin/pip install -q --no-build-isolation -C cmake.define.MVPT_BUILD_TESTS=ON ".[$extras]"
# Headless Chromium (Debian) loads the HTML reports in tests/python/test_report.py; that
# test fails under CI without it and skips elsewhere.
if ! command -v chromium >/dev/null 2>&1; then
    SUDO=""
    [ "$(id -u)" = 0 ] || SUDO=sudo
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends chromium >/dev/null \
        || echo "warning: could not install chromium; the report's browser test will skip" >&2
fi
# pyproject.toml's build-dir, build/{wheel_tag}
tag=$(.venv/bin/python -c 'import sys, sysconfig; v = "cp%d%d" % sys.version_info[:2]; print(f"{v}-{v}-" + sysconfig.get_platform().replace("-", "_").replace(".", "_"))')
"build/$tag/mvpt_tests" --gtest_brief=1
# The Python tests on up to four cores (pytest-xdist), then those marked `serial`, which time
# renders and signals, alone; the ten slowest of each are listed. Exit status 5 (no test
# selected, e.g. by -k) is no failure.
jobs=$(nproc); [ "$jobs" -le 4 ] || jobs=4
run_pytest() { .venv/bin/python -m pytest tests/python -q -rs "$@" || [ $? = 5 ]; }
run_pytest -n "$jobs" -m "not serial" --durations=10 "$@"
run_pytest -m serial --durations=10 "$@"
