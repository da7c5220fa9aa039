#!/usr/bin/env bash
# Times both README commands as a new user would meet them: a minimal Debian 12 root made by
# debootstrap (nothing installed, nothing cached) from the Debian mirror this machine's apt uses,
# the tree of a commit copied in, then in a chroot `tools/run.sh --duration 2` (the main job)
# and `tools/test.sh` (the suite), every output line stamped with seconds since start and each
# step's time and exit status reported. Needs root and debootstrap.
# Usage: tools/fresh-machine.sh [ROOT_DIR] [COMMIT]
set -euo pipefail
command -v debootstrap >/dev/null || {
  echo "fresh-machine: needs debootstrap (apt-get install debootstrap) and root" >&2
  exit 1
}
root_dir=${1:-/tmp/saw-fresh-root}
commit=${2:-HEAD}
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
echo "fresh-machine: debootstrap bookworm from $mirror"
debootstrap --variant=minbase bookworm "$root_dir" "$mirror" >/dev/null
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
chroot "$root_dir" /usr/bin/env -i HOME=/root PATH=/usr/sbin:/usr/bin:/sbin:/bin /bin/bash -c '
  cd /root/sawrt
  s=${EPOCHREALTIME/./}
  stamp() { while IFS= read -r l; do n=${EPOCHREALTIME/./}; printf "%6d.%01d %s\n" $(((n-s)/1000000)) $(((n-s)/100000%10)) "$l"; done; }
  status=0
  report=""
  # step NAME COMMAND...: runs a README command, stamped; its time and exit status kept for the end.
  step() {
    local name=$1 t0=${EPOCHREALTIME/./} rc=0
    shift
    echo "== $name"
    "$@" 2>&1 | stamp || rc=$?
    local t1=${EPOCHREALTIME/./}
    local line
    printf -v line "%-28s %6d s  exit %d\n" "$name" $(((t1-t0)/1000000)) "$rc"
    report+=$line
    [ "$rc" -eq 0 ] || status=1
  }
  set -o pipefail
  step "tools/run.sh --duration 2" tools/run.sh --duration 2
  step "tools/test.sh" tools/test.sh
  n=${EPOCHREALTIME/./}
  printf "%s" "$report"
  echo "total $(((n-s)/1000000)) s"
  exit $status'
