"""Read and write a skinned glTF 2.0 character (``.glb`` or ``.gltf`` with its buffers).

trimesh loads glTF meshes but drops skins, so this small reader takes what skinning needs straight from the
JSON and the binary buffer (glTF 2.0 spec, sections 3.6 "Buffers", 3.7 "Skins"):

* ``vertices (V, 3)``, ``normals (V, 3)``, ``faces (K, 3)`` of every triangle primitive of the first skinned
  mesh node, concatenated;
* ``joints (V, 4)`` and ``weights (V, 4)`` (``JOINTS_0``/``WEIGHTS_0``, indices into the skin's joints;
  normalised integer weights are scaled to [0, 1]; each row is renormalised to sum to 1);
* ``joint_names (J,)``, ``parents (J,)`` (the nearest ancestor node that is also a joint, -1 for none) and
  ``bind_positions (J, 3)``: joint j's position in the bind pose, the translation of ``inverse(IBM_j)`` where
  ``IBM_j`` is the skin's inverse bind matrix (it maps mesh space to joint j's local space).

The bind pose is the pose the vertices are modelled in; a skinned vertex is
``v' = sum_k w_k (G_{j_k} IBM_{j_k}) v`` with ``G_j`` joint j's world transform. :func:`write_skinned_glb`
writes a character in the same form (joints with translations only, ``IBM_j = translate(-b_j)``), used to
derive the shipped character and by the tests.
"""
from __future__ import annotations

import base64
import json
import os
import pathlib
import struct
from dataclasses import dataclass
from typing import NoReturn

import numpy as np

from evalsuite.errors import InputError

_COMPONENTS = {5120: np.int8, 5121: np.uint8, 5122: np.int16, 5123: np.uint16, 5125: np.uint32, 5126: np.float32}
_WIDTH = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT4": 16}
_GLB_MAGIC, _JSON_CHUNK, _BIN_CHUNK = 0x46546C67, 0x4E4F534A, 0x004E4942


@dataclass
class SkinnedMesh:
    """A character in its bind pose (see the module doc for each array's meaning)."""

    vertices: np.ndarray        # (V, 3) float64
    normals: np.ndarray         # (V, 3) float64, unit
    faces: np.ndarray           # (K, 3) uint32
    joints: np.ndarray          # (V, 4) int64, indices into joint_names
    weights: np.ndarray         # (V, 4) float64, rows sum to 1
    joint_names: list
    parents: np.ndarray         # (J,) int64, -1 for roots
    bind_positions: np.ndarray  # (J, 3) float64
    source: str = ""


def _fail(path, message: str) -> NoReturn:
    raise InputError(message, path=path, field="character")


def _load_json_and_bin(path: pathlib.Path) -> tuple[dict, bytes | None]:
    try:
        raw = path.read_bytes()
    except OSError as e:
        _fail(path, f"cannot read the character file ({e.strerror or e})")
    if raw[:4] == b"glTF":
        try:
            magic, version, _length = struct.unpack_from("<III", raw, 0)
            chunk_len, chunk_type = struct.unpack_from("<II", raw, 12)
            doc = json.loads(raw[20:20 + chunk_len])
            off = 20 + chunk_len
            binary = None
            if off + 8 <= len(raw):
                bin_len, bin_type = struct.unpack_from("<II", raw, off)
                if bin_type == _BIN_CHUNK:
                    binary = raw[off + 8:off + 8 + bin_len]
        except (struct.error, ValueError, UnicodeDecodeError) as e:
            _fail(path, f"not a readable binary glTF (.glb): {e}")
        if magic != _GLB_MAGIC or version != 2 or chunk_type != _JSON_CHUNK:
            _fail(path, f"expected a glTF 2.0 binary file, got version {version}")
        return doc, binary
    try:
        return json.loads(raw), None
    except (ValueError, UnicodeDecodeError) as e:
        _fail(path, f"expected a glTF 2.0 file (.glb, or .gltf JSON), could not parse it: {e}")


def _buffers(doc: dict, glb_bin: bytes | None, path: pathlib.Path) -> list[bytes]:
    out: list[bytes] = []
    for i, buf in enumerate(doc.get("buffers", [])):
        uri = buf.get("uri")
        if uri is None:
            if glb_bin is None:
                _fail(path, f"buffers[{i}] has no uri and the file has no binary chunk")
            else:
                out.append(glb_bin)
        elif uri.startswith("data:"):
            out.append(base64.b64decode(uri.split(",", 1)[1]))
        else:
            target = path.parent / uri
            if not target.is_file():
                _fail(path, f"buffers[{i}] names {uri!r}, which is not beside the file")
            out.append(target.read_bytes())
    return out


def _accessor(doc: dict, buffers: list[bytes], index: int, path) -> np.ndarray:
    try:
        acc = doc["accessors"][index]
        dtype = np.dtype(_COMPONENTS[acc["componentType"]])
        width = _WIDTH[acc["type"]]
        count = int(acc["count"])
        view = doc["bufferViews"][acc["bufferView"]]
        data = buffers[view["buffer"]]
    except (KeyError, IndexError, TypeError) as e:
        _fail(path, f"accessor {index} is malformed or points to a missing buffer view ({e})")
    start = view.get("byteOffset", 0) + acc.get("byteOffset", 0)
    stride = view.get("byteStride") or dtype.itemsize * width
    if start + stride * (count - 1) + dtype.itemsize * width > len(data):
        _fail(path, f"accessor {index} runs past the end of its buffer")
    rows = np.ndarray((count, width), dtype=dtype, buffer=data, offset=start, strides=(stride, dtype.itemsize))
    out = np.array(rows)
    if acc.get("normalized") and dtype.kind in "ui":
        out = out.astype(np.float64) / float(2 ** (8 * dtype.itemsize - (dtype.kind == "i")) - 1)
    return out


def read_skinned_gltf(path) -> SkinnedMesh:
    """The first skinned mesh of a glTF 2.0 file; one-line :class:`InputError` naming the file when it has none."""
    path = pathlib.Path(path)
    doc, glb_bin = _load_json_and_bin(path)
    buffers = _buffers(doc, glb_bin, path)
    nodes = doc.get("nodes", [])
    node = next((n for n in nodes if "skin" in n and "mesh" in n), None)
    if node is None or not doc.get("skins"):
        _fail(path, "the glTF has no skinned mesh (no node with both 'mesh' and 'skin'); the character style "
                    "needs a rigged character with JOINTS_0/WEIGHTS_0")
    skin = doc["skins"][node["skin"]]
    parts = []
    offset = 0
    for k, prim in enumerate(doc["meshes"][node["mesh"]]["primitives"]):
        attrs = prim.get("attributes", {})
        if prim.get("mode", 4) != 4:
            continue
        missing = [a for a in ("POSITION", "JOINTS_0", "WEIGHTS_0") if a not in attrs]
        if missing:
            _fail(path, f"mesh primitive {k} lacks {', '.join(missing)}: not skinned")
        pos = _accessor(doc, buffers, attrs["POSITION"], path).astype(np.float64)
        faces = (_accessor(doc, buffers, prim["indices"], path).reshape(-1, 3).astype(np.int64) if "indices" in prim
                 else np.arange(len(pos)).reshape(-1, 3))
        normals = (_accessor(doc, buffers, attrs["NORMAL"], path).astype(np.float64) if "NORMAL" in attrs else None)
        parts.append((pos, normals, faces + offset, _accessor(doc, buffers, attrs["JOINTS_0"], path).astype(np.int64),
                      _accessor(doc, buffers, attrs["WEIGHTS_0"], path).astype(np.float64)))
        offset += len(pos)
    if not parts:
        _fail(path, "the skinned mesh has no triangle primitive")
    vertices = np.concatenate([p[0] for p in parts])
    faces = np.concatenate([p[2] for p in parts])
    if any(p[1] is None for p in parts):
        import trimesh

        normals = np.asarray(trimesh.Trimesh(vertices, faces, process=False).vertex_normals, dtype=np.float64)
    else:
        normals = np.concatenate([p[1] for p in parts])
    joints = np.concatenate([p[3] for p in parts])
    weights = np.concatenate([p[4] for p in parts])
    joint_nodes = list(skin["joints"])
    if joints.max(initial=0) >= len(joint_nodes) or joints.min(initial=0) < 0:
        _fail(path, f"JOINTS_0 refers to joint {int(joints.max())}, but the skin has {len(joint_nodes)} joints")
    total = weights.sum(axis=1, keepdims=True)
    if np.any(total <= 0):
        _fail(path, f"{int((total <= 0).sum())} vertices have no skin weight (WEIGHTS_0 sums to 0)")
    weights = weights / total
    if "inverseBindMatrices" in skin:
        ibm = _accessor(doc, buffers, skin["inverseBindMatrices"], path).reshape(-1, 4, 4).transpose(0, 2, 1)
        bind = np.linalg.inv(ibm.astype(np.float64))[:, :3, 3]
    else:
        bind = _node_world(nodes)[joint_nodes][:, :3, 3]
    parent_node = {c: i for i, n in enumerate(nodes) for c in n.get("children", [])}
    index = {n: j for j, n in enumerate(joint_nodes)}
    parents = []
    for n in joint_nodes:
        p = parent_node.get(n)
        while p is not None and p not in index:
            p = parent_node.get(p)
        parents.append(index[p] if p is not None else -1)
    names = [str(nodes[n].get("name", f"joint{j}")) for j, n in enumerate(joint_nodes)]
    length = np.linalg.norm(normals, axis=1, keepdims=True)
    normals = np.where(length > 1e-8, normals / np.maximum(length, 1e-12), [0.0, 0.0, 1.0])   # unused vertices
    return SkinnedMesh(vertices, normals,
                       faces.astype(np.uint32), joints, weights, names, np.array(parents, dtype=np.int64), bind,
                       os.fspath(path))


def _node_world(nodes: list) -> np.ndarray:
    """World matrices ``(N, 4, 4)`` of the nodes (translation, rotation quaternion xyzw, scale, or matrix)."""
    from scipy.spatial.transform import Rotation

    local = np.repeat(np.eye(4)[None], len(nodes), axis=0)
    for i, n in enumerate(nodes):
        if "matrix" in n:
            local[i] = np.asarray(n["matrix"], float).reshape(4, 4).T
        else:
            local[i, :3, :3] = Rotation.from_quat(n.get("rotation", [0, 0, 0, 1])).as_matrix() * np.asarray(
                n.get("scale", [1, 1, 1]), float)
            local[i, :3, 3] = n.get("translation", [0, 0, 0])
    world = local.copy()
    parent = {c: i for i, n in enumerate(nodes) for c in n.get("children", [])}
    for i in range(len(nodes)):
        m, p = local[i], parent.get(i)
        while p is not None:
            m, p = local[p] @ m, parent.get(p)
        world[i] = m
    return world


def write_skinned_glb(path, vertices, faces, joint_names, parents, bind_positions, joints, weights,
                      normals=None) -> pathlib.Path:
    """Write a skinned character as ``.glb``: joints translated only, ``IBM_j = translate(-bind_positions[j])``.

    Shapes: vertices/normals ``(V, 3)``, faces ``(K, 3)``, joints/weights ``(V, 4)``, bind_positions ``(J, 3)``.
    """
    vertices = np.asarray(vertices, np.float32)
    faces = np.asarray(faces, np.uint32)
    if normals is None:
        import trimesh

        normals = trimesh.Trimesh(vertices, faces, process=False).vertex_normals
    bind = np.asarray(bind_positions, np.float64)
    parents = [int(p) for p in parents]
    ibm = np.repeat(np.eye(4, dtype=np.float32)[None], len(bind), axis=0)
    ibm[:, :3, 3] = -bind
    arrays = [(vertices, 5126, "VEC3", 34962), (np.asarray(normals, np.float32), 5126, "VEC3", 34962),
              (np.asarray(joints, np.uint16), 5123, "VEC4", 34962), (np.asarray(weights, np.float32), 5126, "VEC4", 34962),
              (faces.reshape(-1, 1), 5125, "SCALAR", 34963), (ibm.transpose(0, 2, 1).reshape(-1, 16), 5126, "MAT4", None)]
    blob, views, accessors = b"", [], []
    for i, (a, ctype, kind, target) in enumerate(arrays):
        data = np.ascontiguousarray(a).tobytes()
        view = {"buffer": 0, "byteOffset": len(blob), "byteLength": len(data)}
        if target:
            view["target"] = target
        views.append(view)
        acc = {"bufferView": i, "componentType": ctype, "count": len(a), "type": kind}
        if i == 0:
            acc["min"], acc["max"] = vertices.min(axis=0).tolist(), vertices.max(axis=0).tolist()
        accessors.append(acc)
        blob += data + b"\0" * (-len(data) % 4)
    n_j = len(bind)
    nodes: list[dict] = []
    for j, name in enumerate(joint_names):
        p = parents[j]
        t = bind[j] - (bind[p] if p >= 0 else 0.0)
        nodes.append({"name": str(name), "translation": [float(x) for x in t]})
    for j, p in enumerate(parents):
        if p >= 0:
            nodes[p].setdefault("children", []).append(j)
    nodes.append({"name": "body", "mesh": 0, "skin": 0})
    roots = [j for j, p in enumerate(parents) if p < 0] + [n_j]
    doc = {"asset": {"version": "2.0", "generator": "evalsuite renderers.gltf_skin"},
           "scene": 0, "scenes": [{"nodes": roots}], "nodes": nodes,
           "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1, "JOINTS_0": 2, "WEIGHTS_0": 3},
                                       "indices": 4}]}],
           "skins": [{"joints": list(range(n_j)), "inverseBindMatrices": 5}],
           "accessors": accessors, "bufferViews": views, "buffers": [{"byteLength": len(blob)}]}
    text = json.dumps(doc, separators=(",", ":")).encode()
    text += b" " * (-len(text) % 4)
    out = struct.pack("<III", _GLB_MAGIC, 2, 12 + 8 + len(text) + 8 + len(blob))
    out += struct.pack("<II", len(text), _JSON_CHUNK) + text + struct.pack("<II", len(blob), _BIN_CHUNK) + blob
    path = pathlib.Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(out)
    return path
