"""Where the shared data lives: `../shared/data` beside the repository. A clone made elsewhere
(CI clones into a temporary folder) finds it through `MACHSCAN_SHARED_DATA`, or beside the
checkout it was cloned from (its `origin`, when that is a local path)."""

import os
import subprocess
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _find() -> Path:
    candidates = []
    if os.environ.get("MACHSCAN_SHARED_DATA"):
        candidates.append(Path(os.environ["MACHSCAN_SHARED_DATA"]))
    candidates.append(ROOT.parent / "shared" / "data")
    try:
        origin = subprocess.run(
            ["git", "-C", str(ROOT), "config", "--get", "remote.origin.url"], capture_output=True, text=True, check=False
        ).stdout.strip()
    except OSError:
        origin = ""
    if origin and Path(origin).is_dir():
        candidates.append(Path(origin).resolve().parent / "shared" / "data")
    return next((c for c in candidates if c.is_dir()), candidates[0])


DATA = _find()
