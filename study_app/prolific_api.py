"""An optional client of Prolific's researcher API for the review of a study's submissions: approve,
reject, bonus and request a return, behind an API token (``EVALSUITE_PROLIFIC_TOKEN`` or ``--token``).

Endpoints (Prolific API v1, ``Authorization: Token <token>``):

* approve / reject: ``POST /submissions/<id>/transition/`` with ``{"action": "APPROVE"}`` or
  ``{"action": "REJECT", "message": ..., "rejection_category": ...}``;
* request a return: ``POST /submissions/<id>/request-return/`` with ``{"request_return_reasons": [...]}``;
* bonus: ``POST /submissions/bonus-payments/`` with ``{"study_id": ..., "csv_bonuses": "<pid>,<amount>\\n..."}``
  then ``POST /bulk-bonus-payments/<id>/pay/``.

A submission id is the ``SESSION_ID`` Prolific put in the study link (the review export's ``submission_id``).
Nothing here runs unless the researcher calls it; the study server never talks to Prolific by itself.
"""
from __future__ import annotations

import json
import re
import urllib.error
import urllib.request
from collections.abc import Iterable

from evalsuite.errors import InputError

__all__ = ["ProlificClient", "ProlificError", "DEFAULT_BASE_URL", "REJECTION_CATEGORIES"]

DEFAULT_BASE_URL = "https://api.prolific.com/api/v1"
REJECTION_CATEGORIES = ("TOO_QUICKLY", "TOO_SLOWLY", "FAILED_INSTRUCTIONS", "INCOMP_LONGITUDINAL", "FAILED_CHECK",
                        "LOW_EFFORT", "MALINGERING", "NO_CODE", "BAD_CODE", "NO_DATA", "UNSUPP_DEVICE", "OTHER")
_ID_RE = re.compile(r"^[A-Za-z0-9_-]{1,64}$")


class ProlificError(InputError):
    """Prolific refused or could not be reached; the message says which call and why."""


class ProlificClient:
    """The calls of the review flow; each returns Prolific's JSON answer."""

    def __init__(self, token: str, base_url: str = DEFAULT_BASE_URL, timeout: float = 30.0):
        if not token or not token.strip():
            raise ProlificError("no Prolific API token; set EVALSUITE_PROLIFIC_TOKEN or pass --token")
        self.token, self.base_url, self.timeout = token.strip(), base_url.rstrip("/"), timeout

    def _post(self, path: str, body: dict) -> dict:
        req = urllib.request.Request(self.base_url + path, data=json.dumps(body).encode(), method="POST",
                                     headers={"Authorization": f"Token {self.token}",
                                              "Content-Type": "application/json", "Accept": "application/json"})
        try:
            with urllib.request.urlopen(req, timeout=self.timeout) as resp:
                text = resp.read().decode("utf-8", "replace")
        except urllib.error.HTTPError as exc:
            detail = exc.read().decode("utf-8", "replace")[:300]
            raise ProlificError(f"Prolific answered {exc.code} to POST {path}: {detail}") from None
        except (urllib.error.URLError, OSError) as exc:
            raise ProlificError(f"could not reach Prolific for POST {path}: {exc}") from None
        try:
            return json.loads(text) if text.strip() else {}
        except json.JSONDecodeError:
            raise ProlificError(f"Prolific's answer to POST {path} is not JSON: {text[:200]!r}") from None

    @staticmethod
    def _id(value: str, what: str) -> str:
        if not isinstance(value, str) or not _ID_RE.match(value):
            raise ProlificError(f"{what}: expected a Prolific id (letters and digits), got {value!r}")
        return value

    def approve(self, submission_id: str) -> dict:
        return self._post(f"/submissions/{self._id(submission_id, 'submission')}/transition/",
                          {"action": "APPROVE"})

    def reject(self, submission_id: str, message: str, category: str = "FAILED_CHECK") -> dict:
        """Reject a submission; Prolific wants a message of at least 100 characters for the participant."""
        if category not in REJECTION_CATEGORIES:
            raise ProlificError(f"rejection category: expected one of {', '.join(REJECTION_CATEGORIES)}, got "
                                f"{category!r}")
        if len(message.strip()) < 100:
            raise ProlificError(f"rejection message: Prolific needs at least 100 characters, got {len(message.strip())}")
        return self._post(f"/submissions/{self._id(submission_id, 'submission')}/transition/",
                          {"action": "REJECT", "message": message.strip(), "rejection_category": category})

    def request_return(self, submission_id: str, reasons: Iterable[str]) -> dict:
        reasons = [r for r in reasons if r]
        if not reasons:
            raise ProlificError("request return: expected at least one reason")
        return self._post(f"/submissions/{self._id(submission_id, 'submission')}/request-return/",
                          {"request_return_reasons": reasons})

    def bonus(self, study_id: str, bonuses: dict[str, float]) -> dict:
        """Set up and pay bonuses (participant id -> amount in the study's currency, e.g. 0.50)."""
        if not bonuses:
            raise ProlificError("bonus: expected at least one participant and amount")
        lines = []
        for pid, amount in bonuses.items():
            if not isinstance(amount, (int, float)) or isinstance(amount, bool) or not 0 < amount <= 100:
                raise ProlificError(f"bonus for {pid}: expected an amount above 0 and at most 100, got {amount!r}")
            lines.append(f"{self._id(pid, 'participant')},{amount:.2f}")
        made = self._post("/submissions/bonus-payments/", {"study_id": self._id(study_id, "study"),
                                                            "csv_bonuses": "\n".join(lines) + "\n"})
        bulk = made.get("id")
        if not isinstance(bulk, str):
            raise ProlificError(f"Prolific's bonus answer has no id: {str(made)[:200]}")
        return self._post(f"/bulk-bonus-payments/{self._id(bulk, 'bonus payment')}/pay/", {})
