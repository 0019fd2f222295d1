#!/usr/bin/env bash
# Installs what the FMUs' other platforms need when it is missing (as root;
# otherwise says which packages to install). Sourced by tests/run.sh after
# ensure-build-deps.sh (which defines apt_install). The platforms are the
# rows of fmu-build/src/platform.rs.
# - every cross build: Debian's Rust 1.96 with the standard library's
#   sources (rustc-web, cargo-web, rust-web-src: rustup cannot add targets
#   here);
# - win64: mingw-w64 as linker and for the C test hosts, wine to run them;
# - aarch64-linux: the aarch64 GNU toolchain as linker and for the C test
#   hosts (with its C library under /usr/aarch64-linux-gnu), qemu-user to
#   run them.

cross_packages=()
for p in rustc-web cargo-web rust-web-src gcc-mingw-w64-x86-64 wine64 wine \
    gcc-aarch64-linux-gnu qemu-user; do
    dpkg -s "$p" >/dev/null 2>&1 || cross_packages+=("$p")
done
if [ ${#cross_packages[@]} -gt 0 ]; then
    apt_install "${cross_packages[@]}"
fi
unset cross_packages
