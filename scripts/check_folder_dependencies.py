#!/usr/bin/env python3
"""Checks the include graph between the project's folders.

Every tracked .h/.cc file belongs to its folder (e.g. robot_agent/filters); an
#include "a/b/c.h" of a tracked header is an edge from the including file's folder to
a/b. Fails, naming them, if
  * folders include each other, directly or through others (a cycle), or
  * a file under robot_agent/ other than the agent's main includes the scenario
    (common/config/), which holds the ground truth: the agent gets its own options.
Usage: check_folder_dependencies.py [SOURCE_ROOT]
"""
import os
import re
import subprocess
import sys

# The only file under robot_agent/ that may read the scenario: it projects the agent's options.
SCENARIO_READERS_IN_AGENT = {"robot_agent/robot_agent_main.cc"}
SCENARIO_FOLDER = "common/config"

INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"', re.M)


def tracked_sources(root):
    out = subprocess.run(["git", "ls-files", "*.h", "*.cc"], cwd=root, check=True,
                         capture_output=True, text=True).stdout
    return [f for f in out.split("\n") if f]


def folder_graph(root, files):
    known = set(files)
    edges = {}
    agent_readers = []
    for f in files:
        src = os.path.dirname(f)
        with open(os.path.join(root, f), encoding="utf-8") as handle:
            text = handle.read()
        for inc in INCLUDE.findall(text):
            if inc not in known:
                continue  # a generated or system header
            dst = os.path.dirname(inc)
            if dst != src:
                edges.setdefault(src, set()).add(dst)
            if (f.startswith("robot_agent/") and dst == SCENARIO_FOLDER
                    and f not in SCENARIO_READERS_IN_AGENT):
                agent_readers.append(f"{f} includes {inc}")
    return edges, agent_readers


def cycles(edges):
    """Strongly connected components with more than one folder (Tarjan)."""
    index, low, on_stack, stack, found = {}, {}, set(), [], []
    counter = [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on_stack.add(v)
        for w in sorted(edges.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    nodes = set(edges) | {w for ws in edges.values() for w in ws}
    for v in sorted(nodes):
        if v not in index:
            visit(v)
    return found


def main():
    root = sys.argv[1] if len(sys.argv) > 1 else "."
    edges, agent_readers = folder_graph(root, tracked_sources(root))
    problems = []
    for component in cycles(edges):
        members = set(component)
        links = [f"{a} -> {b}" for a in component for b in sorted(edges.get(a, ())) if b in members]
        problems.append("folders include each other: " + ", ".join(links))
    problems += [f"the agent reads the scenario: {r}" for r in agent_readers]
    for p in problems:
        print(p, file=sys.stderr)
    if not problems:
        print(f"{len(edges)} folders, no include cycle; the agent's code does not read the scenario")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
