#!/usr/bin/env bash
# Set-up command 1: install what mvpt needs on Debian 12, build it into a
# virtual environment (.venv) and render the built-in 9-view demo into out/.
set -euo pipefail
cd "$(dirname "$0")/.."
SUDO=""
[ "$(id -u)" = 0 ] || SUDO=sudo
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
# Compilers and the libraries made for the field, all from Debian.
$SUDO apt-get install -y -qq --no-install-recommends \
    build-essential cmake ninja-build python3 python3-venv python3-dev \
    libembree-dev libtbb-dev libopenexr-dev libpugixml-dev libtinyobjloader-dev \
    libstb-dev zlib1g-dev libgtest-dev libllvm19 >/dev/null
[ -x .venv/bin/python ] || python3 -m venv .venv
.venv/bin/pip install -q --upgrade pip
# The build tools live in .venv and every build of mvpt (this one, scripts/test.sh's and
# scripts/build-wheel.sh's) shares one build directory (pyproject.toml): each rebuilds only what changed.
.venv/bin/pip install -q "scikit-build-core>=0.10" "nanobind>=2.0"
# With the extras for comparison reports and display outputs (Pillow, matplotlib, FLIP, ffmpeg).
.venv/bin/pip install -q --no-build-isolation ".[reports]"
.venv/bin/mvpt demo -o out
