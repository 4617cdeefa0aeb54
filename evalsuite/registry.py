"""One registry type for every extension point, with installed plug-ins found through entry points.

The extension points and their entry-point groups (``docs/architecture.md`` has a worked example of each):

=====================  ===============================  ==================================================
registry               group                            an entry point gives
=====================  ===============================  ==================================================
metric families        ``evalsuite.metric_families``    a ``MetricFamily`` (instance or subclass)
study page kinds       ``evalsuite.page_kinds``         a ``PageKind`` (instance or subclass)
generators             ``evalsuite.generators``         a ``Generator`` subclass
corpus layouts         ``evalsuite.corpus_layouts``     a ``Layout``, or a ``@register_layout`` function
transcript formats     ``evalsuite.transcript_formats`` a ``TranscriptFormat``
feature recipes        ``evalsuite.feature_recipes``    a ``Recipe``
motion formats         ``evalsuite.motion_formats``     a ``MotionFormat``
judgement importers    ``evalsuite.judgement_formats``  an ``Importer`` (:mod:`evalsuite.analysis.importers`)
critic encoders        ``evalsuite.critic_encoders``    an ``Encoder`` (:mod:`evalsuite.critic`)
=====================  ===============================  ==================================================

A :class:`Registry` maps a name to an item and is a read-only ``Mapping``:

* :meth:`~Registry.register` adds an item; :meth:`~Registry.register_lazy` adds a ``"module:attr"`` target
  that is imported on first use (the built-in generators);
* an installed package adds items with entry points in the registry's group (``name = "package.module:attr"``).
  The group is read (package metadata only, nothing imported) on the first lookup of an unknown name or the
  first listing; an entry point is imported when its name is looked up or when every item is asked for.
  Its object is the item, a subclass of the item type (instantiated without arguments), or anything whose
  import registered the name itself (a module, a decorated function). A registered name wins over an entry
  point of the same name;
* :meth:`~Registry.get` (and ``registry[name]``) gives the item; an unknown name raises
  :class:`~evalsuite.errors.UnknownNameError` (a ``KeyError`` too) listing the known names and the closest
  ones; a plug-in that cannot be imported raises :class:`~evalsuite.errors.PluginError`;
* ``names()``, ``in``, ``len`` and iteration see every known name without importing anything;
  :meth:`~Registry.entries` says where each comes from; ``loaded()``, ``items()`` and ``values()`` import
  everything, skipping (with a warning) an installed plug-in that fails to load.
"""
from __future__ import annotations

import importlib
import importlib.metadata
import threading
import warnings
from collections.abc import Callable, ItemsView, Iterator, Mapping, ValuesView
from dataclasses import dataclass
from typing import Any, Generic, TypeVar, cast

from evalsuite.errors import InputError, PluginError, UnknownNameError, did_you_mean

__all__ = ["Registry", "Entry", "import_target"]

T = TypeVar("T")


@dataclass(frozen=True)
class Entry:
    """Where a name comes from: ``origin`` is ``"builtin"``, ``"registered"`` or ``"entry point"``;
    ``target`` the ``"module:attr"`` it is (or will be) imported from; ``distribution`` the installed package
    (``"name version"``) of an entry point; ``loaded`` whether the item has been imported."""

    name: str
    origin: str
    target: str | None = None
    distribution: str | None = None
    loaded: bool = False


def import_target(target: str) -> object:
    """The object named by ``"package.module:attr"`` (``attr`` may be dotted, e.g. ``Class.method``)."""
    module_name, sep, attr = target.partition(":")
    if not sep or not module_name.strip() or not attr.strip():
        raise PluginError(f"{target!r} is not 'package.module:attr'")
    obj: object = importlib.import_module(module_name.strip())
    for part in attr.strip().split("."):
        obj = getattr(obj, part)
    return obj


def _distribution(ep: importlib.metadata.EntryPoint) -> str | None:
    dist = getattr(ep, "dist", None)
    return f"{dist.name} {dist.version}" if dist is not None else None


class Registry(Mapping[str, T], Generic[T]):
    """Name -> item for one extension point.

    Args:
        what: what an item is called in messages ("metric family").
        group: the entry-point group installed packages use (None: no plug-ins).
        base: the item type; an entry point giving a subclass of it is instantiated without arguments, and
            anything that is not an instance is refused.
        name_of: the name an item carries itself (``family.name``); it must equal the registered name.
        check: called with ``(name, item)`` before every registration; raises ``ValueError`` to refuse.
        load: turns a ``"module:attr"`` target into an item (default: :func:`import_target` and the
            ``base`` rule); used for lazy entries and entry points.
        error: the :class:`UnknownNameError` subclass raised for an unknown name.
        field: the field named in errors ("metrics", "layout", ...).
        hint: appended to the list of known names in the unknown-name error.
    """

    def __init__(self, what: str, group: str | None = None, *, base: type | None = None,
                 name_of: Callable[[T], str] | None = None, check: Callable[[str, T], None] | None = None,
                 load: Callable[[str], T] | None = None, error: type[UnknownNameError] = UnknownNameError,
                 field: str | None = None, hint: str = "") -> None:
        self.what = what
        self.group = group
        self.field = field
        self._base = base
        self._name_of = name_of
        self._check = check
        self._load = load
        self._error = error
        self._hint = hint
        self._items: dict[str, T] = {}
        self._entries: dict[str, Entry] = {}
        self._eps: dict[str, importlib.metadata.EntryPoint] | None = None
        self._failed: dict[str, InputError] = {}
        self._lock = threading.RLock()

    def __repr__(self) -> str:
        return f"Registry({self.what!r}, group={self.group!r}, names={self.names()!r})"

    # --- adding and removing ---------------------------------------------------------------------------

    def register(self, name: str, item: T, *, replace: bool = False, origin: str = "registered") -> T:
        """Add ``item`` under ``name``; ValueError for a taken name unless ``replace`` (which keeps its place)."""
        with self._lock:
            if not name:
                raise ValueError(f"a {self.what} needs a name")
            if self._name_of is not None and self._name_of(item) != name:
                raise ValueError(f"a {self.what} named {self._name_of(item)!r} cannot be registered as {name!r}")
            if name in self._entries and not replace:
                raise ValueError(f"a {self.what} named {name!r} is registered already")
            if self._check is not None:
                self._check(name, item)
            self._items[name] = item
            self._entries[name] = Entry(name, origin, loaded=True)
            self._failed.pop(name, None)
            return item

    def register_lazy(self, name: str, target: str, *, replace: bool = False, origin: str = "builtin") -> None:
        """Add ``"module:attr"`` under ``name``, imported by the first :meth:`get`."""
        with self._lock:
            if name in self._entries and not replace:
                raise ValueError(f"a {self.what} named {name!r} is registered already")
            self._items.pop(name, None)
            self._entries[name] = Entry(name, origin, target)

    def unregister(self, name: str) -> None:
        """Forget ``name`` (an installed plug-in of that name is found again by the next lookup)."""
        self.pop(name)

    def pop(self, name: str, default: T | None = None) -> T | None:
        with self._lock:
            self._entries.pop(name, None)
            self._failed.pop(name, None)
            return self._items.pop(name, default)

    def refresh(self) -> None:
        """Read the entry-point group again (after installing a package in a running process)."""
        with self._lock:
            self._eps = None
            self._failed.clear()

    # --- looking up ------------------------------------------------------------------------------------

    def names(self) -> list[str]:
        """Every known name, registered ones first (in registration order), imports nothing."""
        return list(self._entries) + [n for n in self._entry_points() if n not in self._entries]

    def entries(self) -> list[Entry]:
        """Every known name with its origin, imports nothing."""
        eps = self._entry_points()
        return list(self._entries.values()) + [Entry(n, "entry point", ep.value, _distribution(ep))
                                               for n, ep in eps.items() if n not in self._entries]

    def entry(self, name: str) -> Entry:
        """Where ``name`` comes from (UnknownNameError when nowhere)."""
        for e in self.entries():
            if e.name == name:
                return e
        raise self.unknown(name)

    def get(self, name: str) -> T:  # type: ignore[override]  # (no default: an unknown name is an error)
        """The item called ``name``, imported if needed."""
        with self._lock:
            if name in self._items:
                return self._items[name]
            if name in self._failed:
                raise self._failed[name]
            entry = self._entries.get(name)
            if entry is not None and entry.target is not None:
                return self._resolve(name, entry.target, entry.origin, None)
            ep = self._entry_points().get(name)
            if ep is None:
                raise self.unknown(name)
            return self._resolve(name, ep.value, "entry point", ep)

    def unknown(self, name: str) -> UnknownNameError:
        """The error for an unknown name: the known names and the closest ones."""
        known = sorted(self.names())
        hint = did_you_mean(name, known)
        return self._error(f"unknown {self.what} {name!r}; known: {', '.join(known) or '(none)'}{self._hint}{hint}",
                           field=self.field)

    def current(self) -> dict[str, T]:
        """The items registered or imported so far, in order; imports nothing, reads no package metadata."""
        return {n: self._items[n] for n in self._entries if n in self._items}

    def loaded(self) -> dict[str, T]:
        """Every item, imported, in :meth:`names` order; an installed plug-in that fails to load is left out
        with a warning (looking it up by name raises its error)."""
        out: dict[str, T] = {}
        for name in self.names():
            try:
                out[name] = self.get(name)
            except InputError as exc:
                if self._entries.get(name, Entry(name, "entry point")).origin != "entry point":
                    raise
                warnings.warn(f"{self.what} plug-in {name!r} left out: {exc}", RuntimeWarning, stacklevel=2)
        return out

    # Mapping: names without importing, items imported
    def __getitem__(self, name: str) -> T:
        return self.get(name)

    def __iter__(self) -> Iterator[str]:
        return iter(self.names())

    def __len__(self) -> int:
        return len(self.names())

    # a registry is one object, compared by identity (Mapping's == would import every plug-in)
    __hash__ = object.__hash__

    def __eq__(self, other: object) -> bool:
        return self is other

    def __contains__(self, name: object) -> bool:
        return isinstance(name, str) and (name in self._entries or name in self._entry_points())

    def items(self) -> ItemsView[str, T]:
        return self.loaded().items()

    def values(self) -> ValuesView[T]:
        return self.loaded().values()

    # --- internals -------------------------------------------------------------------------------------

    def _entry_points(self) -> dict[str, importlib.metadata.EntryPoint]:
        if self._eps is None:
            found: dict[str, importlib.metadata.EntryPoint] = {}
            if self.group is not None:
                for ep in importlib.metadata.entry_points(group=self.group):
                    if ep.name in found and found[ep.name].value != ep.value:
                        warnings.warn(f"two installed packages give the {self.what} {ep.name!r}: "
                                      f"{_distribution(found[ep.name])} and {_distribution(ep)}; using the first",
                                      RuntimeWarning, stacklevel=3)
                        continue
                    found.setdefault(ep.name, ep)
            self._eps = found
        return self._eps

    def _resolve(self, name: str, target: str, origin: str, ep: importlib.metadata.EntryPoint | None) -> T:
        dist = _distribution(ep) if ep is not None else None
        source = f"{target!r}" + (f" (entry point of {dist})" if dist else "")
        try:
            obj: object = self._load(target) if self._load is not None else \
                ep.load() if ep is not None else import_target(target)
            if name in self._items:          # its import registered it (e.g. a decorated function)
                item = self._items[name]
            else:
                item = self._adapt(name, obj, source)
                self.register(name, item, replace=True, origin=origin)
        except InputError as exc:
            if ep is not None:
                self._failed[name] = exc
            raise
        except Exception as exc:  # noqa: BLE001  (a plug-in's import can fail in any way)
            err = PluginError(f"cannot load {self.what} {name!r} from {source}: {type(exc).__name__}: {exc}",
                              field=self.field)
            if ep is not None:
                self._failed[name] = err
            raise err from None
        self._entries[name] = Entry(name, origin, target, dist, True)
        return item

    def _adapt(self, name: str, obj: object, source: str) -> T:
        base = self._base
        if base is None:
            return cast(T, obj)
        if isinstance(obj, type) and issubclass(obj, base):
            obj = obj()
        if not isinstance(obj, base):
            raise PluginError(f"{source} gives {_describe(obj)}, not a {base.__name__} (an instance or a "
                              f"subclass), and importing it registered no {self.what} named {name!r}",
                              field=self.field)
        return cast(T, obj)


def _describe(obj: Any) -> str:
    if isinstance(obj, type):
        return f"the class {obj.__module__}.{obj.__qualname__}"
    return f"an object of type {type(obj).__name__}"
