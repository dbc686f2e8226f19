#!/usr/bin/env bash
# Installs the cross tools that `acdrive export m4` and tests/test_export_target.py need:
# the Cortex-M compiler (gcc-arm-none-eabi), its C library (libnewlib-arm-none-eabi) and the
# Arm board models of QEMU (qemu-system-arm); and clang, the second host compiler the exported
# C is checked with (tests/test_export_compilers.py). Debian/Ubuntu (apt-get). Does nothing when
# all four tools are already present; as root it installs them, otherwise through sudo.
set -euo pipefail

packages=(gcc-arm-none-eabi libnewlib-arm-none-eabi qemu-system-arm clang)
newlib_math=/usr/lib/arm-none-eabi/newlib/thumb/v7e-m+fp/hard/libm.a

present() {
    command -v arm-none-eabi-gcc >/dev/null 2>&1 \
        && command -v arm-none-eabi-size >/dev/null 2>&1 \
        && command -v qemu-system-arm >/dev/null 2>&1 \
        && command -v clang >/dev/null 2>&1 \
        && { [ -e "$newlib_math" ] || arm-none-eabi-gcc -mcpu=cortex-m4 -mfpu=fpv4-sp-d16 \
            -mfloat-abi=hard -print-file-name=libm.a | grep -q /; }
}

if present; then
    echo "cross tools present: arm-none-eabi-gcc, newlib, qemu-system-arm, clang (nothing to install)"
    exit 0
fi
if ! command -v apt-get >/dev/null 2>&1; then
    echo "install-cross-tools.sh: apt-get not found; install ${packages[*]} with your system's package manager" >&2
    exit 1
fi
if [ "$(id -u)" -eq 0 ]; then
    run=()
elif command -v sudo >/dev/null 2>&1; then
    run=(sudo)
else
    echo "install-cross-tools.sh: not root and sudo not found; as root run: apt-get install -y --no-install-recommends ${packages[*]}" >&2
    exit 1
fi
export DEBIAN_FRONTEND=noninteractive
"${run[@]}" apt-get update
"${run[@]}" apt-get install -y --no-install-recommends "${packages[@]}"
present || { echo "install-cross-tools.sh: the tools are still missing after apt-get install" >&2; exit 1; }
echo "cross tools installed: ${packages[*]}"
