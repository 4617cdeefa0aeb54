"""EMAGE's skeleton-aware FGD autoencoder (``VAESKConv``, checkpoint ``AESKConv_240_100.bin``), written anew.

The GENEA Leaderboard and EMAGE/BEAT2 compute FGD on the latents of this network (``metrics.md`` §2.6).
Architecture facts (read from PantoMatrix ``emage_evaltools`` and its skeleton module):

* Input: 6D rotations of the 55 SMPL-X joints, ``(B, T, 330)``, joint ``j`` at columns ``6j..6j+5``; ``T`` cut
  to a multiple of 32 frames.
* Skeleton: edge 0 joins the pelvis to a virtual joint 55, edge ``i`` (1..54) is ``(parent[i], i)``; edge ``i``
  carries joint ``i``'s channels. Two edges are neighbours when they share a joint; a convolution output for an
  edge sees every edge at graph distance <= 2.
* 4 residual blocks, channels per edge 6, 6, 6, 12, 12 (growth 1, 1, 2, 1). Block: ``tanh(pool(GN(conv4(x)) +
  conv1(x)))`` with ``conv4`` kernel 4 / stride 2 / zero padding 1, ``conv1`` kernel 1 / stride 2, both masked
  to the neighbourhood; ``GN`` = GroupNorm with 10 groups; ``pool`` averages chains of edges (pairs; the last
  block averages each whole chain into one edge, 20 chains x 12 = 240 channels).
* Latent (``map2latent``, not variational): the last block's output, ``(B, T/16, 240)``.

The checkpoint also holds the decoder and the unused ``fc_mu``/``fc_logvar``; they are built here too so that
``load_state_dict(strict=True)`` checks every tensor of the published file.
"""
from __future__ import annotations

import hashlib
import pathlib

import numpy as np
import torch
from scipy.sparse.csgraph import shortest_path
from scipy.spatial.transform import Rotation
from torch import nn
from torch.nn import functional as F

from evalsuite.errors import InputError
from evalsuite.motion.smplx_layout import SMPLX_PARENTS

VAE_LENGTH = 240
INPUT_DIM = 330
CHUNK = 32
DOWNSAMPLE = 16
GROWTH = (1, 1, 2, 1)
CHANNEL_BASE = 6
NEIGHBOUR_DISTANCE = 2
GROUPS = 10
EMAGE_FORMAT = "evalsuite-emage-aeskconv"


def skeleton_edges(parents=SMPLX_PARENTS) -> list[tuple[int, int]]:
    """Edges (parent, child): edge 0 = (0, J) to a virtual joint J = len(parents), edge i = (parents[i], i)."""
    return [(0, len(parents))] + [(int(parents[i]), i) for i in range(1, len(parents))]


def edge_neighbours(edges, distance: int = NEIGHBOUR_DISTANCE) -> list[list[int]]:
    """For each edge, the sorted indices of edges at most ``distance`` hops away (sharing a joint = 1 hop)."""
    n = len(edges)
    adj = np.zeros((n, n))
    for i, a in enumerate(edges):
        for j, b in enumerate(edges):
            if i != j and set(a) & set(b):
                adj[i, j] = 1
    dist = shortest_path(adj, unweighted=True)
    return [[j for j in range(n) if dist[i, j] <= distance] for i in range(n)]


def pooling_groups(edges, last: bool) -> tuple[list[list[int]], list[tuple[int, int]]]:
    """Chains of edges between branching joints, split into pooled groups, and the pooled skeleton's edges.

    A depth-first walk from joint 0 (children in edge order) cuts a chain at every joint of degree > 2 (other
    than 0) and at leaves. Non-last: an odd chain keeps its first edge alone, the rest are averaged in pairs;
    last: each whole chain is one group.
    """
    degree: dict[int, int] = {}
    for a, b in edges:
        degree[a] = degree.get(a, 0) + 1
        degree[b] = degree.get(b, 0) + 1
    chains: list[list[int]] = []

    def walk(joint: int, chain: list[int]) -> None:
        if degree[joint] > 2 and joint != 0:
            chains.append(chain)
            chain = []
        if degree[joint] == 1:
            chains.append(chain)
            return
        for idx, (a, b) in enumerate(edges):
            if a == joint:
                walk(b, chain + [idx])

    walk(0, [])
    groups: list[list[int]] = []
    new_edges: list[tuple[int, int]] = []
    for chain in chains:
        if last:
            groups.append(chain)
            continue
        if len(chain) % 2 == 1:
            groups.append([chain[0]])
            new_edges.append(tuple(edges[chain[0]]))
            chain = chain[1:]
        for k in range(0, len(chain), 2):
            groups.append([chain[k], chain[k + 1]])
            new_edges.append((edges[chain[k]][0], edges[chain[k + 1]][1]))
    return groups, new_edges


class SkeletonConv(nn.Module):
    """Conv1d whose weight (out, in, k) is multiplied by a fixed 0/1 mask: output edge e sees its neighbours."""

    def __init__(self, neighbours, in_per_edge: int, out_per_edge: int, kernel: int, stride: int, padding: int):
        super().__init__()
        n = len(neighbours)
        self.stride, self.padding = stride, padding
        self.weight = nn.Parameter(torch.zeros(out_per_edge * n, in_per_edge * n, kernel))
        self.bias = nn.Parameter(torch.zeros(out_per_edge * n))
        mask = torch.zeros_like(self.weight)
        for e, near in enumerate(neighbours):
            cols = [k * in_per_edge + c for k in near for c in range(in_per_edge)]
            mask[e * out_per_edge:(e + 1) * out_per_edge, cols, :] = 1
        self.mask = nn.Parameter(mask, requires_grad=False)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        x = F.pad(x, (self.padding, self.padding))
        return F.conv1d(x, self.weight * self.mask, self.bias, self.stride)


class SkeletonPool(nn.Module):
    """Mean over each group of edges, per channel: ``y = W x`` with W (groups*c, edges*c)."""

    def __init__(self, groups, n_edges: int, per_edge: int):
        super().__init__()
        w = torch.zeros(len(groups) * per_edge, n_edges * per_edge)
        for g, members in enumerate(groups):
            for e in members:
                for c in range(per_edge):
                    w[g * per_edge + c, e * per_edge + c] = 1.0 / len(members)
        self.weight = nn.Parameter(w, requires_grad=False)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return torch.matmul(self.weight, x)


class SkeletonResidual(nn.Module):
    """``tanh(pool(GroupNorm(conv_k4_s2(x)) + conv_k1_s2(x)))`` on (B, edges*c_in, T) -> (B, groups*c_out, T/2)."""

    def __init__(self, edges, c_in: int, c_out: int, last: bool):
        super().__init__()
        near = edge_neighbours(edges)
        self.residual = nn.Sequential(SkeletonConv(near, c_in, c_out, 4, 2, 1), nn.GroupNorm(GROUPS, c_out * len(edges)))
        self.shortcut = SkeletonConv(near, c_in, c_out, 1, 2, 0)
        groups, self.new_edges = pooling_groups(edges, last)
        parts: list[nn.Module] = []
        if len(groups) != len(edges):
            parts.append(SkeletonPool(groups, len(edges), c_out))
        parts.append(nn.Tanh())
        self.common = nn.Sequential(*parts)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return self.common(self.residual(x) + self.shortcut(x))


class LocalEncoder(nn.Module):
    """Four skeleton residual blocks: (B, T, 330) -> (B, T/16, 240)."""

    def __init__(self, parents=SMPLX_PARENTS):
        super().__init__()
        edges = skeleton_edges(parents)
        base = [CHANNEL_BASE]
        for g in GROWTH:
            base.append(base[-1] * g)
        self.layers = nn.ModuleList()
        for i in range(len(GROWTH)):
            block = SkeletonResidual(edges, base[i], base[i + 1], last=i == len(GROWTH) - 1)
            self.layers.append(nn.Sequential(block))
            edges = block.new_edges

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        out = x.permute(0, 2, 1)
        for layer in self.layers:
            out = layer(out)
        return out.permute(0, 2, 1)


class _ResBlock(nn.Module):
    def __init__(self, ch: int):
        super().__init__()
        self.model = nn.Sequential(nn.Conv1d(ch, ch, 3, 1, 1), nn.LeakyReLU(0.2), nn.Conv1d(ch, ch, 3, 1, 1))

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return x + self.model(x)


class Decoder(nn.Module):
    """The checkpoint's decoder (2 residual blocks, 4 x [upsample 2, conv3, leaky ReLU], conv3); kept for loading."""

    def __init__(self):
        super().__init__()
        chans = [VAE_LENGTH] * 4 + [INPUT_DIM]
        parts: list[nn.Module] = [_ResBlock(VAE_LENGTH), _ResBlock(VAE_LENGTH)]
        for i in range(4):
            parts += [nn.Upsample(scale_factor=2, mode="nearest"), nn.Conv1d(chans[i], chans[i + 1], 3, 1, 1),
                      nn.LeakyReLU(0.2)]
        parts.append(nn.Conv1d(INPUT_DIM, INPUT_DIM, 3, 1, 1))
        self.main = nn.Sequential(*parts)

    def forward(self, z: torch.Tensor) -> torch.Tensor:
        return self.main(z.permute(0, 2, 1)).permute(0, 2, 1)


class AESKConv(nn.Module):
    """The whole published network; :meth:`map2latent` is what FGD uses."""

    def __init__(self, parents=SMPLX_PARENTS):
        super().__init__()
        self.encoder = LocalEncoder(parents)
        self.decoder = Decoder()
        self.fc_mu = nn.Linear(VAE_LENGTH, VAE_LENGTH)
        self.fc_logvar = nn.Linear(VAE_LENGTH, VAE_LENGTH)

    def map2latent(self, x: torch.Tensor) -> torch.Tensor:
        return self.encoder(x)


def expected_shapes() -> dict[str, tuple[int, ...]]:
    """Every tensor name and shape of the published state dict (after removing a ``module.`` prefix)."""
    return {k: tuple(v.shape) for k, v in AESKConv().state_dict().items()}


def axis_angle_to_rot6d(poses: np.ndarray) -> np.ndarray:
    """Axis-angle (T, 3J) -> 6D (T, 6J): per joint R = exp([r]x), 6D = [R[0,0..2], R[1,0..2]] (first two ROWS,
    the PyTorch3D ``matrix_to_rotation_6d`` that EMAGE uses)."""
    poses = np.asarray(poses, dtype=np.float64)
    if poses.ndim != 2 or poses.shape[1] % 3:
        raise InputError(f"axis-angle poses must be (T, 3*J), got shape {poses.shape}")
    t, d = poses.shape
    mats = Rotation.from_rotvec(poses.reshape(-1, 3)).as_matrix()
    return mats[:, :2, :].reshape(t, 2 * d)


def state_from_checkpoint(obj, source: str = "checkpoint") -> dict[str, torch.Tensor]:
    """The state dict inside a loaded EMAGE ``.bin`` (``model_state``, ``module.`` removed), checked key by key."""
    state = obj.get("model_state", obj) if isinstance(obj, dict) else None
    if not isinstance(state, dict):
        raise InputError(f"{source}: expected a torch state dict (or a dict with 'model_state'), got {type(obj).__name__}")
    state = {(k[7:] if k.startswith("module.") else k): v for k, v in state.items()}
    want = expected_shapes()
    missing = [k for k in want if k not in state]
    if missing:
        raise InputError(f"{source}: not an AESKConv_240 checkpoint: key {missing[0]!r} missing "
                         f"({len(missing)} missing in all)")
    extra = [k for k in state if k not in want]
    if extra:
        raise InputError(f"{source}: not an AESKConv_240 checkpoint: unexpected key {extra[0]!r}")
    for k, shape in want.items():
        got = tuple(state[k].shape)
        if got != shape:
            raise InputError(f"{source}: key {k!r} has shape {got}, expected {shape}")
    return {k: state[k].detach().to(torch.float32) for k in want}


def build_model(state: dict[str, torch.Tensor]) -> AESKConv:
    model = AESKConv()
    model.load_state_dict(state, strict=True)
    return model.eval()


def import_emage(checkpoint, out, source_note: str | None = None, allow_pickle: bool = False) -> AESKConv:
    """Convert ``AESKConv_240_100.bin`` into an evalsuite model file (state dict + provenance + input convention)."""
    checkpoint = pathlib.Path(checkpoint)
    try:
        obj = torch.load(checkpoint, map_location="cpu", weights_only=not allow_pickle)
    except Exception as exc:  # torch raises many types for a bad file
        hint = "" if allow_pickle else "; if it is a trusted file holding pickled objects, pass --unsafe-pickle"
        raise InputError(f"{checkpoint}: cannot be read as a torch checkpoint ({type(exc).__name__}){hint}") from None
    state = state_from_checkpoint(obj, str(checkpoint))
    model = build_model(state)
    meta = {
        "architecture": "VAESKConv (EMAGE AESKConv_240)",
        "source_file": checkpoint.name, "source_sha256": hashlib.sha256(checkpoint.read_bytes()).hexdigest(),
        "source_note": source_note or "EMAGE emage_evaltools AESKConv_240_100.bin, downloaded by the user",
        "input": "6D rotations (first two rows of each joint's rotation matrix) of the 55 SMPL-X joints, "
                 "(T, 330) at 30 fps, T cut to a multiple of 32",
        "latent": f"(T/{DOWNSAMPLE}, {VAE_LENGTH}) per sequence", "fps": 30.0,
    }
    torch.save({"format": EMAGE_FORMAT, "format_version": 1, "meta": meta, "state_dict": state}, out)
    return model


def is_emage_model_file(obj) -> bool:
    return isinstance(obj, dict) and obj.get("format") == EMAGE_FORMAT and isinstance(obj.get("meta"), dict)


def load_emage_model(path) -> tuple[AESKConv, dict]:
    """Read a file written by :func:`import_emage`: (model in eval mode, meta)."""
    obj = torch.load(path, map_location="cpu", weights_only=True)
    if not is_emage_model_file(obj):
        raise InputError(f"{path}: not an evalsuite EMAGE AESKConv model file (write one with evalsuite fgd import-emage)")
    return build_model(state_from_checkpoint(obj["state_dict"], str(path))), obj["meta"]


def aeskconv_latents(model: AESKConv, rot6d: np.ndarray) -> np.ndarray:
    """Latents of one sequence as the Leaderboard takes them: rot6d (T, 330) -> (T'/16, 240), T' = T - T mod 32.

    One pass over the whole cut sequence (as ``emage_evaltools`` FGD.get_feature does), CPU, float32.
    """
    x = np.asarray(rot6d, dtype=np.float32)
    if x.ndim != 2 or x.shape[1] != INPUT_DIM:
        raise InputError(f"AESKConv input must be (T, {INPUT_DIM}) 6D rotations, got shape {x.shape}")
    n = x.shape[0] - x.shape[0] % CHUNK
    if n == 0:
        raise InputError(f"AESKConv needs at least {CHUNK} frames, got {x.shape[0]}")
    with torch.no_grad():
        return model.map2latent(torch.from_numpy(np.ascontiguousarray(x[:n]))[None]).numpy()[0]
