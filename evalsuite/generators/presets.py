"""Named configurations of the re-implementations: ``cpu-small`` (evalsuite's variant) and ``paper``.

``cpu-small`` is what the plug-ins do with no option: narrower networks, shorter schedules and the regularisation
chosen on the synthetic speaker so that a CPU trains each system in minutes (docs/generators.md). It is
evalsuite's variant, not the published system. ``paper`` gives each system as its paper describes it (widths,
windows, losses and weights, features, schedule); where the paper is silent the original code's value is used and
the table says so. ``evalsuite train --preset NAME`` merges the preset's values under the user's own options
(``--set`` and ``--config`` win), and ``model.json`` / ``generation.json`` name the preset.

Each row of a system's table is one option: its ``cpu-small`` value (the plug-in's default), its ``paper`` value,
where the paper gives it (``source``), the original code's value where it differs (``code``), and the allowed
range (``allowed``). The rows come from the options' declarations (:mod:`evalsuite.generators.options`; each
system's in ``evalsuite/generators/<system>/options.py``), where the plug-in's defaults and help are declared too.
"""
from __future__ import annotations

import json
import pathlib
from collections.abc import Mapping
from typing import Any

from evalsuite.errors import InputError
from evalsuite.generators.aud2repr2pose.options import OPTIONS as AUD2
from evalsuite.generators.ferstl_mogan.options import OPTIONS as FERSTL
from evalsuite.generators.gesticulator.options import OPTIONS as GESTICULATOR
from evalsuite.generators.gesture2vec.options import OPTIONS as GESTURE2VEC
from evalsuite.generators.options import Options, PresetOption

__all__ = ["PresetOption", "PRESETS", "DEFAULT_PRESET", "SYSTEM_OPTIONS", "DECLARED", "system_options",
           "preset_values", "apply_preset", "model_preset", "markdown_table"]

PRESETS = ("cpu-small", "paper")
DEFAULT_PRESET = "cpu-small"


# each system's options, declared once (evalsuite/generators/<system>/options.py)
DECLARED: dict[str, Options] = {"gesticulator": GESTICULATOR, **AUD2, "gesture2vec": GESTURE2VEC, "ferstl-mogan": FERSTL}
# each system's rows of the presets table, from those declarations
SYSTEM_OPTIONS: dict[str, tuple[PresetOption, ...]] = {name: o.preset_rows() for name, o in DECLARED.items()}


def system_options(generator: str) -> Options:
    """The options ``generator`` declares (its defaults, help, ranges and paper values)."""
    if generator not in DECLARED:
        raise InputError(f"{generator} declares no options here (re-implementations: {', '.join(DECLARED)})",
                         field="--generator")
    return DECLARED[generator]


def preset_values(generator: str, preset: str) -> dict[str, Any]:
    """The options ``preset`` sets for ``generator``: nothing for ``cpu-small`` (the plug-in's defaults are that
    preset), the table's ``paper`` column for ``paper``."""
    if preset not in PRESETS:
        raise InputError(f"unknown preset {preset!r}; presets: {', '.join(PRESETS)}", field="--preset")
    if preset == DEFAULT_PRESET:
        return {}
    if generator not in SYSTEM_OPTIONS:
        raise InputError(f"{generator} has no '{preset}' preset (presets exist for "
                         f"{', '.join(SYSTEM_OPTIONS)})", field="--preset")
    return {o.name: o.paper for o in SYSTEM_OPTIONS[generator]}


def apply_preset(generator: str, preset: str, config: Mapping[str, Any]) -> dict[str, Any]:
    """``config`` over the preset's values (the user's options win)."""
    return {**preset_values(generator, preset), **dict(config)}


def model_preset(model_dir: str | pathlib.Path | None) -> str | None:
    """The preset a model folder was trained with (``model.json``), or None (no folder, or not trained here)."""
    if model_dir is None:
        return None
    try:
        record = json.loads((pathlib.Path(model_dir) / "model.json").read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    return record.get("preset") if isinstance(record, dict) else None


def markdown_table(generator: str) -> str:
    """The docs' table of one system: option, the paper's value (with its source), the original code's where it
    differs, and each preset's."""
    lines = ["| option | paper (source) | original code | `paper` | `cpu-small` |", "|---|---|---|---|---|"]
    for o in SYSTEM_OPTIONS[generator]:
        lines.append(f"| `{o.name}` | {o.source} | {o.code or 'same'} | {o.paper} | {o.cpu_small} |")
    return "\n".join(lines)
