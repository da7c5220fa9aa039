#!/usr/bin/env bash
# Times the README's two commands' installs as a new user meets them: a minimal Debian 12 root
# made by debootstrap --variant=minbase (nothing installed, no apt or pip cache) from the Debian
# mirror this machine's apt uses, the tree of a commit copied in (git archive), then in a chroot
# (this host's /proc, /sys, /dev bound in; all unmounted on exit):
#   1. the main job's install part: `tools/bootstrap.sh`, exactly what `tools/run.sh` runs first
#      (through tools/build.sh): apt-get update, the build's Debian packages, the Ruckig sdist;
#   2. without --build, `cmake --preset release` (configure only): proof that step 1 is enough to
#      configure; timed but not counted in either figure;
#      with --build, the rest of the main job, `tools/run.sh --duration 2`: configure, build saw-rt
#      and the packages it loads (about 6-10 minutes on 2 cores), a 2 s run; counted in the main
#      job's figure;
#   3. the test command's install part, after the main job as the README orders them:
#      `tools/bootstrap.sh --tests`, what `tools/test.sh` runs first: the tests' Debian packages
#      (QEMU, the RT kernel and its initramfs, clang, Xvfb...) and the Python venv from PyPI;
#   4. with --suite, the rest of the test command, `tools/test.sh` (the whole build, every test).
# Each step's wall-clock time includes its downloads, so it depends on this host's network and
# mirror; debootstrap's own time is reported apart and counted nowhere. Every output line is
# stamped with seconds since the start; the last lines are the figures and each step's exit status.
# Needs root and debootstrap.
# Usage: tools/fresh-machine.sh [--build] [--suite] [ROOT_DIR] [COMMIT]   (defaults /tmp/saw-fresh-root HEAD)
set -euo pipefail
build=0
suite=0
pos=()
for a in "$@"; do
  case $a in
    --build) build=1 ;;
    --suite) suite=1 ;;
    -*) echo "usage: tools/fresh-machine.sh [--build] [--suite] [ROOT_DIR] [COMMIT]" >&2; exit 2 ;;
    *) pos+=("$a") ;;
  esac
done
set -- ${pos[@]+"${pos[@]}"}
[ "$(id -u)" -eq 0 ] || { echo "fresh-machine: needs root (debootstrap, chroot, mounts)" >&2; exit 1; }
command -v debootstrap >/dev/null || {
  echo "fresh-machine: needs debootstrap (apt-get install debootstrap) and root" >&2
  exit 1
}
root_dir=$(realpath -m "${1:-/tmp/saw-fresh-root}")
commit=${2:-HEAD}
[ "$root_dir" != / ] || { echo "fresh-machine: ROOT_DIR must not be /" >&2; exit 2; }
repo=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
# Everything mounted below the root, deepest first: the bind mounts made here, and any a test
# made inside (`ip netns` mounts /run/netns).
cleanup() {
  awk -v r="$root_dir" '$2 == r || index($2, r "/") == 1 { print $2 }' /proc/mounts | sort -r |
    while read -r m; do umount -l "$m" 2>/dev/null || true; done
}
trap cleanup EXIT
cleanup
rm -rf "$root_dir"
# The mirror of this machine's own apt sources (deb822 `.sources` stanzas, or one-line
# sources.list entries) that serves bookworm itself, not its security suite.
mirror=$(awk 'BEGIN { RS = ""; FS = "\n" }
  { uri = ""; ok = 0; off = 0
    for (i = 1; i <= NF; i++) {
      n = split($i, w, /[ \t]+/)
      if (w[1] == "URIs:") uri = w[2]
      if (w[1] == "Enabled:" && w[2] == "no") off = 1
      if (w[1] == "Suites:") for (j = 2; j <= n; j++) if (w[j] == "bookworm") ok = 1
    }
    if (ok && !off && uri != "") { print uri; exit } }' /etc/apt/sources.list.d/*.sources 2>/dev/null || true)
if [ -z "$mirror" ] && [ -f /etc/apt/sources.list ]; then
  mirror=$(awk '$1 == "deb" && / bookworm / { for (i = 2; i <= NF; i++) if ($i ~ /:\/\//) { print $i; exit } }' \
    /etc/apt/sources.list)
fi
[ -n "$mirror" ] || { echo "fresh-machine: no bookworm entry in this machine's apt sources" >&2; exit 1; }
echo "fresh-machine: debootstrap --variant=minbase bookworm from $mirror (not counted)"
SECONDS=0
debootstrap --variant=minbase bookworm "$root_dir" "$mirror" >/dev/null
echo "fresh-machine: debootstrap took ${SECONDS} s"
# A network reached through a proxy with a local CA (as in some sandboxes): trust it inside too.
if compgen -G "/usr/local/share/ca-certificates/*.crt" >/dev/null; then
  mkdir -p "$root_dir/usr/local/share/ca-certificates"
  cp /usr/local/share/ca-certificates/*.crt "$root_dir/usr/local/share/ca-certificates/"
fi
# The root a mount point of its own, as a machine's is: `ip netns exec`/`ip -n` remount it
# (`mount --make-rslave /`), which fails on a plain directory.
mount --bind "$root_dir" "$root_dir"
for d in proc sys dev dev/shm; do mount --bind "/$d" "$root_dir/$d"; done
cp /etc/resolv.conf "$root_dir/etc/resolv.conf"
mkdir -p "$root_dir/root/sawrt"
git -C "$repo" archive "$commit" | tar -x -C "$root_dir/root/sawrt"
chroot "$root_dir" /usr/bin/env -i HOME=/root PATH=/usr/sbin:/usr/bin:/sbin:/bin \
  SAW_BUILD=$build SAW_SUITE=$suite /bin/bash -c '
  cd /root/sawrt
  s=${EPOCHREALTIME/./}
  stamp() { while IFS= read -r l; do n=${EPOCHREALTIME/./}; printf "%6d.%01d %s\n" $(((n-s)/1000000)) $(((n-s)/100000%10)) "$l"; done; }
  status=0
  report=""
  took=0
  # step NAME COMMAND...: runs a command, stamped; its time (in $took) and exit status kept for the end.
  step() {
    local name=$1 t0=${EPOCHREALTIME/./} rc=0
    shift
    echo "== $name"
    "$@" 2>&1 | stamp || rc=$?
    local t1=${EPOCHREALTIME/./}
    took=$(((t1-t0)/1000000))
    local line
    printf -v line "%-50s %6d s  exit %d\n" "$name" "$took" "$rc"
    report+=$line
    [ "$rc" -eq 0 ] || status=1
  }
  set -o pipefail
  step "main job install: tools/bootstrap.sh" tools/bootstrap.sh
  main=$took
  summary="main job install: $main s"
  if [ "$SAW_BUILD" = 1 ]; then
    step "main job rest: tools/run.sh --duration 2" tools/run.sh --duration 2
    summary+=" (with its build and run: $((main + took)) s)"
  else
    # Not counted: shows that the build part alone configures the release preset.
    step "configure check: cmake --preset release" cmake --preset release
  fi
  step "test command install: tools/bootstrap.sh --tests" tools/bootstrap.sh --tests
  summary+="; test-command install: $took s"
  if [ "$SAW_SUITE" = 1 ]; then
    step "test command rest: tools/test.sh" tools/test.sh
    summary+=" (the whole test command after it: $took s)"
  fi
  n=${EPOCHREALTIME/./}
  printf "%s" "$report"
  echo "total in the chroot $(((n-s)/1000000)) s"
  echo "$summary"
  exit $status'
