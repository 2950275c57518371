#!/usr/bin/env bash
# Makes sure the outside tools the project needs are installed; installs what is missing
# with apt-get (Debian):
#   - the GNU RISC-V toolchain (gcc-riscv64-unknown-elf brings binutils-riscv64-unknown-elf),
#     to assemble and link the firmware;
#   - picolibc-riscv64-unknown-elf, the C library the C test firmware (tests/firmware/) links
#     against (gcc's --specs=picolibc.specs comes from it);
#   - dosfstools and mtools, with which the tests check SD card images independently;
#   - gdb-multiarch, which the tests drive against the board model's GDB stub (make debug);
#   - gcc-aarch64-linux-gnu and qemu-user, with which the tests build the fast engine for AArch64
#     and check its host floating-point probe there (tests/slow/test_host_fp.py);
#   - chromium and chromium-driver, the browser the live view's test drives through Selenium
#     (tests/end_to_end/test_view_browser.py). A large install that the rest does not need: if apt-get cannot
#     install them this says so and goes on, and that test is skipped saying why.
set -euo pipefail
missing=""
for tool in riscv64-unknown-elf-as riscv64-unknown-elf-ld riscv64-unknown-elf-objcopy; do
    command -v "$tool" >/dev/null || missing="binutils-riscv64-unknown-elf gcc-riscv64-unknown-elf"
done
[ -f /usr/lib/picolibc/riscv64-unknown-elf/picolibc.specs ] || missing="$missing picolibc-riscv64-unknown-elf"
command -v fsck.fat >/dev/null || [ -x /usr/sbin/fsck.fat ] || [ -x /sbin/fsck.fat ] || missing="$missing dosfstools"
command -v mdir >/dev/null || missing="$missing mtools"
command -v gdb-multiarch >/dev/null || missing="$missing gdb-multiarch"
command -v aarch64-linux-gnu-gcc >/dev/null || missing="$missing gcc-aarch64-linux-gnu"
command -v qemu-aarch64 >/dev/null || missing="$missing qemu-user"
browser=""
command -v chromium >/dev/null || browser="chromium"
command -v chromedriver >/dev/null || browser="$browser chromium-driver"
[ -z "$missing" ] && [ -z "$browser" ] && exit 0
echo "[setup] missing tools: installing Debian packages: $missing $browser"
echo "[setup] (this needs root: apt-get update && apt-get install)"
sudo=""
if [ "$(id -u)" != 0 ]; then
    if command -v sudo >/dev/null; then sudo="sudo"; else
        echo "error: not root and no sudo; install as root: apt-get install $missing $browser" >&2
        exit 1
    fi
fi
$sudo apt-get update -qq
if [ -n "$missing" ]; then
    DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq $missing >/dev/null
fi
if [ -n "$browser" ] && ! DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq $browser >/dev/null; then
    echo "warning: apt-get could not install $browser: the live view's browser test will be skipped" >&2
fi
command -v riscv64-unknown-elf-as >/dev/null || { echo "error: the RISC-V toolchain did not install" >&2; exit 1; }
[ -f /usr/lib/picolibc/riscv64-unknown-elf/picolibc.specs ] || { echo "error: picolibc did not install" >&2; exit 1; }
