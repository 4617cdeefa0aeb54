"""Named setups of the learned metrics: joint sets with their position convention, and networks.

``JOINT_PRESETS``: a name gives the joints *and* the BVH translation convention the
reference extractor was trained with. ``genea2023`` = the 56 joints of the GENEA 2023 FGD
scripts with PyMO's convention (joint position channels added to the OFFSET), i.e. what
``load_motion(path, convention="pymo")`` computes. Every joint preset of
:mod:`evalsuite.motion.presets` is also accepted (with the motion's own convention).

``ARCHITECTURES``: the layer widths of each reference network (see network.py).
"""
from __future__ import annotations

from evalsuite.errors import InputError
from evalsuite.motion.presets import PRESETS

JOINT_PRESETS: dict[str, dict] = {
    "genea2023": {"joints": PRESETS["genea2023"], "convention": "pymo"},
    "genea2023_upper": {"joints": PRESETS["genea2023_upper"], "convention": "pymo"},
}

ARCHITECTURES: dict[str, dict] = {
    # GENEA 2022 widened the first convolutions to 128/64 channels; 2023 kept that network.
    "genea2023": {"conv_channels": (128, 64), "variational_head": False, "decoder_hidden": 64},
    "genea2022": {"conv_channels": (128, 64), "variational_head": False, "decoder_hidden": 64},
    "genea2020": {"conv_channels": (32, 64), "variational_head": False, "decoder_hidden": 64},
    # Yoon et al. 2020: bone directions, a (non-sampled) variational head; feature = fc_mu.
    "yoon2020": {"conv_channels": (32, 64), "variational_head": True, "decoder_hidden": 64},
}


def resolve_joint_spec(spec, available: list[str] | None = None) -> tuple[list[str], str | None]:
    """Joint names and convention from a preset name, ``"A,B,C"``, a list, or ``"all"``.

    ``"all"`` needs ``available`` (the joints of the data) and keeps them all.
    """
    if isinstance(spec, str):
        if spec in JOINT_PRESETS:
            p = JOINT_PRESETS[spec]
            return list(p["joints"]), p["convention"]
        if spec in PRESETS:
            return list(PRESETS[spec]), None
        if spec == "all":
            if available is None:
                raise InputError("joints 'all' needs data to take the joint names from")
            return list(available), None
        names = [n.strip() for n in spec.split(",") if n.strip()]
    else:
        names = [str(n) for n in spec]
    if not names:
        raise InputError(f"no joints in {spec!r}; give a preset ({', '.join(sorted(set(JOINT_PRESETS) | set(PRESETS)))}), "
                         "'all' or a comma-separated list")
    if len(set(names)) != len(names):
        raise InputError("joint names must be unique")
    return names, None


def architecture_preset(name: str) -> dict:
    if name not in ARCHITECTURES:
        raise InputError(f"unknown architecture {name!r}; expected one of {', '.join(ARCHITECTURES)}")
    return dict(ARCHITECTURES[name])
