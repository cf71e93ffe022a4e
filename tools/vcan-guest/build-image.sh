#!/bin/sh
# Build (once, cached) the QEMU guest used to run the CAN suite on a host kernel without SocketCAN:
# Debian's own kernel (fetched with apt-get download, unpacked with dpkg -x, never installed) and a
# busybox-static initramfs that loads virtio/9p/can/vcan/overlay modules, mounts the host / over 9p and runs
# a job script in a chroot, or boots the host's systemd on an overlay of it (see init.sh).
# Usage: build-image.sh CACHE_DIR      -> CACHE_DIR/vmlinuz, CACHE_DIR/initrd.gz
set -eu
cache=${1:?usage: build-image.sh CACHE_DIR}
here=$(cd "$(dirname "$0")" && pwd)
mkdir -p "$cache"
cache=$(cd "$cache" && pwd)

fail() { echo "vcan-guest: $*" >&2; exit 1; }
for tool in busybox cpio gzip dpkg apt-get; do
    command -v $tool >/dev/null 2>&1 || fail "missing host tool '$tool' (apt-get install busybox-static cpio)"
done
bb=$(command -v busybox)
# A dynamically linked busybox cannot run in the initramfs (no libc there).
if file "$bb" 2>/dev/null | grep -q 'dynamically linked'; then
    fail "$bb is dynamically linked; install busybox-static"
fi

# 1. Kernel: the exact linux-image-6.1.0-NN-amd64 that linux-image-amd64 depends on (no glob: a glob
#    would download every version).
if [ ! -s "$cache/vmlinuz" ] || [ ! -d "$cache/modules" ]; then
    pkg=$(apt-cache depends linux-image-amd64 2>/dev/null | sed -n 's/^ *Depends: \(linux-image-[0-9][^ ]*\)$/\1/p' | head -n 1)
    [ -n "$pkg" ] || fail "apt-cache cannot resolve linux-image-amd64's kernel package (run apt-get update?)"
    rm -rf "$cache/deb" "$cache/x" && mkdir -p "$cache/deb"
    (cd "$cache/deb" && apt-get download "$pkg" >/dev/null 2>&1) || fail "apt-get download $pkg failed"
    dpkg -x "$cache"/deb/*.deb "$cache/x"
    cp "$cache"/x/boot/vmlinuz-* "$cache/vmlinuz"
    rm -rf "$cache/modules" && mv "$cache"/x/lib/modules/* "$cache/modules"
    rm -rf "$cache/x" "$cache/deb"
    echo "$pkg" >"$cache/kernel-package"
fi

# 2. Initramfs; rebuilt when init.sh or this script change.
stamp=$(cat "$here/init.sh" "$here/build-image.sh" | cksum | cut -d' ' -f1)
if [ -s "$cache/initrd.gz" ] && [ "$(cat "$cache/initrd.stamp" 2>/dev/null)" = "$stamp" ]; then
    exit 0
fi
root="$cache/initramfs"
rm -rf "$root" && mkdir -p "$root/bin" "$root/lib/modules" "$root/proc" "$root/sys" "$root/dev" "$root/host"
cp "$bb" "$root/bin/busybox"
ln -s busybox "$root/bin/sh"
# Dependency order (see /work/shared/notes/vcan-guest.md).
mods="virtio_ring virtio virtio_pci_legacy_dev virtio_pci_modern_dev virtio_pci netfs fscache 9pnet 9pnet_virtio 9p can can-raw can-dev vcan overlay"
: >"$root/lib/modules/order"
for m in $mods; do
    f=$(find "$cache/modules" -name "$m.ko" | head -n 1)
    [ -n "$f" ] || fail "module $m.ko not found in $(cat "$cache/kernel-package" 2>/dev/null)"
    cp "$f" "$root/lib/modules/"
    echo "$m" >>"$root/lib/modules/order"
done
cp "$here/init.sh" "$root/init"
chmod 755 "$root/init"
(cd "$root" && find . | cpio -o -H newc --quiet | gzip -1) >"$cache/initrd.gz.tmp"
mv "$cache/initrd.gz.tmp" "$cache/initrd.gz"
echo "$stamp" >"$cache/initrd.stamp"
