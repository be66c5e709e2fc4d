"""The library example of ``docs/usage.md`` runs as printed (so it cannot drift from the
code)."""

import contextlib
import io
import re
from pathlib import Path

USAGE = Path(__file__).resolve().parents[1] / "docs" / "usage.md"


def test_usage_library_example_runs_and_the_set_holds_the_truth():
    text = USAGE.read_text(encoding="utf-8")
    section = text.split("## Using it as a library", 1)[1].split("\n## ", 1)[0]
    blocks = re.findall(r"```python\n(.*?)```", section, flags=re.S)
    assert len(blocks) == 1
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        exec(compile(blocks[0], "docs/usage.md", "exec"), {"__name__": "readme_example"})
    lines = out.getvalue().splitlines()
    assert [line.split(":")[0] for line in lines] == ["infoset", "ukf"]
    assert "truth inside True" in lines[0]
