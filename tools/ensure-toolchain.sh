#!/usr/bin/env bash
# Makes sure the GNU RISC-V toolchain (Debian: gcc-riscv64-unknown-elf, which brings
# binutils-riscv64-unknown-elf) is installed; installs it with apt-get when missing.
set -euo pipefail
if command -v riscv64-unknown-elf-as >/dev/null && command -v riscv64-unknown-elf-ld >/dev/null \
        && command -v riscv64-unknown-elf-objcopy >/dev/null; then
    exit 0
fi
packages="binutils-riscv64-unknown-elf gcc-riscv64-unknown-elf"
echo "[setup] the RISC-V toolchain is missing: installing Debian packages: $packages"
echo "[setup] (this needs root: apt-get update && apt-get install)"
sudo=""
if [ "$(id -u)" != 0 ]; then
    if command -v sudo >/dev/null; then sudo="sudo"; else
        echo "error: not root and no sudo; install as root: apt-get install $packages" >&2
        exit 1
    fi
fi
$sudo apt-get update -qq
DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq $packages >/dev/null
command -v riscv64-unknown-elf-as >/dev/null || { echo "error: toolchain install failed" >&2; exit 1; }
