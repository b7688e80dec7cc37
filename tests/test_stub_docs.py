"""The stub carries the same docstrings as the compiled module (DESIGN: editors show what help()
shows); `python scripts/sync_stub_docs.py` brings it back in step."""

import importlib.util
from pathlib import Path

import machscan._core as core

SCRIPT = Path(__file__).resolve().parent.parent / "scripts" / "sync_stub_docs.py"


def load_sync():
    spec = importlib.util.spec_from_file_location("sync_stub_docs", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_stub_docstrings_match_the_compiled_module():
    sync = load_sync()
    source = sync.STUB.read_text()
    assert sync.synced(source, core) == source, "run: python scripts/sync_stub_docs.py"
    # Static methods carry their own text, not staticmethod's.
    assert core.KinematicChain.ac_head.__doc__.strip() in source
    assert "Convert a function to be a static method" not in source


def test_sync_rewrites_a_stale_docstring_and_fills_a_missing_one():
    sync = load_sync()
    stale = 'def octree_simplify(points, d_min) -> None:\n    """old text"""\n\ndef crop_box(points) -> None: ...\n'
    new = sync.synced(stale, core)
    assert "old text" not in new
    assert core.octree_simplify.__doc__.splitlines()[0] in new
    assert core.crop_box.__doc__.splitlines()[0] in new
    compile(new, "stub", "exec")
