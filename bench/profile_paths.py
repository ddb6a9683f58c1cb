"""Instructions per camera path of mvpt's renderer, measured with callgrind.

    python bench/profile_paths.py cbox-rgb --res 32 --write-xml /tmp/cbox.xml   # prints BASE
    cmake -S . -B build/prof -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \\
        -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O3 -DNDEBUG -g" -DMVPT_BUILD_BENCH=ON
    cmake --build build/prof --target mvpt_profile
    valgrind --tool=callgrind build/prof/mvpt_profile /tmp/cbox.xml BASE 64
    callgrind_annotate --inclusive=yes callgrind.out.* | grep Renderer::render

Prepares one of bench_vs_mitsuba.py's scenes (includes inlined, box filter, film scaled to
--res). With --write-xml it only writes that XML for the C++ driver bench/profile_paths.cpp
(one thread, no Python start-up under valgrind); the inclusive cost of Renderer::render
divided by the camera path count it prints is the instructions per path: a deterministic
measure, unlike wall time on a shared machine. Without it, the scene is rendered here with
one thread; --hash prints a SHA-256 of the float32 image, to check that an optimisation
leaves images bit-identical.
"""
from __future__ import annotations

import argparse
import hashlib
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parent / "tests" / "python"))
import bench_vs_mitsuba as bench  # noqa: E402
import mitsuba_compare as mc  # noqa: E402


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scene", choices=[s[0] for s in bench.SCENES])
    ap.add_argument("--res", type=int, default=32)
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--hash", action="store_true", help="print the image's SHA-256")
    ap.add_argument("--write-xml", default=None, help="write the prepared XML here, print its base dir")
    ap.add_argument("--shared", default=None)
    args = ap.parse_args(argv)

    root = bench.shared_dir(args.shared)
    name, rel, defines = next(s for s in bench.SCENES if s[0] == args.scene)
    xml, base = mc.prepare_scene(root / rel, defines, max_res=args.res, box_filter=True)
    if args.write_xml:
        # Defines are substituted by the loader: keep them as <default>s of the written file.
        import xml.etree.ElementTree as ET
        tree = ET.fromstring(xml)
        for k, v in defines.items():
            for d in tree.iter("default"):
                if d.get("name") == k:
                    d.set("value", str(v))
                    break
            else:
                tree.insert(0, ET.Element("default", {"name": k, "value": str(v)}))
        Path(args.write_xml).write_text(ET.tostring(tree, encoding="unicode"))
        print(base)
        return 0
    import mvpt
    scene = mc.load_mvpt(xml, defines, base)
    t0 = time.perf_counter()
    r = mvpt.render(scene, spp=args.spp, seed=args.seed, threads=args.threads)
    dt = time.perf_counter() - t0
    img = np.ascontiguousarray(np.asarray(r.images[r.view_ids[0]], np.float32))
    paths = img.shape[0] * img.shape[1] * args.spp
    print(f"{name}: {img.shape[1]}x{img.shape[0]} x {args.spp} spp = {paths} camera paths, "
          f"{dt:.3f} s, {paths / dt / 1e6:.3f} M paths/s, {args.threads} thread(s)")
    if args.hash:
        print("sha256", hashlib.sha256(img.tobytes()).hexdigest())
    return 0


if __name__ == "__main__":
    sys.exit(main())
