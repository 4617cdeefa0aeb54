"""The registry of study page kinds: one module per kind, registered by :func:`register_page_kind`.

Built-in kinds: consent, instructions, questionnaire, headphone_check, training, pairwise, mushra, likert,
finish. Adding a kind is one module with a :class:`~study_app.pages.base.PageKind` subclass and its
template (``templates/pages/<name>.html``) and client hooks (``static/pages/<name>.js``); see
``docs/architecture.md``. An installed package adds a kind with an entry point in the group
``evalsuite.page_kinds`` (a ``PageKind`` subclass or instance, its templates in ``template_folder``).
:data:`KINDS` is the :class:`~evalsuite.registry.Registry`.
"""
from __future__ import annotations

import pathlib

from evalsuite.registry import Registry
from study_app.pages.base import BlockKind, Media, Outcome, PageKind

__all__ = ["KINDS", "PageKind", "BlockKind", "Outcome", "Media", "register_page_kind", "unregister_page_kind",
           "get_kind", "get_block_kind", "page_kinds", "TEMPLATE_FOLDER"]

TEMPLATE_FOLDER = pathlib.Path(__file__).resolve().parent.parent / "templates" / "pages"
KINDS: Registry[PageKind] = Registry("page kind", "evalsuite.page_kinds", base=PageKind, name_of=lambda k: k.name,
                                     field="type")


def register_page_kind(kind: PageKind, *, replace: bool = False) -> PageKind:
    return KINDS.register(kind.name, kind, replace=replace)


def unregister_page_kind(name: str) -> None:
    KINDS.unregister(name)


def page_kinds() -> dict[str, PageKind]:
    """Name -> kind: the built-in kinds, those registered in this process, then installed plug-ins."""
    return KINDS.loaded()


def get_kind(name: str) -> PageKind:
    """The kind of a page type; :class:`~evalsuite.errors.UnknownNameError` (a KeyError) for an unknown one
    (definitions are checked at load time)."""
    return KINDS.get(name)


def get_block_kind(name: str) -> BlockKind:
    """The kind of a rating block's pages (TypeError for a kind that is not a block)."""
    kind = KINDS.get(name)
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
