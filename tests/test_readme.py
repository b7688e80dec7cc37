"""The README tour runs as written: every ```python block, in order, in one namespace, from the
repository root (where `../shared/data` is; a clone elsewhere reads it where `paths` finds it)."""

import os
import re
import shutil
from pathlib import Path

import pytest

from paths import DATA

ROOT = Path(__file__).resolve().parents[1]


def blocks():
    text = (ROOT / "README.md").read_text()
    return re.findall(r"```python\n(.*?)```", text, flags=re.S)


def test_the_readme_starts_with_its_two_commands():
    text = (ROOT / "README.md").read_text()
    first = re.search(r"```bash\n(.*?)```", text, flags=re.S).group(1).strip().splitlines()
    assert first == ["pip install . && machscan demo", "bash scripts/test.sh"]
    assert "bash scripts/test.sh" in (ROOT / ".ci" / "run").read_text()


def test_the_tour_runs_as_written(monkeypatch):
    pytest.importorskip("matplotlib")
    code = blocks()
    assert len(code) >= 4
    monkeypatch.chdir(ROOT)
    namespace: dict = {"__name__": "readme"}
    for k, block in enumerate(code):
        block = block.replace('Path("../shared/data")', f"Path({str(DATA)!r})")
        exec(compile(block, f"README.md python block {k + 1}", "exec"), namespace)
    assert os.path.isdir(namespace["out"])
    assert namespace["report"].contours, "the tour's inspection matched its contours"
    # The tour leaves its files for a reader to open; the test run does not (each run wrote 33 MB).
    shutil.rmtree(namespace["out"])
