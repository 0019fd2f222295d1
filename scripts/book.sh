#!/usr/bin/env bash
# The docs build: the mdBook manual (docs/book/) and the API docs.
# - installs mdbook from crates.io into target/tools (git-ignored) unless
#   target/tools/bin/mdbook is already the pinned version;
# - builds the book into target/book (book.toml's build-dir: nothing that git
#   tracks is written);
# - fails on a broken internal link of the built book or of README.md
#   (scripts/check_links.py; external links are not checked);
# - runs `cargo doc --no-deps --workspace` with warnings denied.
# Usage: bash scripts/book.sh (from anywhere). Honours CARGO_TARGET_DIR for
# cargo doc; the book and mdbook stay under the repository's target/.
set -euo pipefail
cd "$(dirname "$0")/.."

MDBOOK_VERSION=0.5.4
tools=target/tools
mdbook="$tools/bin/mdbook"

if [ "$("$mdbook" --version 2>/dev/null)" != "mdbook v$MDBOOK_VERSION" ]; then
    echo "== [${SECONDS} s] installing mdbook $MDBOOK_VERSION into $tools (crates.io)"
    # Without the default features (serve, watch, search): only `mdbook build`.
    cargo install mdbook --locked --version "$MDBOOK_VERSION" --no-default-features \
        --root "$tools"
fi

echo "== [${SECONDS} s] mdbook build docs/book -> target/book"
"$mdbook" build docs/book

echo "== [${SECONDS} s] internal links of the book and of README.md"
python3 scripts/check_links.py --html target/book --markdown README.md

echo "== [${SECONDS} s] cargo doc --no-deps --workspace (warnings denied)"
# Rustdoc's warnings are errors (-D warnings); cargo's own warnings fail too.
# The libraries, then the binaries bench_mpc and eigenmpc-demo. Not the CLI's
# binary `eigenmpc` (a 7-line main over the eigenmpc_cli library): it would
# be documented into the same doc/eigenmpc/ as the core library `eigenmpc`
# (cargo: "output filename collision"); nor fmu-build's, which cargo skips
# beside its library of the same name.
doc_log=$(mktemp)
trap 'rm -f "$doc_log"' EXIT
export RUSTDOCFLAGS="${RUSTDOCFLAGS:-} -D warnings"
cargo doc --no-deps --workspace --lib 2>&1 | tee "$doc_log"
cargo doc --no-deps -p eigenmpc -p eigenmpc-demo --bins 2>&1 | tee -a "$doc_log"
if grep -E '^(warning|error)' "$doc_log"; then
    echo "cargo doc warned (above)" >&2
    exit 1
fi

echo "== [${SECONDS} s] the book is target/book/index.html"
