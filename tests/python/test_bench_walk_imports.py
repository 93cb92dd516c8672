"""The scripts beside the walk benchmark (bench/walk/) import each other without a circle: what
two of them share lives in a module both import (walk_pose.py), not in one of the scripts.
Each script also still loads on its own and answers --help."""

import ast
import pathlib
import subprocess
import sys

import pytest

WALK = pathlib.Path(__file__).resolve().parents[2] / "bench" / "walk"
SCRIPTS = sorted(p.stem for p in WALK.glob("*.py"))


def _sibling_imports(name):
    """The bench/walk modules that `name`.py imports anywhere in its text (also inside functions)."""
    found = set()
    for node in ast.walk(ast.parse((WALK / f"{name}.py").read_text())):
        if isinstance(node, ast.Import):
            found |= {a.name.split(".")[0] for a in node.names}
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            found.add(node.module.split(".")[0])
    return found & set(SCRIPTS)


def _cycle(graph):
    """A circle of the import graph as a list of names, or None (depth-first search)."""
    state, stack = {}, []

    def visit(n):
        state[n] = "open"
        stack.append(n)
        for m in sorted(graph[n]):
            if state.get(m) == "open":
                return stack[stack.index(m):] + [m]
            if m not in state and (c := visit(m)):
                return c
        state[n] = "done"
        stack.pop()
        return None

    for n in sorted(graph):
        if n not in state and (c := visit(n)):
            return c
    return None


def test_cycle_finder_finds_a_circle():
    # The finder itself, on the circle this test guards against and on a chain.
    assert _cycle({"alternate": {"single_pose"}, "single_pose": {"alternate"}}) == \
        ["alternate", "single_pose", "alternate"]
    assert _cycle({"a": {"b"}, "b": {"c"}, "c": set()}) is None


def test_walk_scripts_import_no_circle():
    graph = {name: _sibling_imports(name) for name in SCRIPTS}
    assert "walk_pose" in graph["alternate"] and "walk_pose" in graph["single_pose"]
    assert _cycle(graph) is None, f"import circle: {' -> '.join(_cycle(graph))}"


@pytest.mark.parametrize("script", ["alternate", "single_pose", "frame_hashes", "loop_frames"])
def test_walk_scripts_answer_help(script):
    out = subprocess.run([sys.executable, str(WALK / f"{script}.py"), "--help"],
                         capture_output=True, text=True, timeout=120)
    assert out.returncode == 0 and out.stdout.startswith("usage: ")
