#!/bin/sh
# Guest PID 1: load modules, mount the host / over 9p, run the job in a chroot, print the exit marker.
/bin/busybox --install -s /bin
mount -t proc proc /proc
mount -t sysfs sys /sys
mount -t devtmpfs dev /dev
for m in $(cat /lib/modules/order); do
    insmod /lib/modules/$m.ko || echo "MCA-GUEST: insmod $m failed"
done
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
