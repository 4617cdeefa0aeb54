"""Finding generators: the built-in table, installed plug-ins, and ad-hoc ``module:Class`` / ``file.py:Class``.

* **Built-in**: :data:`BUILTIN` maps a name to ``"module:Class"``; the modules are cheap to import (no torch
  at import time), so listing them reads their specs.
* **Installed plug-ins**: packages declare an entry point in the group ``evalsuite.generators``
  (``name = "package.module:Class"``). Listing shows them *without importing them* (name, distribution,
  target); ``info`` and ``generate`` import the one asked for. A built-in name cannot be taken over.
* **Registered** in a running process: :func:`register_generator`.
* **Ad-hoc**: ``-g package.module:Class`` or ``-g path/to/file.py:Class``.
"""
from __future__ import annotations

import importlib
import importlib.util
import pathlib
import sys
from dataclasses import dataclass

from evalsuite.errors import UnknownNameError
from evalsuite.generators.contract import Generator, GeneratorError, GeneratorSpec
from evalsuite.registry import Registry

__all__ = ["BUILTIN", "ENTRY_POINT_GROUP", "GENERATORS", "GeneratorEntry", "UnknownGeneratorError",
           "list_generators", "find_generator", "generator_class", "register_generator"]

ENTRY_POINT_GROUP = "evalsuite.generators"

BUILTIN: dict[str, str] = {
    # conditions (operators over the corpus's motion or any other condition)
    "natural": "evalsuite.generators.conditions.basic:Natural",
    "mean_pose": "evalsuite.generators.conditions.basic:MeanPose",
    "precomputed": "evalsuite.generators.conditions.basic:Precomputed",
    "mismatched": "evalsuite.generators.conditions.mismatched:Mismatched",
    "random_segments": "evalsuite.generators.conditions.random_segments:RandomSegments",
    "gaussian_noise": "evalsuite.generators.conditions.degradations:GaussianNoise",
    "attenuated": "evalsuite.generators.conditions.degradations:Attenuated",
    "fluctuation": "evalsuite.generators.conditions.degradations:Fluctuation",
    "fixing": "evalsuite.generators.conditions.degradations:Fixing",
    "smoothed": "evalsuite.generators.conditions.degradations:Smoothed",
    "oracle": "evalsuite.generators.conditions.oracle:Oracle",
    # re-implementations of the seed papers (trainable on a CPU)
    "gesticulator": "evalsuite.generators.gesticulator.plugin:Gesticulator",
    "aud2pose": "evalsuite.generators.aud2repr2pose.plugin:Aud2Pose",
    "aud2motion": "evalsuite.generators.aud2repr2pose.plugin:Aud2Motion",
    "aud2repr2pose": "evalsuite.generators.aud2repr2pose.plugin:Aud2Repr2Pose",
    "gesture2vec": "evalsuite.generators.gesture2vec.plugin:Gesture2Vec",
    "ferstl-mogan": "evalsuite.generators.ferstl_mogan.plugin:FerstlMogan",
    # published models
    "aud2repr2pose-demo": "evalsuite.generators.aud2repr2pose_demo.plugin:Aud2Repr2PoseDemoGenerator",
    # adapters
    "external": "evalsuite.generators.bridge:ExternalCommand",
    "gesticulator-original": "evalsuite.generators.gesticulator_original.plugin:GesticulatorOriginal",
}


@dataclass(frozen=True)
class GeneratorEntry:
    """A generator as listed: ``origin`` is ``"builtin"``, ``"entry point"``, ``"registered"`` or ``"ad hoc"``; ``spec`` is None
    for an installed plug-in that has not been imported."""

    name: str
    target: str
    origin: str
    distribution: str | None = None
    spec: GeneratorSpec | None = None


def _load_file_class(path: pathlib.Path, cls_name: str) -> type:
    if not path.is_file():
        raise GeneratorError(f"no such plug-in file {path}", field="generator")
    mod_name = f"evalsuite_plugin_{abs(hash(str(path.resolve())))}"
    spec = importlib.util.spec_from_file_location(mod_name, path)
    if spec is None or spec.loader is None:
        raise GeneratorError(f"cannot import {path} as a Python module", field="generator")
    module = importlib.util.module_from_spec(spec)
    sys.modules[mod_name] = module  # so that worker processes can unpickle its requests by module name
    spec.loader.exec_module(module)
    try:
        found: type = getattr(module, cls_name)
        return found
    except AttributeError:
        raise GeneratorError(f"{path} defines no {cls_name!r}", field="generator") from None


def generator_class(target: str) -> type[Generator]:
    """The class named by ``"module:Class"`` or ``"file.py:Class"``, checked to be a :class:`Generator`."""
    module_name, sep, cls_name = target.rpartition(":")
    if not sep or not module_name or not cls_name:
        raise GeneratorError(f"{target!r} is not a generator name, 'module:Class' or 'file.py:Class'",
                             field="generator")
    if module_name.endswith(".py") or "/" in module_name or "\\" in module_name:
        cls = _load_file_class(pathlib.Path(module_name), cls_name)
    else:
        try:
            module = importlib.import_module(module_name)
        except ModuleNotFoundError as exc:
            raise GeneratorError(f"cannot import {module_name!r} for generator {target!r}: {exc}",
                                 field="generator") from None
        attr = getattr(module, cls_name, None)
        if attr is None:
            raise GeneratorError(f"module {module_name!r} has no {cls_name!r}", field="generator")
        cls = attr
    return _checked(cls, target)


def _checked(cls: object, target: str) -> type[Generator]:
    if not (isinstance(cls, type) and issubclass(cls, Generator)):
        raise GeneratorError(f"{target!r} is not a subclass of evalsuite.generators.Generator", field="generator")
    if not isinstance(getattr(cls, "spec", None), GeneratorSpec):
        raise GeneratorError(f"{target!r} has no GeneratorSpec in its 'spec' attribute", field="generator")
    return cls


def _target_of(cls: type) -> str:
    return f"{cls.__module__}:{cls.__qualname__}"


class UnknownGeneratorError(GeneratorError, UnknownNameError):
    """A generator name that is neither built in, registered, installed nor ``module:Class``."""


GENERATORS: Registry[type[Generator]] = Registry(
    "generator", ENTRY_POINT_GROUP, load=generator_class, error=UnknownGeneratorError, field="generator",
    hint=" (or give 'module:Class' / 'file.py:Class')")
for _name, _target in BUILTIN.items():
    GENERATORS.register_lazy(_name, _target)


def register_generator(name: str, cls: type[Generator], *, replace: bool = False) -> type[Generator]:
    """Add a generator class under ``name`` in this process (an installed package uses an entry point)."""
    return GENERATORS.register(name, _checked(cls, _target_of(cls)), replace=replace)


def _entry(name: str, cls: type[Generator] | None) -> GeneratorEntry:
    e = GENERATORS.entry(name)
    target = e.target or (_target_of(cls) if cls is not None else "")
    return GeneratorEntry(name, target, e.origin, e.distribution, cls.spec if cls is not None else None)


def list_generators() -> list[GeneratorEntry]:
    """Built-ins and registered ones (with their specs) and installed plug-ins (not imported), sorted by name."""
    out = [_entry(e.name, None if e.origin == "entry point" and not e.loaded else GENERATORS.get(e.name))
           for e in GENERATORS.entries()]
    return sorted(out, key=lambda e: e.name)


def find_generator(name: str) -> GeneratorEntry:
    """A generator by built-in name, installed plug-in name, or ``module:Class`` / ``file.py:Class``."""
    if name in GENERATORS:
        return _entry(name, GENERATORS.get(name))
    if ":" in name:
        cls = generator_class(name)
        return GeneratorEntry(cls.spec.name, name, "ad hoc", None, cls.spec)
    raise GENERATORS.unknown(name)
