#!/usr/bin/env bash
# The project's test command (README "Two commands", docs/book/src/tests.md): formatting, lints,
# Rust tests, FMU packaging, Python tests of the FMUs (fmpy, libcosim).
# Installs what a fresh Debian machine lacks.
set -euo pipefail
cd "$(dirname "$0")/.."

# apt_install and the build's Debian packages (libclang-dev, binutils, gcc),
# then the other platforms' (win64: Debian's Rust with its sources, mingw,
# wine).
source scripts/ensure-build-deps.sh
source scripts/ensure-cross-deps.sh

# A build, the demo and the tests write nothing git tracks (issue 36): the
# tree's state (changes and untracked files) now, compared after each step
# that builds or runs something (so a developer's uncommitted work is fine,
# a file the run rewrites is not).
tree_state() { { git status --porcelain=v1 -uall; git diff; } | sha256sum; }
tree_at_start=$(tree_state)
assert_tree_unchanged() {
    if [ "$(tree_state)" != "$tree_at_start" ]; then
        echo "$1 changed files git tracks, or left files git does not ignore:" >&2
        git status --short >&2
        git diff --stat >&2
        exit 1
    fi
}

echo "== [${SECONDS} s] cargo fmt --check"
cargo fmt --all -- --check
echo "== [${SECONDS} s] cargo clippy"
cargo clippy --workspace --all-targets -- -D warnings
echo "== [${SECONDS} s] the FMUs link only what they run (cargo tree; docs/book/src/fmus.md \"What each FMU links\")"
fmu_links() { cargo tree -p "$1" -e normal,build --prefix none | awk '{print $1}' | sort -u; }
# The one FMU binary (every shipped and exported FMU) and the C library.
for p in eigenmpc-robot-fmu eigenmpc-fmu; do
    forbidden='clap|plotters|indicatif|yaml_serde|toml|zip|anyhow|cbindgen|bindgen|libloading|fmi|eigenmpc-cli'
    if bad=$(fmu_links "$p" | grep -xE "$forbidden"); then
        echo "$p links what it does not run: $bad" >&2
        exit 1
    fi
done
echo "== [${SECONDS} s] no kernel chosen by the CPU at run time in the numerics (nalgebra without std: no matrixmultiply)"
# nalgebra's std feature brings matrixmultiply (FMA / AVX / SSE2 / NEON
# kernels picked at run time) and the platform's libm into every dynamic
# matrix product and SVD: the same source would give other bits elsewhere.
if cargo tree --workspace -e normal,build,dev --prefix none | grep -q '^matrixmultiply '; then
    echo "matrixmultiply is back in the build: something enabled nalgebra's std feature" >&2
    cargo tree --workspace -e features -i nalgebra >&2
    exit 1
fi
echo "== [${SECONDS} s] cargo test"
cargo test --workspace
# fmu-build, the demo and the CLI in one cargo invocation: one feature set
# (the demo's, which depends on the other two), so each shared crate is
# compiled once and demo/run.sh's `cargo run --release -p eigenmpc-demo`
# finds everything built. The C hosts export a robot with the CLI, and the
# Python tests compare with `eigenmpc simulate`.
echo "== [${SECONDS} s] release build of fmu-build, the demo and the CLI"
cargo build --release -p fmu-build -p eigenmpc-demo -p eigenmpc-cli
release_dir="${CARGO_TARGET_DIR:-target}/release"
echo "== [${SECONDS} s] fmu-build (the FMU binary for linux64, win64 and aarch64-linux, target/fmu/*.fmu and fmi3/*.fmu, the C library, include/eigenmpc.h)"
"$release_dir/fmu-build"
assert_tree_unchanged "fmu-build"

echo "== [${SECONDS} s] the same bits on every machine: the shipped descriptions natively, on baseline and AVX2 x86-64 and on aarch64 (tests/same_bits.sh)"
bash tests/same_bits.sh

echo "== [${SECONDS} s] demo (the main job, on the FMUs just built): controller FMU drives plant FMU"
bash demo/run.sh --no-build --out-dir target/demo-ci
for f in demo.csv demo.png demo.svg; do
    test -s "target/demo-ci/$f" || { echo "demo did not write target/demo-ci/$f" >&2; exit 1; }
done
# The book's two other demo runs (docs/book/src/demo.md): a robot parameter file, 3 links. Each
# must bring the energy into the 5 % band.
demo_reaches_band() {
    local out
    out=$(bash demo/run.sh --no-build "$@")
    echo "$out"
    grep -q "5 % for good: [0-9]" <<<"$out" || { echo "demo $*: 5 % band not reached" >&2; exit 1; }
}
demo_reaches_band --model robots/lab-double-pendulum-A0.yml --energy 2 --tau-max 0.5 \
    --duration 30 --out-dir target/demo-ci-A0
demo_reaches_band --links 3 --out-dir target/demo-ci-3
# A robot file of 4 links: no shipped pair, the demo exports one (eigenmpc export).
demo_reaches_band --model robots/examples/four-link-rigid.yml --energy 1 --duration 15 \
    --out-dir target/demo-ci-4link
if bash demo/run.sh --no-build --links 4 --out-dir target/demo-ci-4 2>/dev/null; then
    echo "demo --links 4 should be refused" >&2
    exit 1
fi

assert_tree_unchanged "the demo"

echo "== [${SECONDS} s] C host tests (include/eigenmpc.h; linux64 with gcc, win64 with mingw under wine, aarch64-linux under qemu-user)"
bash tests/c/hosts.sh

echo "== [${SECONDS} s] Python test environment (.venv)"
if [ ! -x .venv/bin/python ]; then
    # Debian's python3 lacks ensurepip until python3-venv is installed.
    if ! python3 -c "import ensurepip, venv" >/dev/null 2>&1; then
        apt_install python3-venv
    fi
    rm -rf .venv
    python3 -m venv .venv
fi
stamp=.venv/.requirements.sha
want=$(sha256sum tests/python/requirements.txt | cut -d' ' -f1)
if [ "$(cat "$stamp" 2>/dev/null)" != "$want" ]; then
    .venv/bin/pip install -q --disable-pip-version-check -r tests/python/requirements.txt
    echo "$want" >"$stamp"
fi
# libcosim's Python binding ships as a binary wheel; its test is skipped (and
# says so) where no wheel installs. Its own stamp is written only after a
# successful install, so a failed attempt (e.g. offline) is retried next run.
libcosim_stamp=.venv/.libcosimpy.ok
if [ ! -e "$libcosim_stamp" ]; then
    if .venv/bin/pip install -q --disable-pip-version-check libcosimpy; then
        touch "$libcosim_stamp"
    else
        echo "warning: libcosimpy did not install; the libcosim test will be skipped" >&2
    fi
fi
# ecos (ecospy) runs the shipped SSP; its wheel needs Debian's oneTBB runtime.
dpkg -s libtbb12 >/dev/null 2>&1 || apt_install libtbb12
ecos_stamp=.venv/.ecospy.ok
if [ ! -e "$ecos_stamp" ]; then
    if .venv/bin/pip install -q --disable-pip-version-check ecospy; then
        touch "$ecos_stamp"
    else
        echo "warning: ecospy did not install; the ecos SSP test will be skipped" >&2
    fi
fi
# The Dask sweep runner (python/, with dask[distributed]), installed editable.
sweep_stamp=.venv/.eigenmpc-sweep.sha
want=$(sha256sum python/pyproject.toml | cut -d' ' -f1)
if [ "$(cat "$sweep_stamp" 2>/dev/null)" != "$want" ]; then
    .venv/bin/pip install -q --disable-pip-version-check -e python
    echo "$want" >"$sweep_stamp"
fi
echo "== [${SECONDS} s] pytest"
.venv/bin/python -m pytest tests/python -rs
echo "== [${SECONDS} s] pytest python/ (the Dask sweep runner against the native sweep)"
.venv/bin/python -m pytest python/tests -rs

echo "== [${SECONDS} s] the book (docs/book, mdbook; no broken internal link) and the API docs (cargo doc, warnings denied)"
bash scripts/book.sh
echo "== [${SECONDS} s] the README's commands, as written (tests/readme_commands.sh)"
bash tests/readme_commands.sh
echo "== [${SECONDS} s] the library crates package (scripts/package.sh)"
bash scripts/package.sh
assert_tree_unchanged "the tests"
echo "== [${SECONDS} s] done"
