#!/usr/bin/env bash
# Installs what the FMUs' other platforms need when it is missing (as root;
# otherwise says which packages to install). Sourced by tests/run.sh after
# ensure-build-deps.sh (which defines apt_install).
# - win64: Debian's Rust 1.96 with the standard library's sources
#   (rustc-web, cargo-web, rust-web-src: rustup cannot add targets here),
#   mingw-w64 as linker and for the C test hosts, and wine to run them.

cross_packages=()
for p in rustc-web cargo-web rust-web-src gcc-mingw-w64-x86-64 wine64 wine; do
    dpkg -s "$p" >/dev/null 2>&1 || cross_packages+=("$p")
done
if [ ${#cross_packages[@]} -gt 0 ]; then
    apt_install "${cross_packages[@]}"
fi
unset cross_packages
