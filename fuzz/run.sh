#!/usr/bin/env bash
# Builds the libFuzzer targets (Clang, ASan + UBSan) and runs each, starting from seed corpora
# made of the repository's own inputs and fuzz/regressions/<target>/ (every input that once
# crashed: each is replayed first). Prints, per target, the executions, the coverage and whether
# it found anything; exits 1 on a finding (its input is in build/fuzz/findings/<target>/).
#   bash fuzz/run.sh [SECONDS] [TARGET ...]   a hunt: SECONDS (default 60) per target, a random
#                                             seed, the corpus in build/fuzz/corpus/ kept and grown
#   bash fuzz/run.sh --fixed [TARGET ...]     what CI runs: a fixed seed and a fixed number of
#                                             executions per target (about 15 s each) from the
#                                             seeds alone (nearly the same inputs on every run)
# A longer hunt: bash fuzz/run.sh 3600 fuzz_obj   (docs/testing.md, "Fuzzing").
set -euo pipefail
cd "$(dirname "$0")/.."
fixed=0
if [ "${1:-}" = --fixed ]; then fixed=1; shift; fi
seconds=60
if [ $fixed = 0 ] && [ $# -gt 0 ]; then seconds=$1; shift; fi
# Executions per target in --fixed runs: about 15 s of each on one core of a 2-core machine.
declare -A fixed_runs=([fuzz_scene_xml]=50000 [fuzz_obj]=15000 [fuzz_ply]=25000 [fuzz_serialized]=40000
                       [fuzz_image]=12000 [fuzz_json]=150000 [fuzz_vol]=50000)
command -v clang++ >/dev/null || { echo "fuzz/run.sh needs clang++ (apt-get install clang libclang-rt-14-dev)" >&2; exit 2; }
cmake -S . -B build/fuzz -G Ninja -DCMAKE_CXX_COMPILER=clang++ -DMVPT_FUZZ=ON -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null
cmake --build build/fuzz >/dev/null
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(fuzz_scene_xml fuzz_obj fuzz_ply fuzz_serialized fuzz_image fuzz_json fuzz_vol)

# Seed corpora from the repository (and the shared scenes when present).
seeds=build/fuzz/seeds
rm -rf "$seeds" && mkdir -p "$seeds"/{fuzz_scene_xml,fuzz_obj,fuzz_ply,fuzz_serialized,fuzz_image,fuzz_json,fuzz_vol}
find scenes tests/scenes python/mvpt/data -name '*.xml' -exec cp -t "$seeds/fuzz_scene_xml" {} + 2>/dev/null || true
find tests/scenes -name '*.obj' -exec cp -t "$seeds/fuzz_obj" {} +
find tests/scenes -name '*.ply' -exec cp -t "$seeds/fuzz_ply" {} +
find scenes -name '*.json' -exec cp -t "$seeds/fuzz_json" {} +
# The serialized and image targets read a selector byte first.
for f in $(find tests/scenes -name '*.serialized'); do { printf '\000'; cat "$f"; } > "$seeds/fuzz_serialized/$(basename "$f")"; done
if [ -x .venv/bin/python ]; then
  .venv/bin/python - "$seeds/fuzz_image" <<'PY'
import sys, os, tempfile, numpy as np
from mvpt import _core
out = sys.argv[1]
img = np.random.default_rng(1).random((8, 8, 3), dtype=np.float32)
with tempfile.TemporaryDirectory() as t:
    _core.write_exr(os.path.join(t, "a.exr"), {c: np.ascontiguousarray(img[..., i]) for i, c in enumerate("RGB")})
    _core.write_png(os.path.join(t, "a.png"), img)
    for name, sel in (("a.exr", 0), ("a.png", 1)):
        open(os.path.join(out, name), "wb").write(bytes([sel]) + open(os.path.join(t, name), "rb").read())
hdr = b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 2 +X 2\n" + bytes([128, 64, 32, 129]) * 4
open(os.path.join(out, "a.hdr"), "wb").write(bytes([2]) + hdr)
import struct  # a 2x3x2 grid of 3 channels for the .vol reader
vol = b"VOL\x03" + struct.pack("<iiiii", 1, 2, 3, 2, 3) + struct.pack("<6f", 0, 0, 0, 1, 1, 1)
open(os.path.join(os.path.dirname(out), "fuzz_vol", "a.vol"), "wb").write(vol + np.arange(36, dtype="<f4").tobytes())
PY
fi

export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=0:abort_on_error=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
jobs=${FUZZ_JOBS:-$(nproc)}
# One target: its regression inputs, then SECONDS of fuzzing; a summary line in build/fuzz/<t>.summary.
fuzz_one() {
  local t=$1 corpus=build/fuzz/corpus/$1 findings=build/fuzz/findings/$1 log=build/fuzz/$1.log verdict budget
  budget=(-max_total_time="$seconds")
  if [ $fixed = 1 ]; then  # a fresh corpus: the run starts from the repository alone
    corpus=build/fuzz/corpus-fixed/$t
    rm -rf "$corpus"
    budget=(-seed=1 -runs="${fixed_runs[$t]}" -max_total_time=300)
  fi
  mkdir -p "$corpus" "$findings"
  if [ -d "fuzz/regressions/$t" ] && [ -n "$(ls -A "fuzz/regressions/$t")" ]; then
    if ! build/fuzz/$t -runs=0 -artifact_prefix="$findings/" "fuzz/regressions/$t" >"build/fuzz/$t.regressions.log" 2>&1; then
      echo "$t: a regression input fails again (build/fuzz/$t.regressions.log): FINDING" >"build/fuzz/$t.summary"
      return
    fi
  fi
  if build/fuzz/$t "${budget[@]}" -timeout=25 -rss_limit_mb=4096 -max_len=65536 \
       -artifact_prefix="$findings/" "$corpus" "$seeds/$t" >"$log" 2>&1; then
    verdict="no finding"
  else
    verdict="FINDING (see $log and $findings/)"
  fi
  local runs cov
  runs=$(grep -o 'Done [0-9]* runs' "$log" | tail -1 | grep -o '[0-9]*' || echo "?")
  cov=$(grep -o 'cov: [0-9]*' "$log" | tail -1 | grep -o '[0-9]*' || echo "?")
  echo "$t: $runs executions, coverage $cov edges, corpus $(ls "$corpus" | wc -l) inputs: $verdict" \
    >"build/fuzz/$t.summary"
}
running=0
for t in "${targets[@]}"; do  # $jobs targets at a time (each fuzzer uses one core)
  fuzz_one "$t" &
  running=$((running + 1))
  if [ "$running" -ge "$jobs" ]; then wait -n; running=$((running - 1)); fi
done
wait
status=0
for t in "${targets[@]}"; do
  cat "build/fuzz/$t.summary"
  grep -q FINDING "build/fuzz/$t.summary" && status=1
done
exit $status
