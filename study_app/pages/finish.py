"""``finish``: the last page (exactly one); reaching it completes the session and shows the code."""
from __future__ import annotations

from study_app.pages.base import PageKind


class FinishKind(PageKind):
    name = "finish"
    position = "last"


KIND = FinishKind()
