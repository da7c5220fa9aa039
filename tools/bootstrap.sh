#!/usr/bin/env bash
# Installs everything sawrt needs on Debian 12; idempotent and quick when all is present.
# --check: look at the Debian packages again even if this package list was checked before.
set -euo pipefail

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cache="$root/.cache"

apt_packages=(
  build-essential cmake ninja-build pkg-config git python3 python3-venv python3-pip
  libeigen3-dev liborocos-kdl-dev libusb-1.0-0-dev
  libfastrtps-dev libfastcdr-dev fastddsgen libssl-dev openssl  # openssl: the keystore tests check our files with it
  libyaml-cpp-dev libcli11-dev libfmt-dev
  libgtest-dev libbenchmark-dev rt-tests stress-ng clang-format
  libzeroc-ice-dev zeroc-ice-compilers iproute2
  clang libclang-rt-14-dev ccache  # the fuzz preset (libFuzzer), faster rebuilds in CI
  cyclonedds-dev cyclonedds-tools  # an independent secure DDS peer (Debian's build has the security plugins)
  # sawgui's tests: real windows under Xvfb; what PySide6's xcb platform plugin links beyond libxcb1
  # (found with ldd on plugins/platforms/libqxcb.so and lib/libQt6XcbQpa.so.6).
  xvfb xauth libxkbcommon-x11-0 libxcb-cursor0 libxcb-icccm4 libxcb-keysyms1 libxcb-image0
  libxcb-render-util0 libxcb-randr0 libxcb-shape0 libxcb-xkb1 libxcb-xfixes0 libxcb-sync1 libxcb-shm0
  libegl1 libgl1 libfontconfig1 libdbus-1-3
  file  # CPackDeb reads the binaries' types with it: the package tests fail without it on a new root
  # tests/kernel: Debian's PREEMPT_RT kernel booted under QEMU by virtme-ng (from the venv), with
  # can-utils as an independent SocketCAN peer inside the guest.
  qemu-system-x86 linux-image-rt-amd64 can-utils busybox-static  # busybox-static: virtme-ng's initramfs (9p is a module)
)

# The package check runs once per package list (and with --check): builds call this script
# every time, and asking dpkg about every package each build is wasted seconds.
mkdir -p "$cache"
apt_stamp="$cache/apt-packages.sha256"
want_apt=$(printf '%s\n' "${apt_packages[@]}" | sha256sum | cut -d' ' -f1)
if [ "${1:-}" = "--check" ] || [ "$(cat "$apt_stamp" 2>/dev/null)" != "$want_apt" ]; then
  missing=()
  for p in "${apt_packages[@]}"; do
    if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
      missing+=("$p")
    fi
  done
  if ((${#missing[@]})); then
    echo "bootstrap: installing from Debian: ${missing[*]}"
    sudo=""
    [ "$(id -u)" -eq 0 ] || sudo="sudo"
    $sudo apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
  fi
  echo "$want_apt" > "$apt_stamp"
fi

# Ruckig: pinned sdist from PyPI, checksum verified, unpacked into an ignored cache.
ruckig_version=0.19.4
ruckig_sha256=71d003bf0ff9aa0031d4520b0290a5ffa6458149f5afce8be3ed6d6fba49ea64
ruckig_dir="$cache/ruckig-$ruckig_version"
if [ ! -f "$ruckig_dir/CMakeLists.txt" ]; then
  mkdir -p "$cache"
  tarball="$cache/ruckig-$ruckig_version.tar.gz"
  if [ ! -f "$tarball" ]; then
    echo "bootstrap: fetching the ruckig==$ruckig_version sdist (by file name, nothing built)"
    python3 "$root/tools/fetch_sdist.py" ruckig "$ruckig_version" "$ruckig_sha256" "$cache"
  fi
  echo "$ruckig_sha256  $tarball" | sha256sum --check --quiet ||
    { echo "bootstrap: checksum mismatch for $tarball" >&2; rm -f "$tarball"; exit 1; }
  tar -xzf "$tarball" -C "$cache"
fi

# A Python venv for the tools (plots, experiment scripts), rebuilt when requirements change.
venv="$root/.venv"
stamp="$venv/.requirements.sha256"
want=$(sha256sum "$root/tools/requirements.txt" | cut -d' ' -f1)
if [ ! -x "$venv/bin/python" ] || [ "$(cat "$stamp" 2>/dev/null)" != "$want" ]; then
  echo "bootstrap: creating the tools venv (.venv)"
  python3 -m venv "$venv"
  "$venv/bin/python" -m pip install --quiet --disable-pip-version-check -r "$root/tools/requirements.txt"
  echo "$want" > "$stamp"
fi
