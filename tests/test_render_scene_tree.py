"""renderers._scene_tree: pyrender's scene graph kept without networkx gives the paths and poses networkx gives."""
import networkx
import numpy as np
import pytest

from renderers._gl import import_pyrender
from renderers._scene_tree import NETWORKX, NodeTree, shortest_path


def _translation(x, y, z):
    m = np.eye(4)
    m[:3, 3] = (x, y, z)
    return m


def test_paths_match_networkx_on_the_same_tree():
    edges = [("a", "world"), ("b", "a"), ("c", "b"), ("d", "a"), ("e", "world")]
    tree, graph = NodeTree(), networkx.DiGraph()
    for g in (tree, graph):
        g.add_node("world")
        for child, parent in edges:
            g.add_node(child)
            g.add_edge(child, parent)
    for node in "abcde":
        assert shortest_path(tree, node, "world") == networkx.shortest_path(graph, node, "world")
        assert list(tree.neighbors(node)) == list(graph.neighbors(node))
    tree.remove_node("b")
    graph.remove_node("b")
    assert "b" not in tree and len(tree) == graph.number_of_nodes()
    assert list(tree.neighbors("c")) == list(graph.neighbors("c")) == []   # c is a root now in both
    with pytest.raises(ValueError, match="no path"):
        shortest_path(tree, "c", "world")


def test_a_second_parent_is_refused():
    tree = NodeTree()
    tree.add_edge("hand", "arm")
    tree.add_edge("hand", "arm")            # the same edge again is fine
    with pytest.raises(ValueError, match="has a parent already"):
        tree.add_edge("hand", "leg")


@pytest.mark.parametrize("graphs", [NETWORKX, networkx], ids=["node tree", "networkx"])
def test_pyrender_scene_poses_and_removal_through_the_tree(monkeypatch, graphs):
    pr = import_pyrender()
    monkeypatch.setattr(pr.scene, "nx", graphs)
    scene = pr.Scene()
    root = pr.Node(name="root", matrix=_translation(1, 0, 0))
    scene.add_node(root)
    arm = pr.Node(name="arm", matrix=_translation(0, 2, 0))
    scene.add_node(arm, parent_node=root)
    hand = pr.Node(name="hand", matrix=_translation(0, 0, 3))
    scene.add_node(hand, parent_node=arm)
    np.testing.assert_allclose(scene.get_pose(hand)[:3, 3], [1, 2, 3])
    assert scene.get_pose(arm)[:3, 3].tolist() == [1, 2, 0]
    scene.remove_node(arm)                   # its child goes with it, as pyrender does
    assert hand not in scene.nodes and arm not in scene.nodes and root in scene.nodes
    np.testing.assert_allclose(scene.get_pose(root)[:3, 3], [1, 0, 0])


def test_pyrender_is_imported_with_the_tree_and_networkx_stays_real():
    import subprocess
    import sys

    code = ("import sys\nfrom renderers._gl import import_pyrender\npr = import_pyrender()\n"
            "print(pr.scene.nx.DiGraph.__name__, 'networkx' in sys.modules)\n"
            "import networkx\nprint(networkx.DiGraph.__module__)\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.split()
    assert out == ["NodeTree", "False", "networkx.classes.digraph"], out
