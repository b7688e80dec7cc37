"""Copy the docstrings of the compiled `machscan._core` into `python/machscan/_core.pyi`, so that
editors show the same text as `help()` (DESIGN: the .pyi carries the same text). The Rust doc
comments in `crates/python/src/` are the source; run this after changing one:

    python scripts/sync_stub_docs.py          # rewrite the stub
    python scripts/sync_stub_docs.py --check  # exit 1 if the stub is out of step

`tests/test_stub_docs.py` runs the check.
"""

from __future__ import annotations

import argparse
import ast
import inspect
import sys
from pathlib import Path

STUB = Path(__file__).resolve().parent.parent / "python" / "machscan" / "_core.pyi"


def runtime_doc(obj: object) -> str | None:
    doc = inspect.getdoc(obj)
    return doc.strip() if doc else None


def documented(tree: ast.Module, core: object):
    """(stub node, runtime docstring) for every function, class, method and property."""
    for node in tree.body:
        if isinstance(node, (ast.FunctionDef, ast.ClassDef)) and hasattr(core, node.name):
            owner = getattr(core, node.name)
            yield node, runtime_doc(owner)
            if isinstance(node, ast.ClassDef):
                for member in node.body:
                    if isinstance(member, ast.FunctionDef) and not member.name.startswith("__") and member.name in vars(owner):
                        # getattr, not vars(): a static method's own doc is staticmethod's.
                        yield member, runtime_doc(getattr(owner, member.name))


def quoted(doc: str, indent: str) -> list[str]:
    text = doc.replace("\\", "\\\\").replace('"""', '\\"\\"\\"')
    lines = text.split("\n")
    if len(lines) == 1:
        return [f'{indent}"""{text}"""']
    out = [f'{indent}"""{lines[0]}']
    out += [f"{indent}{line}" if line else "" for line in lines[1:]]
    out.append(f'{indent}"""')
    return out


def synced(source: str, core: object) -> str:
    tree = ast.parse(source)
    lines = source.split("\n")
    edits = []  # (first line, last line, new lines), 0-based, inclusive
    for node, doc in documented(tree, core):
        if not doc:
            continue
        body, first = node.body, node.body[0]
        indent = " " * (node.col_offset + 4)
        is_text = isinstance(first, ast.Expr) and isinstance(first.value, ast.Constant) and isinstance(first.value.value, str)
        is_ellipsis = isinstance(first, ast.Expr) and isinstance(first.value, ast.Constant) and first.value.value is Ellipsis
        if is_text:
            if inspect.cleandoc(first.value.value).strip() != doc:
                edits.append((first.lineno - 1, first.end_lineno - 1, quoted(doc, indent)))
        elif is_ellipsis and len(body) == 1:
            # The docstring becomes the body; `def f(...) -> T: ...` opens one.
            before = lines[first.lineno - 1][: first.col_offset]
            head = [before.rstrip()] if before.strip() else []
            edits.append((first.lineno - 1, first.lineno - 1, head + quoted(doc, indent)))
        else:
            edits.append((first.lineno - 1, first.lineno - 2, quoted(doc, indent)))
    for first, last, new in sorted(edits, reverse=True):
        lines[first : last + 1] = new
    return "\n".join(lines)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--check", action="store_true", help="only report whether the stub is in step")
    args = ap.parse_args()
    import machscan._core as core

    source = STUB.read_text()
    new = synced(source, core)
    if args.check:
        if new != source:
            print(f"{STUB} is out of step with machscan._core: run python scripts/sync_stub_docs.py")
            return 1
        return 0
    STUB.write_text(new)
    return 0


if __name__ == "__main__":
    sys.exit(main())
