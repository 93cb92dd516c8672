"""The code's layout: the Python package's imports form no circle and respect its layers,
and the C++ core's includes follow the data flow between its folders. Both read the sources
as text (ast, #include lines); nothing is imported or compiled."""

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


def test_nothing_below_the_frame_loop_imports_it():
    below = [m for m in MODULES if m.startswith(("gigascroll.views", "gigascroll.pack"))
             or m in ("gigascroll.runtime", "gigascroll.photon")]
    assert len(below) > 8
    offenders = [m for m in below if "gigascroll.walk.frame_loop" in reachable(m) | {m}]
    assert offenders == []


def test_the_layers_below_the_gallery_do_not_import_it():
    # The flow's lower layers (prepare, determine, load, cache, sample, the photon renderer and
    # the shared modules) reach nothing above them: not the gallery, the exhibition, the
    # server, the commands, the benchmarks or the scenarios. gigascroll.render takes a Gallery
    # through the core type it derives from, not by importing gigascroll.gallery.
    lower = [m for m in MODULES if m.startswith(("gigascroll.views", "gigascroll.pack"))
             or m in ("gigascroll.runtime", "gigascroll.photon", "gigascroll.walk.frame_loop",
                      "gigascroll.errors", "gigascroll.outputs", "gigascroll.display_mapping")]
    assert "gigascroll.photon" in lower and len(lower) > 10
    upper = ("gigascroll.gallery", "gigascroll.exhibit", "gigascroll.serve", "gigascroll.commands",
             "gigascroll.benchmarks", "gigascroll.scenarios", "gigascroll.cli")
    bad = [f"{a} -> {b}" for a in lower for b in sorted(reachable(a)) if b.startswith(upper)]
    assert bad == []


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
