"""The loops compiled once per instruction set (MVPT_MULTI_ISA, core/simd.h) are vector loops
in their AVX2 clone as in their AVX-512 one.

GCC vectorises a loop with a branch it cannot turn into selects only where AVX-512's masks
can execute both sides; with AVX2 it leaves the whole loop scalar, silently. A division or
a subtraction under a condition (they may trap) is enough. The shifts of a sample to every
view were scalar on AVX2 CPUs that way; vectorised, the 5x5 light field renders in about
28 % less CPU time there. This test reads the disassembly of the C++ test
binary, which links the same kernels, and fails when a function's AVX-512 clone uses vector
registers and its AVX2 clone uses none.
"""
from __future__ import annotations

import re
import shutil
import subprocess
import sys
import sysconfig
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
# scripts/test.sh builds the C++ tests in the package's build directory, build/{wheel_tag} (pyproject.toml).
_PY = "cp%d%d" % sys.version_info[:2]
BINARY = ROOT / "build" / f"{_PY}-{_PY}-{sysconfig.get_platform().replace('-', '_').replace('.', '_')}" / "mvpt_tests"
HEADER = re.compile(r"^[0-9a-f]+ <(.*) \[clone \.(arch_x86_64_v[34])\]>:$")


def vector_counts(disassembly: str) -> dict:
    """(function, clone) -> instructions naming a ymm or zmm register, from `objdump -d -C`."""
    counts, current = {}, None
    for line in disassembly.splitlines():
        if line.endswith(">:"):
            m = HEADER.match(line)
            current = (m.group(1), m.group(2)) if m else None
            if current:
                counts.setdefault(current, 0)
        elif current and ("ymm" in line or "zmm" in line):
            counts[current] += 1
    return counts


def scalar_avx2_clones(counts: dict) -> list:
    """Functions whose AVX-512 clone has vector instructions and whose AVX2 clone has none."""
    return sorted(f for (f, clone), n in counts.items()
                  if clone == "arch_x86_64_v4" and n > 0 and counts.get((f, "arch_x86_64_v3"), 0) == 0)


def test_checker_finds_a_scalar_avx2_clone():
    text = """\
0000000000001000 <ns::kernel(float*) [clone .arch_x86_64_v4]>:
    1000:\tvaddps %zmm1,%zmm2,%zmm3
0000000000002000 <ns::kernel(float*) [clone .arch_x86_64_v3]>:
    2000:\tvaddss %xmm1,%xmm2,%xmm3
0000000000002100 <ns::kernel(float*) [clone .arch_x86_64_v3] [clone .cold]>:
    2100:\tvaddps %ymm1,%ymm2,%ymm3
0000000000003000 <ns::other(float*) [clone .arch_x86_64_v4]>:
    3000:\tvaddps %ymm1,%ymm2,%ymm3
0000000000004000 <ns::other(float*) [clone .arch_x86_64_v3]>:
    4000:\tvaddps %ymm1,%ymm2,%ymm3
"""
    assert scalar_avx2_clones(vector_counts(text)) == ["ns::kernel(float*)"]


def test_avx2_clones_are_vector_loops():
    if not BINARY.is_file():
        pytest.skip(f"{BINARY.relative_to(ROOT)} is not built (scripts/test.sh builds it before the Python tests)")
    if shutil.which("objdump") is None:
        pytest.skip("objdump (binutils) is not installed")
    text = subprocess.run(["objdump", "-d", "--no-show-raw-insn", "-C", str(BINARY)], capture_output=True,
                          text=True, check=True).stdout
    counts = vector_counts(text)
    if not counts:
        pytest.skip("the binary has no per-instruction-set clones (not built by GCC for x86-64)")
    names = {f for f, _ in counts}
    # The test must see the kernels it guards: the shifts to every view, the Phong lobes, the segments.
    for kernel in ("shift_kernel", "phong_lobes", "segment_kernel"):
        assert any(kernel + "(" in f for f in names), f"{kernel} not found in {BINARY.name}"
    assert scalar_avx2_clones(counts) == []
