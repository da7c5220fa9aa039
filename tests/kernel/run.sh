#!/usr/bin/env bash
# The kernel-level tests: boots Debian's PREEMPT_RT kernel (the host's /boot/vmlinuz-*-rt-amd64,
# never a downloaded one) under QEMU with virtme-ng, over this machine's root read-only and
# without network, and runs tests/kernel/guest.sh there: every check in one boot, each writing
# RESULTS/NAME.result. KVM when a short probe shows a KVM guest booting, else software
# emulation (TCG). Exit 0 when the guest ran to its end (the checks' own verdicts are the
# Kernel.* CTest tests, read by result.sh), 1 when it did not, 77 (skip) when QEMU, virtme-ng
# or the kernel package is missing.
# Usage: run.sh SRC RESULTS NAME=PROGRAM...   (the built programs guest.sh needs, by name)
set -euo pipefail
src=$(realpath "$1")
out=$(realpath -m "$2")  # absolute: the guest runs its checks from /tmp
shift 2

skip() {
  echo "SKIP: $*"
  mkdir -p "$out"
  echo "$*" > "$out/skipped"
  exit 77
}

rm -rf "$out"
kernel=$(find /boot -maxdepth 1 -name 'vmlinuz-*-rt-amd64' 2>/dev/null | sort -V | tail -n 1)
[ -n "$kernel" ] || skip "no PREEMPT_RT kernel in /boot (Debian's linux-image-rt-amd64; tools/bootstrap.sh --tests installs it)"
command -v qemu-system-x86_64 > /dev/null || skip "no qemu-system-x86_64 (Debian's qemu-system-x86)"
[ -x "$src/.venv/bin/vng" ] || skip "no virtme-ng in the tools venv ($src/.venv: tools/bootstrap.sh --tests)"
command -v busybox > /dev/null || skip "no busybox for virtme-ng's initramfs (Debian's busybox-static)"
mkdir -p "$out"
for target in "$@"; do
  name=${target%%=*}
  path=${target#*=}
  [ -x "$path" ] || { echo "run.sh: $name: $path is not built" >&2; exit 1; }
  path=$(realpath "$path")
  printf '%s=%q\n' "$name" "$path" >> "$out/targets.env"
done

# KVM hangs on some hosts right after the real-mode setup, before the kernel prints anything: a
# KVM guest that prints its banner within 15 s works (one boots in well under a second).
accel=tcg
if [ -r /dev/kvm ] && [ -w /dev/kvm ]; then
  if timeout 15 qemu-system-x86_64 -accel kvm -m 256 -nodefaults -nographic -no-reboot -net none \
    -serial stdio -monitor none -kernel "$kernel" -append "console=ttyS0 panic=-1 earlyprintk=serial" \
    < /dev/null 2> /dev/null | grep -q -m1 "Linux version"; then
    accel=kvm
  fi
fi
echo "kernel: $kernel; accelerator: $accel"
echo "$accel" > "$out/accelerator"

args=(-r "$kernel" --cpus 2 --memory 2G --rwdir "$out" --exec "$src/tests/kernel/guest.sh $src $out")
[ "$accel" = kvm ] || args+=(--disable-kvm)
SECONDS=0
rc=0
# virtme-run (virtme-ng's helper) must be on PATH. No --network: the guest has loopback only.
PATH="$src/.venv/bin:$PATH" timeout --kill-after=10 840 vng "${args[@]}" < /dev/null > "$out/console.log" 2>&1 || rc=$?
echo "$SECONDS" > "$out/seconds"
echo "guest: $SECONDS s in all ($accel), the kernel up $(cat "$out/boot-seconds" 2>/dev/null || echo '?') s when the checks began"
for r in "$out"/*.result; do
  [ -e "$r" ] && echo "  $(basename "$r" .result): $(head -n 1 "$r")"
done
if [ ! -e "$out/done" ]; then
  echo "FAIL: the guest did not run to its end (vng exit $rc); its console:"
  tail -n 40 "$out/console.log"
  exit 1
fi
