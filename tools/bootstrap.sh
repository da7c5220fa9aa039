#!/usr/bin/env bash
# Installs what sawrt needs on Debian 12, in two parts; idempotent and quick when all is present.
#   tools/bootstrap.sh          the build's part: what configuring and building every target of the
#                               release preset needs (the libraries, saw-rt, saw-gateway, sawctl, the
#                               tools, the test binaries, the .debs) and the pinned Ruckig sdist.
#                               tools/build.sh (so the main job, tools/run.sh) calls this.
#   tools/bootstrap.sh --tests  that, then what running the test suite and the tools' scripts needs
#                               on top: QEMU and the PREEMPT_RT kernel (tests/kernel), clang (the fuzz
#                               preset), Xvfb and Qt's X libraries, can-utils, stress-ng, rt-tests, a
#                               Cyclone DDS peer, and the Python venv (.venv, tools/requirements.txt).
#                               tools/test.sh, .ci/run and the scripts that use .venv call this.
# --check (with either): look at the Debian packages again even if this package list was checked before.
set -euo pipefail

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cache="$root/.cache"

tests=0
check=0
for a in "$@"; do
  case $a in
    --tests) tests=1 ;;
    --check) check=1 ;;
    *) echo "usage: tools/bootstrap.sh [--tests] [--check]" >&2; exit 2 ;;
  esac
done

# The build's part: every find_package/find_program REQUIRED of the release preset's configure,
# and what its build and packaging run. fastddsgen is a Java program (half of this list's download).
build_packages=(
  build-essential cmake ninja-build pkg-config git python3
  python3-pip  # tools/fetch_sdist.py reads pip's configuration for the index it fetches Ruckig from
  libeigen3-dev liborocos-kdl-dev libusb-1.0-0-dev
  libfastrtps-dev libfastcdr-dev fastddsgen libssl-dev
  libyaml-cpp-dev libcli11-dev libfmt-dev
  libgtest-dev  # the test binaries are part of the release preset's build (SAW_BUILD_TESTS)
  libzeroc-ice-dev zeroc-ice-compilers  # saw-latency's Ice baseline (tools/bench, SAW_WITH_ICE)
  file  # CPackDeb reads the binaries' types with it: the .debs are not made without it on a new root
)

# The tests' part: nothing here is needed to configure or build the release preset. cyclonedds-dev
# adds a test binary (saw-cyclone-peer, found QUIET): the next configure, tools/test.sh's, builds it.
test_packages=(
  python3-venv  # the tools venv below
  libbenchmark-dev rt-tests stress-ng clang-format
  iproute2  # the network-namespace tests (ip netns, veth)
  openssl   # the keystore tests check our files with the command
  clang libclang-rt-14-dev ccache  # the fuzz preset (libFuzzer), faster rebuilds in CI
  cyclonedds-dev cyclonedds-tools  # an independent secure DDS peer (Debian's build has the security plugins)
  fastdds-tools  # fast-discovery-server: Fast DDS's own discovery server, for ROS_DISCOVERY_SERVER across a router
  # sawgui's tests: real windows under Xvfb; what PySide6's xcb platform plugin links beyond libxcb1
  # (found with ldd on plugins/platforms/libqxcb.so and lib/libQt6XcbQpa.so.6).
  xvfb xauth libxkbcommon-x11-0 libxcb-cursor0 libxcb-icccm4 libxcb-keysyms1 libxcb-image0
  libxcb-render-util0 libxcb-randr0 libxcb-shape0 libxcb-xkb1 libxcb-xfixes0 libxcb-sync1 libxcb-shm0
  libegl1 libgl1 libfontconfig1 libdbus-1-3
  # tests/kernel: Debian's PREEMPT_RT kernel booted under QEMU by virtme-ng (from the venv), with
  # can-utils as an independent SocketCAN peer inside the guest.
  qemu-system-x86 linux-image-rt-amd64 can-utils busybox-static  # busybox-static: virtme-ng's initramfs (9p is a module)
)

# apt_install NAME PACKAGE...: installs those of the packages that are missing. dpkg is asked once
# per package list (and with --check): builds call this script every time, and asking dpkg about
# every package each build is wasted seconds.
apt_install() {
  local name=$1
  shift
  local stamp="$cache/apt-$name.sha256" want missing=() p sudo=""
  want=$(printf '%s\n' "$@" | sha256sum | cut -d' ' -f1)
  if ((check)) || [ "$(cat "$stamp" 2>/dev/null)" != "$want" ]; then
    for p; do
      if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
        missing+=("$p")
      fi
    done
    if ((${#missing[@]})); then
      echo "bootstrap: installing from Debian ($name): ${missing[*]}"
      [ "$(id -u)" -eq 0 ] || sudo="sudo"
      # apt's lists once per run of this script, and only when something is to be installed.
      if ((!apt_updated)); then
        $sudo apt-get update -qq
        apt_updated=1
      fi
      DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
    fi
    echo "$want" > "$stamp"
  fi
}
apt_updated=0
mkdir -p "$cache"
rm -f "$cache/apt-packages.sha256"  # the one list's stamp, before the list was split in two
apt_install build "${build_packages[@]}"
if ((tests)); then apt_install tests "${test_packages[@]}"; fi

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

# The tests' part goes on: a Python venv for the tests and the tools (plots, experiment scripts,
# sawgui, virtme-ng), rebuilt when requirements change. Nothing in the build uses it.
((tests)) || exit 0
venv="$root/.venv"
stamp="$venv/.requirements.sha256"
want=$(sha256sum "$root/tools/requirements.txt" | cut -d' ' -f1)
if [ ! -x "$venv/bin/python" ] || [ "$(cat "$stamp" 2>/dev/null)" != "$want" ]; then
  echo "bootstrap: creating the tools venv (.venv)"
  python3 -m venv "$venv"
  "$venv/bin/python" -m pip install --quiet --disable-pip-version-check -r "$root/tools/requirements.txt"
  echo "$want" > "$stamp"
fi
