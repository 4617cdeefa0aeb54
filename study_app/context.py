"""Typed access to the study and the store of the running app (set up once by the app factory)."""
from __future__ import annotations

from flask import Flask, current_app

from study_app.model import Study
from study_app.storage import Store

__all__ = ["install", "get_study", "get_store", "study_of", "store_of"]

_STUDY, _STORE = "evalsuite_study", "evalsuite_store"


def install(app: Flask, study: Study, store: Store) -> None:
    app.extensions[_STUDY] = study
    app.extensions[_STORE] = store


def study_of(app: Flask) -> Study:
    study = app.extensions[_STUDY]
    assert isinstance(study, Study)
    return study


def store_of(app: Flask) -> Store:
    store = app.extensions[_STORE]
    assert isinstance(store, Store)
    return store


def get_study() -> Study:
    """The study of the app handling the current request."""
    return study_of(current_app)


def get_store() -> Store:
    """The store of the app handling the current request."""
    return store_of(current_app)
