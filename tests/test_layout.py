"""The folders of src/breccia form layers: no folder includes, directly or through others, a
folder that includes it back. Each folder's dependencies are read from its #include lines."""
import os
import re

SOURCE = os.environ["BRECCIA_SOURCE_DIR"]
ROOT = os.path.join(SOURCE, "src", "breccia")
INCLUDE = re.compile(r'#include "breccia/([a-z_]+)/')


def folder_graph():
    graph = {}
    for folder in sorted(os.listdir(ROOT)):
        path = os.path.join(ROOT, folder)
        if not os.path.isdir(path):
            continue
        uses = set()
        for name in os.listdir(path):
            if name.endswith((".hpp", ".cpp", ".in")):
                with open(os.path.join(path, name), encoding="utf-8") as f:
                    uses |= set(INCLUDE.findall(f.read()))
        graph[folder] = uses - {folder}
    return graph


def find_cycle(graph):
    """A list of folders that closes on itself, or None (depth-first search)."""
    state = {}

    def visit(node, trail):
        state[node] = "open"
        for nxt in sorted(graph.get(node, ())):
            if state.get(nxt) == "open":
                return trail[trail.index(nxt):] + [nxt]
            if nxt not in state:
                found = visit(nxt, trail + [nxt])
                if found:
                    return found
        state[node] = "done"
        return None

    for node in sorted(graph):
        if node not in state:
            found = visit(node, [node])
            if found:
                return found
    return None


def test_the_folders_form_layers():
    graph = folder_graph()
    assert {"core", "engine", "law", "protocol", "run"} <= set(graph)
    cycle = find_cycle(graph)
    assert cycle is None, "folder cycle: " + " -> ".join(cycle)


def test_the_cycle_finder_finds_a_planted_cycle():
    assert find_cycle({"a": {"b"}, "b": {"c"}, "c": {"a"}}) == ["a", "b", "c", "a"]
    assert find_cycle({"a": {"b"}, "b": set()}) is None


def test_the_core_depends_on_nothing_of_ours():
    assert folder_graph()["core"] == set()
