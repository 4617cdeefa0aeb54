"""Error types of the study app."""
from __future__ import annotations

from evalsuite.errors import InputError


class StudyDefinitionError(InputError):
    """A study definition or stimulus manifest that cannot be used.

    The message names the file, the field path inside it (``pages[3].levels``) and what
    was expected, so the study author can fix it without reading code.
    """


class StudyStateError(InputError):
    """The database does not fit the study (plans missing or built from another definition)."""
