#!/usr/bin/env bash
# Installs the Debian packages the build needs when they are missing (as
# root; otherwise says which to install). Sourced by tests/run.sh and
# demo/run.sh, so that both README commands work on a fresh Debian machine
# with only Rust and Python.

apt_install() {
    if [ "$(id -u)" != 0 ]; then
        echo "missing Debian packages: $*; install them as root (apt-get install $*)" >&2
        exit 1
    fi
    if [ -z "${APT_UPDATED:-}" ]; then
        apt-get update -qq
        APT_UPDATED=1
    fi
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "$@"
}

# fmi-sys runs bindgen on the FMI headers at build time: it needs libclang.
dpkg -s libclang-dev >/dev/null 2>&1 || apt_install libclang-dev
# The symbol test lists the FMU's exports with nm; fmu-build strips the FMU
# binaries with objcopy; cc-built crates need gcc.
{ command -v nm && command -v objcopy; } >/dev/null 2>&1 || apt_install binutils
command -v gcc >/dev/null 2>&1 || apt_install gcc
