#!/usr/bin/env bash
# The README's test command: installs what the tests need (system libraries included) and runs
# every check: formatting and lints (cargo fmt, clippy, ruff), the Rust unit tests of the core,
# the abi3 wheel built once and installed into a fresh venv with the test extra, the stub check
# and the type check of the package, and pytest over the tests and the notebooks against that
# wheel: what `pip install machscan-*.whl` gives a user is what is tested.
set -euo pipefail
cd "$(dirname "$0")/.."

# System libraries a test dependency needs, installed only when missing.
need=()
for pkg in libusb-1.0-0 libgl1 libx11-6 libgomp1; do
  dpkg -s "$pkg" >/dev/null 2>&1 || need+=("$pkg")
done
if [ ${#need[@]} -gt 0 ]; then
  echo "== installing system libraries: ${need[*]}"
  SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  $SUDO apt-get update -qq && $SUDO apt-get install -y -qq "${need[@]}" >/dev/null
fi

echo "== cargo fmt --check"
cargo fmt --all --check

echo "== the wheel (release, abi3: CPython >= 3.10), built once"
rm -rf target/ci-wheel
python -m pip wheel --quiet --disable-pip-version-check --no-deps --wheel-dir target/ci-wheel .
wheel=$(ls target/ci-wheel/machscan-*-abi3-*.whl)

echo "== a fresh venv with the wheel and the test dependencies"
python -m venv --clear target/ci-venv
venv_python="$PWD/target/ci-venv/bin/python"
"$venv_python" -m pip install --quiet --disable-pip-version-check "${wheel}[test]"

echo "== ruff"
"$venv_python" -m ruff check python tests benchmarks scripts

echo "== cargo clippy"
cargo clippy --quiet --workspace --all-targets -- -D warnings

echo "== cargo test (the core, without Python)"
cargo test --quiet -p machscan-core

echo "== stub check of machscan._core and the type check of the package"
# From outside the source tree, so the installed wheel is the one checked.
(cd /tmp && "$venv_python" -m mypy.stubtest machscan._core)
"$venv_python" -m mypy python/machscan

echo "== pytest (tests and notebooks), against the wheel"
"$venv_python" -m pytest -q -p no:cacheprovider --nbmake tests notebooks "$@"
