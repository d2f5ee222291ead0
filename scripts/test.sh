#!/usr/bin/env bash
# Installs everything the tests need on a fresh machine and runs them all:
# rustfmt, Rust unit tests (mmusv-core alone, no Python), benches compile check, the Python package with its test
# extras, clippy, the core's API docs, ruff, the type-stub check, mypy and pytest (warnings are errors). Exits
# non-zero on any failure (pytest's "no tests" included).
set -euo pipefail
cd "$(dirname "$0")/.."

echo "== system libraries (Open3D, the peer used in tests and benches, needs libusb and libgomp)"
if command -v apt-get >/dev/null 2>&1 && [ "$(id -u)" = "0" ]; then
    if ! ldconfig -p | grep -q libusb-1.0.so.0 || ! ldconfig -p | grep -q libgomp.so.1; then
        apt-get update -qq
        DEBIAN_FRONTEND=noninteractive apt-get install -y -qq libusb-1.0-0 libgomp1 >/dev/null
    fi
fi

echo "== headless Chromium and its driver (the editor's browser tests drive Debian's chromium through Selenium)"
if command -v apt-get >/dev/null 2>&1 && [ "$(id -u)" = "0" ]; then
    if ! command -v chromium >/dev/null 2>&1 || ! command -v chromedriver >/dev/null 2>&1; then
        apt-get update -qq
        DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium chromium-driver >/dev/null
    fi
fi

echo "== toolchains"
command -v cargo >/dev/null || { echo "cargo not found: install a Rust toolchain (rustup) first" >&2; exit 1; }
cargo --version
python3 --version
if ! cargo fmt --version >/dev/null 2>&1 || ! cargo clippy --version >/dev/null 2>&1; then
    command -v rustup >/dev/null || { echo "rustfmt and clippy not found: install them (rustup component add)" >&2; exit 1; }
    rustup component add rustfmt clippy
fi

echo "== cargo fmt --check (Rust formatting)"
cargo fmt --all --check

echo "== cargo test (mmusv-core alone, no Python)"
cargo test -p mmusv-core --release --quiet

echo "== cargo bench --no-run (benches keep compiling)"
cargo bench --no-run --quiet

echo "== pip install the package with test and learn extras (builds the extension in release; ray for the batch"
echo "   tests; torch for the learned detector's tests in tests/learn)"
python3 -m pip install --quiet --disable-pip-version-check -e ".[test,learn]"

echo "== Ultralytics, the YOLO peer of tests/export/test_peer_readers.py, without its dependencies: it asks for OpenCV's"
echo "   GUI build (opencv-python, needing libGL), which would overwrite the headless OpenCV of the test extra; what it"
echo "   imports besides is installed above"
python3 -m pip install --quiet --disable-pip-version-check --no-deps "ultralytics>=8.4,<9" "ultralytics-thop>=2"

echo "== TrackEval, the MOTChallenge peer of tests/export/test_mot.py, without its dependencies for the same reason (it"
echo "   asks for opencv-python); numpy, scipy and tabulate, what its MOTChallenge loader and metrics import, are above"
python3 -m pip install --quiet --disable-pip-version-check --no-deps "trackeval>=1.3,<2"

echo "== cargo clippy, warnings are errors (release: reuses the build scripts and proc macros built above)"
cargo clippy -p mmusv-core -p mmusv-benches -p mmusv-py --release --all-targets --quiet -- -D warnings

echo "== cargo doc (mmusv-core's API docs: no broken or private intra-doc links, warnings are errors)"
RUSTDOCFLAGS="-D warnings" cargo doc -p mmusv-core --no-deps --quiet

echo "== ruff: lint and format check of the Python sources"
python3 -m ruff check python tests benches
python3 -m ruff format --check python tests benches

echo "== type stubs match the compiled module (mypy stubtest) and the package type-checks"
python3 -m mypy.stubtest mmusv._core
python3 -m mypy

echo "== pytest (the 25 slowest tests listed at the end)"
set +e
python3 -m pytest -q -p no:dash -p no:cacheprovider --durations=25 tests
rc=$?
set -e
if [ "$rc" = "5" ]; then
    echo "pytest collected no tests: that is a failure" >&2
    exit 1
fi
exit "$rc"
