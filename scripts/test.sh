#!/usr/bin/env bash
# The README's test command: installs what the tests need (system libraries included) and runs
# every check: formatting and lints (cargo fmt, clippy, ruff), the Rust unit tests, the stub check
# of the extension, and pytest over the tests and the notebooks.
set -euo pipefail
cd "$(dirname "$0")/.."

# System libraries a test dependency needs, installed only when missing.
need=()
for pkg in libusb-1.0-0 libgl1 libgomp1; do
  dpkg -s "$pkg" >/dev/null 2>&1 || need+=("$pkg")
done
if [ ${#need[@]} -gt 0 ]; then
  echo "== installing system libraries: ${need[*]}"
  SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  $SUDO apt-get update -qq && $SUDO apt-get install -y -qq "${need[@]}" >/dev/null
fi

echo "== cargo fmt --check"
cargo fmt --all --check

echo "== building and installing machscan (release) with its test dependencies"
python -m pip install --quiet --disable-pip-version-check ".[test]"

echo "== ruff"
python -m ruff check python tests benchmarks scripts

echo "== cargo clippy"
cargo clippy --quiet --workspace --all-targets -- -D warnings

echo "== cargo test (the core, without Python)"
cargo test --quiet -p machscan-core

echo "== stub check of machscan._core"
# Run from outside the source tree so the installed package is the one checked.
(cd /tmp && python -m mypy.stubtest machscan._core)

echo "== pytest (tests and notebooks)"
python -m pytest -q -p no:cacheprovider --nbmake tests notebooks "$@"
