"""The Python package's modules import each other without cycles (function-local imports
included): a cycle means two modules that cannot be read, tested or changed apart."""
import ast
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[2] / "python" / "mvpt"


def _imports(path: Path) -> set:
    """The package's modules that `path` imports (relative imports, at any depth of the file)."""
    out = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom) and node.level == 1:
            if node.module:
                out.add(node.module.split(".")[0])
            else:
                out.update(alias.name for alias in node.names)
    return out


def test_no_import_cycles():
    modules = {p.stem: p for p in PACKAGE.glob("*.py")}
    graph = {m: {d for d in _imports(p) if d in modules and d != m} for m, p in modules.items()}
    state = {}  # 1: on the current path, 2: done

    def visit(m, path):
        state[m] = 1
        for d in sorted(graph[m]):
            if state.get(d) == 1:
                raise AssertionError("import cycle: " + " -> ".join(path[path.index(d):] + [d]))
            if d not in state:
                visit(d, path + [d])
        state[m] = 2

    for m in sorted(graph):
        if m not in state:
            visit(m, [m])
    # Only the program's entry points (program.py, __main__.py) import the command line.
    assert "cli" not in set().union(*(graph[m] for m in graph if m not in ("__main__", "program", "cli")))
