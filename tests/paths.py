"""Where the test data lives: `data/` at the repository root (public files with their sources,
licences and reference values in `data/README.md`)."""

from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / "data"
