"""Where the shared data lives: `../shared/data` beside the repository."""

from pathlib import Path

DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data"
