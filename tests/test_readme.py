"""README.md's Python example runs as written, so the user's first page cannot go stale."""
from __future__ import annotations

import pathlib
import re

ROOT = pathlib.Path(__file__).resolve().parents[1]


def test_the_python_api_example_runs(tmp_path, monkeypatch):
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    section = text.split("## Python API", 1)[1]
    code = re.search(r"```python\n(.*?)```", section, re.S)
    assert code is not None, "README.md has no Python example under '## Python API'"
    monkeypatch.chdir(tmp_path)                      # the example writes its two folders where it runs
    namespace: dict = {}
    exec(compile(code.group(1), "README.md", "exec"), namespace)
    assert namespace["m"].fps == 24.0
    assert {r["metric"] for r in namespace["result"].summary} >= {"jerk"}
