"""The C++ tree is layered (docs/architecture.md): each folder of src/mvpt includes only its
own files and those of the folders below it, and no header includes itself through others.
An include upward or a cycle means two parts that cannot be read, tested or changed apart.
Intrinsics live in one file, core/simd_gather.cpp; every other vector loop uses core/simd.h."""
import re
from pathlib import Path

SRC = Path(__file__).resolve().parents[2] / "src"
# Lowest first: a file may include its own folder and the folders before it.
LAYERS = ["core", "io", "render", "accel", "loader", "integrators", "renderer"]
# Inside a layer, folders in the same order: multi-view path tracing builds on the path tracers.
SUBLAYERS = {"integrators": ["path", "multiview"]}
INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"', re.M)
INTRINSIC = re.compile(r"\b_mm\d*_\w+\s*\(|\b__m(?:128|256|512)\w*\b|<(?:imm|x86|[a-z]mm)intrin\.h>")
INTRINSICS_FILE = "mvpt/core/simd_gather.cpp"


def include_graph(root: Path) -> dict:
    """{file: set of files it includes}, paths relative to root / "mvpt" (quoted includes,
    resolved against the including file's folder, then against root)."""
    base = root / "mvpt"
    graph = {}
    for f in sorted(base.rglob("*")):
        if f.suffix not in (".h", ".cpp"):
            continue
        deps = set()
        for inc in INCLUDE.findall(f.read_text()):
            for cand in (f.parent / inc, root / inc):
                if cand.is_file():
                    deps.add(cand.resolve().relative_to(root.resolve()).as_posix())
                    break
        graph[f.relative_to(root).as_posix()] = deps
    return graph


def intrinsic_files(root: Path) -> list:
    """The C++ files of root / "mvpt" that use x86 intrinsics, other than INTRINSICS_FILE."""
    return [f.relative_to(root).as_posix() for f in sorted((root / "mvpt").rglob("*"))
            if f.suffix in (".h", ".cpp") and f.relative_to(root).as_posix() != INTRINSICS_FILE
            and INTRINSIC.search(f.read_text())]


def layer_violations(graph: dict) -> list:
    out = []
    for f, deps in graph.items():
        parts = f.split("/")
        if len(parts) < 3 or parts[1] not in LAYERS:
            out.append(f"{f}: outside the layers {LAYERS}")
            continue
        for d in deps:
            dp = d.split("/")
            if dp[0] != "mvpt" or len(dp) < 3 or dp[1] not in LAYERS:
                out.append(f"{f} includes {d}, outside the library's layers")
            elif LAYERS.index(dp[1]) > LAYERS.index(parts[1]):
                out.append(f"{f} ({parts[1]}) includes {d} ({dp[1]}), a higher layer")
            elif dp[1] == parts[1] and (order := SUBLAYERS.get(parts[1])):
                here, there = (p[2] if len(p) > 3 else None for p in (parts, dp))
                if here not in order or there not in order:
                    out.append(f"{f} or {d}: outside the folders {order} of {parts[1]}/")
                elif order.index(there) > order.index(here):
                    out.append(f"{f} ({parts[1]}/{here}) includes {d} ({parts[1]}/{there}), a higher folder")
    return out


def include_cycle(graph: dict):
    state = {}

    def visit(f, path):
        state[f] = 1
        for d in sorted(graph.get(f, ())):
            if state.get(d) == 1:
                return path[path.index(d):] + [d]
            if d not in state and (c := visit(d, path + [d])):
                return c
        state[f] = 2
        return None

    for f in sorted(graph):
        if f not in state and (c := visit(f, [f])):
            return c
    return None


def test_layers():
    problems = layer_violations(include_graph(SRC))
    assert not problems, "\n".join(problems)


def test_no_include_cycles():
    cycle = include_cycle(include_graph(SRC))
    assert cycle is None, " -> ".join(cycle)


def test_intrinsics_in_one_file():
    assert (SRC / INTRINSICS_FILE).is_file()
    assert INTRINSIC.search((SRC / INTRINSICS_FILE).read_text())
    assert not intrinsic_files(SRC), intrinsic_files(SRC)


def test_the_checks_see_violations(tmp_path):
    """The checks fail on a tree with an upward include, a cycle and intrinsics elsewhere."""
    for name, text in {"render/g.cpp": "__m512 v = _mm512_setzero_ps();\n",
                       "accel/h.cpp": "#include <immintrin.h>\n", "core/simd_gather.cpp": "_mm512_storeu_ps(p, v);\n",
                       "core/a.h": '#include "../render/b.h"\n', "render/b.h": '#include "c.h"\n',
                       "render/c.h": '#include "b.h"\n', "render/d.cpp": '#include "../../python/x.h"\n',
                       "integrators/path/e.h": '#include "../multiview/f.h"\n', "integrators/multiview/f.h": ""}.items():
        (tmp_path / "mvpt" / name).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / "mvpt" / name).write_text(text)
    (tmp_path / "python").mkdir()
    (tmp_path / "python" / "x.h").write_text("")
    assert intrinsic_files(tmp_path) == ["mvpt/accel/h.cpp", "mvpt/render/g.cpp"]
    graph = include_graph(tmp_path)
    problems = layer_violations(graph)
    assert any("core/a.h (core) includes mvpt/render/b.h" in p for p in problems), problems
    assert any("outside the library's layers" in p for p in problems), problems
    assert any("integrators/path/e.h (integrators/path) includes" in p for p in problems), problems
    assert include_cycle(graph) in (["mvpt/render/b.h", "mvpt/render/c.h", "mvpt/render/b.h"],
                                    ["mvpt/render/c.h", "mvpt/render/b.h", "mvpt/render/c.h"])
