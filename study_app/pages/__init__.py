"""The registry of study page kinds: one module per kind, registered by :func:`register_page_kind`.

Built-in kinds: consent, instructions, questionnaire, headphone_check, training, pairwise, mushra, likert,
finish. Adding a kind is one module with a :class:`~study_app.pages.base.PageKind` subclass and its
template (``templates/pages/<name>.html``) and client hooks (``static/pages/<name>.js``); see
``docs/architecture.md``.
"""
from __future__ import annotations

import pathlib

from study_app.pages.base import BlockKind, Media, Outcome, PageKind

__all__ = ["PageKind", "BlockKind", "Outcome", "Media", "register_page_kind", "unregister_page_kind",
           "get_kind", "get_block_kind", "page_kinds", "TEMPLATE_FOLDER"]

TEMPLATE_FOLDER = pathlib.Path(__file__).resolve().parent.parent / "templates" / "pages"
_KINDS: dict[str, PageKind] = {}


def register_page_kind(kind: PageKind, *, replace: bool = False) -> PageKind:
    if not kind.name:
        raise ValueError("a page kind needs a name")
    if kind.name in _KINDS and not replace:
        raise ValueError(f"a page kind named {kind.name!r} is registered already")
    _KINDS[kind.name] = kind
    return kind


def unregister_page_kind(name: str) -> None:
    _KINDS.pop(name, None)


def page_kinds() -> dict[str, PageKind]:
    return dict(_KINDS)


def get_kind(name: str) -> PageKind:
    """The kind of a page type; KeyError for an unknown one (definitions are checked at load time)."""
    return _KINDS[name]


def get_block_kind(name: str) -> BlockKind:
    """The kind of a rating block's pages (TypeError for a kind that is not a block)."""
    kind = _KINDS[name]
    if not isinstance(kind, BlockKind):
        raise TypeError(f"page kind {name!r} is not a rating block")
    return kind


def _register_builtins() -> None:
    from study_app.pages import (
        consent,
        finish,
        headphone_check,
        instructions,
        likert,
        mushra,
        pairwise,
        questionnaire,
        training,
    )

    for module in (consent, instructions, questionnaire, headphone_check, training, pairwise, mushra,
                   likert, finish):
        register_page_kind(module.KIND, replace=True)


_register_builtins()
