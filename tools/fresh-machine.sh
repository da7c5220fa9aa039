#!/usr/bin/env bash
# Times the README's main command as a new user would meet it: a minimal Debian 12 root made by
# debootstrap (nothing installed, nothing cached), the tree of a commit copied in, then
# `tools/run.sh --duration 2` in a chroot, every output line stamped with seconds since start.
# Needs root and debootstrap. Usage: tools/fresh-machine.sh [ROOT_DIR] [COMMIT]
set -euo pipefail
root_dir=${1:-/tmp/saw-fresh-root}
commit=${2:-HEAD}
repo=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cleanup() { for d in dev/shm dev sys proc; do umount "$root_dir/$d" 2>/dev/null || true; done; }
trap cleanup EXIT
cleanup
rm -rf "$root_dir"
debootstrap --variant=minbase bookworm "$root_dir" http://deb.debian.org/debian >/dev/null
# A network reached through a proxy with a local CA (as in some sandboxes): trust it inside too.
if compgen -G "/usr/local/share/ca-certificates/*.crt" >/dev/null; then
  mkdir -p "$root_dir/usr/local/share/ca-certificates"
  cp /usr/local/share/ca-certificates/*.crt "$root_dir/usr/local/share/ca-certificates/"
fi
for d in proc sys dev dev/shm; do mount --bind "/$d" "$root_dir/$d"; done
cp /etc/resolv.conf "$root_dir/etc/resolv.conf"
mkdir -p "$root_dir/root/sawrt"
git -C "$repo" archive "$commit" | tar -x -C "$root_dir/root/sawrt"
chroot "$root_dir" /usr/bin/env -i HOME=/root PATH=/usr/sbin:/usr/bin:/sbin:/bin /bin/bash -c '
  cd /root/sawrt
  s=${EPOCHREALTIME/./}
  stamp() { while IFS= read -r l; do n=${EPOCHREALTIME/./}; printf "%6d.%01d %s\n" $(((n-s)/1000000)) $(((n-s)/100000%10)) "$l"; done; }
  tools/run.sh --duration 2 2>&1 | stamp
  n=${EPOCHREALTIME/./}
  echo "total $(((n-s)/1000000)) s"'
