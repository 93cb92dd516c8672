"""The code's layout: the Python package's imports form no circle and follow the data flow
between its layers (PY_LAYERS), and the C++ core's includes follow it between its folders.
Both read the sources as text (ast, #include lines); nothing is imported or compiled."""

import ast
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
PACKAGE = ROOT / "python" / "gigascroll"
CPP = ROOT / "cpp"

# cpp/'s folders in data-flow order; a folder may include its own headers, common's,
# concurrency's and those of the folders before it. bindings may include anything.
CPP_FOLDERS = ("common", "concurrency", "pack", "views", "loading", "cache", "sampling",
               "photon", "display", "gallery", "bindings")
CPP_ALWAYS = ("common", "concurrency")


# ----------------------------------------------------------------------------- Python

def module_name(path: Path) -> str:
    parts = ("gigascroll",) + path.relative_to(PACKAGE).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def package_of(path: Path) -> str:
    name = module_name(path)
    return name if path.name == "__init__.py" else name.rpartition(".")[0]


MODULES = {module_name(p): p for p in sorted(PACKAGE.rglob("*.py"))}
# The compiled core: no Python source, and it imports nothing of the package.
EXTENSIONS = {"gigascroll._core"}


def imports_of(path: Path) -> set[str]:
    """The package's modules this one imports: at module level and inside functions,
    `import a.b`, `from .a import b` (the submodule a.b if there is one, else a; the compiled
    core is left out)."""
    found = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            targets = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package_of(path).split(".")
                base = base[:len(base) - node.level + 1]
                if node.module:
                    base.append(node.module)
                base = ".".join(base)
            else:
                base = node.module or ""
            targets = [f"{base}.{a.name}" if f"{base}.{a.name}" in MODULES.keys() | EXTENSIONS
                       else base for a in node.names]
        else:
            continue
        found.update(t for t in targets if t in MODULES and t != module_name(path))
    return found


GRAPH = {name: imports_of(path) for name, path in MODULES.items()}


def reachable(start: str) -> set[str]:
    seen, todo = set(), [start]
    while todo:
        for m in GRAPH[todo.pop()]:
            if m not in seen:
                seen.add(m)
                todo.append(m)
    return seen


def test_the_package_is_read():
    assert {"gigascroll", "gigascroll.walk.frame_loop", "gigascroll.experiments",
            "gigascroll.views.processing", "gigascroll.pack.build"} <= set(MODULES)
    assert "gigascroll.views.exhibition" in GRAPH["gigascroll.views.processing"]
    # function-level imports count: the CLI's bench command imports its benchmarks there
    assert "gigascroll.benchmarks.views" in GRAPH["gigascroll.commands.bench"]


def test_python_imports_have_no_circle():
    state, circles = {}, []

    def visit(m, stack):
        state[m] = "open"
        stack.append(m)
        for n in sorted(GRAPH[m]):
            if state.get(n) == "open":
                circles.append(" -> ".join(stack[stack.index(n):] + [n]))
            elif n not in state:
                visit(n, stack)
        stack.pop()
        state[m] = "done"

    for m in sorted(GRAPH):
        if m not in state:
            visit(m, [])
    assert circles == []


# The package's modules and packages in data-flow order, as CPP_FOLDERS is for cpp/: a module
# may import its own layer's modules and those of the layers before it, never a later layer's.
# A name stands for the module or package of that name and everything under it; the package
# itself (gigascroll/__init__.py, which re-exports the public names) only for itself.
PY_LAYERS = (
    ("shared", ("gigascroll._core", "gigascroll.errors", "gigascroll.outputs",
                "gigascroll.display_mapping")),
    ("prepare", ("gigascroll.pack",)),
    ("determine", ("gigascroll.views",)),
    ("load, cache, sample", ("gigascroll.runtime",)),
    ("render", ("gigascroll.photon",)),
    ("room", ("gigascroll.room",)),
    ("light", ("gigascroll.gallery",)),
    ("publish", ("gigascroll.iiif_presentation", "gigascroll.export", "gigascroll.iiif_exhibition",
                 "gigascroll.exhibit")),
    ("experiments", ("gigascroll.experiments",)),
    ("walk", ("gigascroll.walk",)),
    ("top", ("gigascroll.scenarios", "gigascroll.benchmarks", "gigascroll.serve",
             "gigascroll.commands", "gigascroll.cli", "gigascroll.__main__", "gigascroll")),
)


def layer_of(module: str, layers=PY_LAYERS) -> int | None:
    """The index of the layer that holds `module` (its longest listed prefix), or None."""
    best, index = "", None
    for i, (_, names) in enumerate(layers):
        for name in names:
            under = "." in name and module.startswith(name + ".")
            if (module == name or under) and len(name) > len(best):
                best, index = name, i
    return index


def layer_violations(graph: dict, layers=PY_LAYERS) -> list[str]:
    """Each module of `graph` ({module: modules it imports}) that no layer holds, and each
    import that points up the flow (to a later layer)."""
    bad = []
    for a in sorted(graph):
        la = layer_of(a, layers)
        if la is None:
            bad.append(f"{a}: in no layer of the data flow")
            continue
        for b in sorted(graph[a]):
            lb = layer_of(b, layers)
            if lb is not None and lb > la:
                bad.append(f"{a} -> {b} points up the flow ({layers[la][0]} comes before "
                           f"{layers[lb][0]})")
    return bad


def test_python_imports_follow_the_data_flow():
    assert layer_violations(GRAPH) == []


def test_the_layer_check_catches_an_import_up_the_flow():
    # A package whose cache imports the walk (up the flow) and whose walk imports the cache
    # (down it), plus a module no layer holds: the first and the last are reported.
    graph = {"gigascroll.runtime": {"gigascroll.walk.frame_loop", "gigascroll.errors"},
             "gigascroll.walk.frame_loop": {"gigascroll.runtime"},
             "gigascroll.errors": set(),
             "gigascroll.stray": set()}
    bad = layer_violations(graph)
    assert bad == ["gigascroll.runtime -> gigascroll.walk.frame_loop points up the flow "
                   "(load, cache, sample comes before walk)",
                   "gigascroll.stray: in no layer of the data flow"]


def test_the_layers_hold_the_package():
    # Every layer names something that exists, and the lower layers reach nothing above them:
    # photon.render takes a Gallery through the core type it derives from, not by importing
    # gigascroll.gallery; the room model is read without the gallery that lights it.
    for _, names in PY_LAYERS:
        for name in names:
            assert name in MODULES or name in EXTENSIONS or any(
                m.startswith(name + ".") for m in MODULES), name
    assert layer_of("gigascroll.room.files") < layer_of("gigascroll.gallery.gallery") \
        < layer_of("gigascroll.walk.gallery_walk") < layer_of("gigascroll.cli")
    assert layer_of("gigascroll.gallery") == layer_of("gigascroll.gallery.exposure")
    assert "gigascroll.gallery.gallery" not in reachable("gigascroll.photon")
    assert not any(m.startswith("gigascroll.gallery") for m in reachable("gigascroll.room.files"))


def test_scenarios_and_benchmarks_do_not_import_each_other():
    scenarios = [m for m in MODULES if m.startswith("gigascroll.scenarios")]
    benchmarks = [m for m in MODULES if m.startswith("gigascroll.benchmarks")]
    assert scenarios and benchmarks
    bad = [f"{a} -> {b}" for group, other in ((scenarios, benchmarks), (benchmarks, scenarios))
           for a in group for b in sorted(reachable(a)) if b in other]
    assert bad == []


def test_only_the_top_imports_serve():
    # serve (the HTTP server of the browser client) sits at the top of the flow beside the
    # commands: only commands, benchmarks and serve itself import it.
    serve = [m for m in MODULES if m.startswith("gigascroll.serve")]
    assert "gigascroll.serve.app" in serve
    top = ("gigascroll.serve", "gigascroll.commands", "gigascroll.benchmarks", "gigascroll.cli")
    bad = [f"{a} -> {b}" for a in MODULES if not a.startswith(top) for b in sorted(GRAPH[a])
           if b in serve]
    assert bad == []


def test_no_star_imports():
    stars = [f"{name}: from {node.module} import *" for name, path in MODULES.items()
             for node in ast.walk(ast.parse(path.read_text()))
             if isinstance(node, ast.ImportFrom) and any(a.name == "*" for a in node.names)]
    assert stars == []


# ----------------------------------------------------------------------------- C++

INCLUDE = re.compile(r'^\s*#\s*include\s*"([^"]+)"', re.M)


def include_violations(root: Path = CPP) -> list[str]:
    bad = []
    for path in sorted(root.rglob("*")):
        if path.suffix not in (".h", ".hpp", ".cpp", ".cc", ".inl") or not path.is_file():
            continue
        rel = path.relative_to(root)
        folder = rel.parts[0] if len(rel.parts) > 1 else ""
        if folder not in CPP_FOLDERS:
            bad.append(f"{rel}: folder {folder or '(cpp/ itself)'} is not one of the data flow's")
            continue
        for target in INCLUDE.findall(path.read_text(errors="replace")):
            x = target.split("/")[0] if "/" in target else folder
            if folder == "bindings" or x == folder or x in CPP_ALWAYS:
                continue
            if x not in CPP_FOLDERS:
                bad.append(f'{rel}: #include "{target}": {x} is not one of the data flow\'s '
                           f"folders")
            elif CPP_FOLDERS.index(x) > CPP_FOLDERS.index(folder):
                bad.append(f'{rel}: #include "{target}" points up the flow ({folder} comes '
                           f"before {x})")
    return bad


def test_cpp_includes_follow_the_data_flow():
    assert include_violations() == []


def test_the_include_check_catches_an_include_up_the_flow(tmp_path):
    # A tree with one include down the flow and one up it: only the second is reported.
    (tmp_path / "pack").mkdir()
    (tmp_path / "cache").mkdir()
    (tmp_path / "pack" / "reader.h").write_text('#include "common/error.h"\n#include "cache/page_table.h"\n')
    (tmp_path / "cache" / "page_table.h").write_text('#include "pack/geometry.h"\n')
    bad = include_violations(tmp_path)
    assert len(bad) == 1 and "pack/reader.h" in bad[0] and "points up the flow" in bad[0]


def test_the_include_check_finds_includes():
    # The check reads the tree it is meant to: there are quoted includes between folders.
    n = sum(len(INCLUDE.findall(p.read_text(errors="replace")))
            for p in CPP.rglob("*") if p.suffix in (".h", ".cpp") and p.is_file())
    assert n > 50
