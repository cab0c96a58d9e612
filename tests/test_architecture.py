"""The package's layers (docs/architecture.md): every import of a module, at its top or inside a function, goes to
its own layer or one below, never to a peer (another folder of the same rank), no modules import each other in a
circle, and at most 5 modules sit at the package root."""

import ast
from pathlib import Path

import psgsl_pgm

PACKAGE = Path(psgsl_pgm.__file__).parent

#: docs/architecture.md, bottom to top; a layer imports only from its own rank or lower ones
RANK = {"kernels": 0, "_shared": 1, "geometry": 2, "io": 3, "core": 4, "olfaction": 5, "networks": 5, "sim": 6,
        "runs": 7, "ros": 7.5, "experiment": 8, "search": 8.5, "teaching": 9, "gym": 9, "cli": 10}
ROOT_MODULES = 11  # psgsl_pgm/__init__.py and __main__.py: they may import any layer


def _layer(module: str) -> int:
    parts = module.split(".")
    if module == "psgsl_pgm.__version__":  # a constant every layer may read
        return 0
    if len(parts) == 1 or parts[1] in ("__init__", "__main__"):
        return ROOT_MODULES
    if parts[1] not in RANK:
        raise KeyError(f"{module}: a folder of psgsl_pgm that docs/architecture.md does not place")
    return RANK[parts[1]]


def _imports(path: Path):
    """(line, imported module) for every psgsl_pgm import in one file, relative ones resolved."""
    rel = path.relative_to(PACKAGE.parent).with_suffix("").parts
    package = rel[:-1] if rel[-1] != "__init__" else rel
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = list(package[: len(package) - node.level + 1])
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            if target.split(".")[0] != "psgsl_pgm":
                continue
            if node.module is None:  # from . import a, b: the modules a, b
                for alias in node.names:
                    yield node.lineno, f"{target}.{alias.name}"
            else:
                yield node.lineno, target
        elif isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name.split(".")[0] == "psgsl_pgm":
                    yield node.lineno, alias.name


def test_imports_flow_down_the_layers_only():
    upward = []
    for path in sorted(PACKAGE.rglob("*.py")):
        module = ".".join(path.relative_to(PACKAGE.parent).with_suffix("").parts)
        own = _layer(module)
        for line, target in _imports(path):
            if own != ROOT_MODULES and _layer(target) > own:
                upward.append(f"{path.relative_to(PACKAGE.parent)}:{line} imports {target}")
    assert upward == []


def _folder(module: str) -> str:
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else ""


def test_peers_never_import_each_other():
    """Two folders of one rank (olfaction and networks) import neither the other."""
    across = []
    for path in sorted(PACKAGE.rglob("*.py")):
        module = ".".join(path.relative_to(PACKAGE.parent).with_suffix("").parts)
        own = _layer(module)
        for line, target in _imports(path):
            if own != ROOT_MODULES and _layer(target) == own and _folder(target) != _folder(module):
                across.append(f"{path.relative_to(PACKAGE.parent)}:{line} imports its peer {target}")
    assert across == []


def _module_graph() -> dict:
    """module -> the package's modules it imports (a package import counts as its __init__)."""
    modules = {".".join(p.relative_to(PACKAGE.parent).with_suffix("").parts): p for p in PACKAGE.rglob("*.py")}
    graph = {}
    for module, path in modules.items():
        out = set()
        for _, target in _imports(path):
            while target and target not in modules and f"{target}.__init__" not in modules:
                target = target.rpartition(".")[0]  # from pkg.mod import name: the module pkg.mod
            if target in modules:
                out.add(target)
            elif f"{target}.__init__" in modules:
                out.add(f"{target}.__init__")
        out.discard(module)
        graph[module] = out
    return graph


def _circles(graph: dict) -> list:
    """Strongly connected components of more than one module (Tarjan), each sorted."""
    index, low, stack, on, out = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in graph.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def test_no_modules_import_each_other_in_a_circle():
    """Within a layer too (a package's __init__ and the modules it re-exports aside): no module reaches itself
    through the imports of others, at the top or inside functions."""
    graph = {m: {t for t in ts if not t.endswith("__init__")} for m, ts in _module_graph().items()}
    assert _circles(graph) == []


def test_the_circle_check_sees_a_circle():
    assert _circles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert _circles({"a": {"b"}, "b": set()}) == []


def test_the_package_root_holds_at_most_five_modules():
    assert len(list(PACKAGE.glob("*.py"))) <= 5


def test_the_rule_sees_an_upward_import(tmp_path):
    """The check itself: an import of search from core is upward, of geometry from core is not."""
    bad = PACKAGE / "core" / "_semantic.py"
    lines = [t for _, t in _imports(bad)]
    assert all(_layer(t) <= RANK["core"] for t in lines)
    assert _layer("psgsl_pgm.search._loop") > RANK["core"] >= _layer("psgsl_pgm.geometry._grid")
