#!/bin/sh
# Guest PID 1: load modules, mount the host / over 9p, run the job in a chroot, print the exit marker.
/bin/busybox --install -s /bin
mount -t proc proc /proc
mount -t sysfs sys /sys
mount -t devtmpfs dev /dev
for m in $(cat /lib/modules/order); do
    insmod /lib/modules/$m.ko || echo "MCA-GUEST: insmod $m failed"
done
# mcainit=systemd (run.sh MCA_GUEST_MODE=systemd): the host tree (shared read-only) becomes the lower layer
# of an overlay root with a tmpfs upper layer, so nothing the guest writes reaches the host; the "results"
# share (writable) is mounted at /mca-results; the job prepares that root (chroot) and the guest's PID 1
# becomes the host's own /lib/systemd/systemd (switch_root). The job's units write the results and power off.
if grep -q 'mcainit=systemd' /proc/cmdline; then
    o="trans=virtio,version=9p2000.L,msize=262144"
    mkdir -p /rw /newroot
    if mount -t 9p -o ro,$o host /host && mount -t tmpfs -o mode=755 rw /rw && mkdir -p /rw/upper /rw/work &&
        mount -t overlay -o lowerdir=/host,upperdir=/rw/upper,workdir=/rw/work overlay /newroot &&
        mkdir -p /newroot/mca-results && mount -t 9p -o $o results /newroot/mca-results; then
        job=$(sed -n 's/.*mcajob=\([^ ]*\).*/\1/p' /proc/cmdline)
        for d in proc sys dev; do mount --bind /$d /newroot/$d; done
        chroot /newroot /bin/sh -c "cd / && exec /bin/sh $job"
        rc=$?
        for d in proc sys dev; do umount /newroot/$d; done
        if [ $rc -eq 0 ]; then
            umount /proc /sys
            mount --move /dev /newroot/dev
            exec switch_root /newroot /lib/systemd/systemd
        fi
        echo "MCA-GUEST: the job preparing the systemd root failed (exit $rc)"
    else
        echo "MCA-GUEST: the overlay root (9p host tree read-only, tmpfs upper, results share) failed"
        rc=96
    fi
    echo "MCA-GUEST-EXIT=$rc"
    poweroff -f
fi
rc=97
if mount -t 9p -o trans=virtio,version=9p2000.L,msize=262144 host /host; then
    for d in proc sys dev; do mount --bind /$d /host/$d; done
    mount -t devpts devpts /host/dev/pts 2>/dev/null
    mount -t tmpfs tmpfs /host/dev/shm 2>/dev/null
    job=$(sed -n 's/.*mcajob=\([^ ]*\).*/\1/p' /proc/cmdline)
    if [ -n "$job" ]; then
        ip link set lo up 2>/dev/null
        chroot /host /bin/sh -c "cd / && exec /bin/sh $job"
        rc=$?
    else
        echo "MCA-GUEST: no mcajob= on the kernel command line"
        rc=98
    fi
else
    echo "MCA-GUEST: 9p mount of the host tree failed"
fi
echo "MCA-GUEST-EXIT=$rc"
sync
poweroff -f
