#!/usr/bin/env bash
# The README's first run on a bare machine, measured: a minimal Debian bookworm (debootstrap --variant=minbase)
# in DIR, this checkout's committed tree (git archive HEAD) copied into it, then inside it scripts/install-deps.sh
# and scripts/demo.sh, with the time each phase took. Needs root, debootstrap and the network; uses the
# machine's cores for about ten minutes, so measure on an otherwise idle machine. DIR is removed first if it
# exists, and kept afterwards (its /src/out/demo holds the run).
#   scripts/first-run.sh [DIR]        default /tmp/beslam-bare
set -euo pipefail
cd "$(dirname "$0")/.."
dir=${1:-/tmp/beslam-bare}
[ "$(id -u)" -eq 0 ] || { echo "first-run: needs root (debootstrap, chroot, mounts)" >&2; exit 1; }
command -v debootstrap >/dev/null || { echo "first-run: debootstrap is not installed (apt-get install debootstrap)" >&2; exit 1; }

unmount() { for m in proc dev sys; do mountpoint -q "$dir/$m" && umount "$dir/$m"; done; return 0; }
if [ -e "$dir" ]; then
  unmount
  rm -rf "$dir"
fi
trap unmount EXIT
debootstrap --variant=minbase bookworm "$dir" http://deb.debian.org/debian >/dev/null
mkdir -p "$dir/src"
git archive HEAD | tar -x -C "$dir/src"
cp /etc/resolv.conf "$dir/etc/resolv.conf"
mount -t proc proc "$dir/proc"
mount --bind /dev "$dir/dev"
mount --bind /sys "$dir/sys"

log="$dir/src/first-run.log"
t0=$(date +%s)
chroot "$dir" env DEBIAN_FRONTEND=noninteractive bash -c 'cd /src && scripts/install-deps.sh' >"$log" 2>&1 ||
  { echo "first-run: install failed, see $log" >&2; exit 1; }
t1=$(date +%s)
chroot "$dir" bash -c 'cd /src && scripts/demo.sh' >>"$log" 2>&1 || { echo "first-run: demo failed, see $log" >&2; exit 1; }
t2=$(date +%s)
built=$(stat -c %Y "$dir/src/build/bin/beslam")
echo "first-run: install $((t1 - t0)) s, configure and build $((built - t1)) s, demo run $((t2 - built)) s;" \
  "total $((t2 - t0)) s ($(grep -c '^Setting up' "$log") packages set up; log $log)"
[ -f "$dir/src/out/demo/summary.json" ] || { echo "first-run: the demo wrote no summary.json, see $log" >&2; exit 1; }
grep -m1 'APE' "$log" || true
