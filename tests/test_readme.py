"""The README tour runs as written: every ```python block, in order, in one namespace, from the
repository root (where `data/` is), as a script runs (``__name__ == "__main__"``); and its Dask
block pasted into a plant script of its own runs under ``python``, process-based cluster and all."""

import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from machscan import synth

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
    namespace: dict = {"__name__": "__main__"}
    for k, block in enumerate(code):
        exec(compile(block, f"README.md python block {k + 1}", "exec"), namespace)
    assert os.path.isdir(namespace["out"])
    assert namespace["report"].contours, "the tour's inspection matched its contours"
    # The tour leaves its files for a reader to open; the test run does not (each run wrote 33 MB).
    shutil.rmtree(namespace["out"])


def test_the_dask_block_runs_pasted_into_a_script(tmp_path):
    # Issue #32 §6: the block as a plant pastes it, below the few lines that make `out` and the scan it opens,
    # run by `python script.py`: worker processes import the script again, which the __main__ guard allows.
    pytest.importorskip("distributed")
    dask_block = next(b for b in blocks() if "LocalCluster" in b)
    # What the tour made before the block: `out`, and the 50 frames saved there.
    scan, _ = synth.groove_scan(seed=0)
    scan.select(slice(0, 50)).save(tmp_path / "scan.npz")
    setup = f"from pathlib import Path\n\nimport machscan\n\nout = Path({str(tmp_path)!r})\n"
    script = tmp_path / "plant_script.py"
    script.write_text(setup + dask_block)
    done = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, timeout=600, cwd=tmp_path)
    assert done.returncode == 0, done.stderr[-3000:]
    assert "(True, 50, None)" in done.stdout and "(False, None," in done.stdout, done.stdout
