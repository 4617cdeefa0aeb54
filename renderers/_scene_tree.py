"""The node tree of a pyrender scene without importing networkx.

pyrender keeps a scene's nodes in a ``networkx.DiGraph`` with one edge from each node to its parent, and asks
it for three things: a node's parent (``neighbors``), the path from a node up to the root ``'world'``
(``networkx.shortest_path``) and the removal of a node. Importing networkx (its algorithms and backend
registry) costs 0.1 s of every rendering command's start, more than the command's first frame. So
:func:`renderers._gl.import_pyrender` imports ``pyrender.scene`` with :data:`NETWORKX` standing in for the
``networkx`` module; ``sys.modules`` gets the real package back at once, so any other code importing networkx
still gets networkx. A node with a second parent is refused instead of silently kept: pyrender never makes
one, and a tree is what the two calls above assume.
"""
from __future__ import annotations

import types
from collections.abc import Hashable, Iterator

__all__ = ["NodeTree", "shortest_path", "NETWORKX"]


class NodeTree:
    """A forest of hashable nodes, each with at most one parent: the part of ``networkx.DiGraph`` that
    ``pyrender.Scene`` uses (an edge ``add_edge(child, parent)`` points from a node to its parent)."""

    def __init__(self) -> None:
        self._parent: dict[Hashable, Hashable | None] = {}

    def add_node(self, node: Hashable) -> None:
        self._parent.setdefault(node, None)

    def add_edge(self, child: Hashable, parent: Hashable) -> None:
        self.add_node(parent)
        current = self._parent.get(child)
        if current is not None and current != parent:
            raise ValueError(f"{child!r} has a parent already ({current!r}); a scene node has one parent")
        self._parent[child] = parent

    def neighbors(self, node: Hashable) -> Iterator[Hashable]:
        """The nodes ``node`` has an edge to: its parent, if any (``DiGraph.neighbors``: successors)."""
        parent = self._parent[node]
        return iter(() if parent is None else (parent,))

    def remove_node(self, node: Hashable) -> None:
        del self._parent[node]
        for child, parent in self._parent.items():    # a child left behind becomes a root, as in networkx
            if parent == node:
                self._parent[child] = None

    def __contains__(self, node: object) -> bool:
        return node in self._parent

    def __len__(self) -> int:
        return len(self._parent)


def shortest_path(graph: NodeTree, source: Hashable, target: Hashable) -> list[Hashable]:
    """The nodes from ``source`` up to its ancestor ``target``, both included (``networkx.shortest_path`` on a
    tree whose edges point to parents). Raises ``ValueError`` when ``target`` is not an ancestor."""
    path = [source]
    while path[-1] != target:
        parent = graph._parent[path[-1]]
        if parent is None:
            raise ValueError(f"no path from {source!r} to {target!r}")
        path.append(parent)
    return path


NETWORKX = types.ModuleType("networkx", "the part of networkx pyrender.scene uses (renderers._scene_tree)")
NETWORKX.DiGraph = NodeTree            # type: ignore[attr-defined]
NETWORKX.shortest_path = shortest_path  # type: ignore[attr-defined]
