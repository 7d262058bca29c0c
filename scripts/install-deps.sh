#!/usr/bin/env bash
# Installs the Debian packages cellray builds and tests with (see DEVELOPERS.md).
# Idempotent: silent when everything is present; needs root (or sudo) only when
# something is missing.
set -euo pipefail

pkgs=(
  build-essential cmake pkg-config git
  ocl-icd-opencl-dev opencl-clhpp-headers opencl-c-headers pocl-opencl-icd clinfo
  libglm-dev libopenimageio-dev openimageio-tools libtbb-dev libcli11-dev
  nlohmann-json3-dev libfmt-dev doctest-dev libbenchmark-dev libtinyobjloader-dev
  libembree-dev python3-matplotlib oclgrind
  clang libclang-rt-14-dev llvm clang-15 libclc-15
  libopenmpi-dev openmpi-bin
  python3-dev python3-venv
)

missing=()
for p in "${pkgs[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'ok installed'; then
    missing+=("$p")
  fi
done
[ ${#missing[@]} -eq 0 ] && exit 0

if [ "$(id -u)" -eq 0 ]; then
  sudo=()
elif command -v sudo >/dev/null 2>&1 && sudo -n true 2>/dev/null; then
  sudo=(sudo -n)
else
  echo "cellray: scripts/install-deps.sh: missing packages: ${missing[*]}" >&2
  echo "cellray: run this script as root (or with passwordless sudo) to install them" >&2
  exit 1
fi

echo "cellray: installing ${#missing[@]} Debian packages: ${missing[*]}" >&2
export DEBIAN_FRONTEND=noninteractive
"${sudo[@]}" apt-get update -qq >/dev/null
"${sudo[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
