#!/bin/sh
# SPDX-License-Identifier: MIT
# systemd for real: this machine's PID 1 is not systemd, so one QEMU guest (tools/vcan-guest,
# MCA_GUEST_SYSTEMD) boots the host's own /lib/systemd/systemd as PID 1 on an overlay root: the host tree,
# shared read-only over 9p, under a tmpfs upper layer (nothing the guest writes reaches the host). Before
# systemd starts, the job below lays a tree made here over that root (one cp): this build installed
# (`cmake --install` with DESTDIR: /usr/local/sbin/mcad, /usr/local/etc/mca/cells, the unit in
# /usr/local/lib/systemd/system, /usr/local/share/mca/mcad-run.sh), masks for the host's units and generators
# that do not belong in the guest, and mca-guest.target as the default: it runs
# tests/daemon/systemd_guest_checks.sh as a oneshot service after basic.target, which writes its lines to the
# results share and powers the guest off.
# usage: systemd_guest.sh BUILD_DIR SOURCE_DIR      (output kept in BUILD_DIR/tests/daemon/systemd-guest)
set -u
B=$(cd "$1" && pwd) S=$(cd "$2" && pwd)
OUT=$B/tests/daemon/systemd-guest
rm -rf "$OUT" && mkdir -p "$OUT/results"
if ! command -v qemu-system-x86_64 >/dev/null 2>&1; then
    echo "systemd_guest: FAIL: qemu-system-x86_64 is missing (apt-get install qemu-system-x86)"
    exit 1
fi
if [ ! -x /lib/systemd/systemd ]; then
    echo "systemd_guest: FAIL: no /lib/systemd/systemd on this host to boot (apt-get install systemd)"
    exit 1
fi
t0=$(date +%s)
DESTDIR=$OUT/stage cmake --install "$B" >"$OUT/install.log" 2>&1 || {
    tail -n 20 "$OUT/install.log"
    echo "systemd_guest: FAIL: cmake --install $B"
    exit 1
}
# The installed cell as an operator of an emulated CPU edits it (the same two edits as vcan_e2e.sh): under
# TCG deadlines are missed all the time (the sim arms do not care: task time advances per tick), so the
# overrun limit is out of reach and the PDNN may take 1 s; everything else is the shipped cell.
cell=$OUT/stage/usr/local/etc/mca/cells/cross_circles_sim.yaml
cp "$cell" "$OUT/cross_circles_sim.shipped.yaml"
sed -i -e 's/^\(  overrun_limit:\).*/\1 3600000   # systemd_guest.sh: emulated guest CPU (TCG)/' \
    -e 's/^\(  pdnn_budget_us:\).*/\1 1000000   # systemd_guest.sh: emulated guest CPU (TCG): the PDNN may take 1 s/' "$cell"
diff "$OUT/cross_circles_sim.shipped.yaml" "$cell" | grep '^[<>]' | sed 's/^</-  /; s/^>/+  /'
marker=etc/mca-systemd-guest-$$
# What the guest lays over its root before systemd starts, made here (each program an emulated CPU starts
# costs it ~0.3 s): R/usr/local what runs mcad from the install (the daemon, its DDS process, the cells, the
# unit, share/mca with mcad-run.sh, scenarios and robots; the development files and the other tools, 27 of
# its 37 MB, stay out), the test's units, the masks, the fstab.
R=$OUT/root
mkdir -p "$R/usr/local" "$R/etc/systemd/system" "$R/etc/systemd/system-generators"
chmod 755 "$R" "$R/etc" "$R/usr" "$R/usr/local"
for d in sbin libexec etc share/mca lib/systemd; do
    mkdir -p "$R/usr/local/$d" && cp -a "$OUT/stage/usr/local/$d/." "$R/usr/local/$d/"
done
# the overlay is writable, the host below it is not: this file must not appear on the host
echo guest >"$R/$marker"
# /tmp and /var/tmp in memory: systemd-tmpfiles --boot would otherwise empty the host's /tmp, one whiteout per
# file in the overlay (15 s)
printf 'tmpfs /tmp tmpfs mode=1777 0 0\ntmpfs /var/tmp tmpfs mode=1777 0 0\n' >"$R/etc/fstab"
U=$R/etc/systemd/system
# the host's own enabled units (timers, getty, databases, time sync) and what needs hardware or a network
for u in systemd-timesyncd.service systemd-pstore.service getty@tty1.service serial-getty@ttyS0.service \
    postgresql.service e2scrub_reap.service remote-fs.target timers.target systemd-networkd.service \
    systemd-networkd-wait-online.service NetworkManager-wait-online.service systemd-udev-trigger.service \
    systemd-udev-settle.service systemd-hwdb-update.service ldconfig.service systemd-random-seed.service \
    systemd-firstboot.service systemd-machine-id-commit.service apt-daily.timer apt-daily-upgrade.timer \
    systemd-journal-catalog-update.service systemd-update-done.service proc-sys-fs-binfmt_misc.automount \
    dev-hugepages.mount dev-mqueue.mount sys-kernel-debug.mount sys-kernel-tracing.mount \
    sys-fs-fuse-connections.mount sys-kernel-config.mount systemd-binfmt.service; do
    ln -s /dev/null "$U/$u"
done
# the host's generators but the fstab one (/tmp): the SysV and database ones cost the emulated CPU ~30 s
for g in /lib/systemd/system-generators/*; do
    case $g in */systemd-fstab-generator) continue ;; esac
    ln -s /dev/null "$R/etc/systemd/system-generators/$(basename "$g")"
done
# the checks go into the overlay too: once systemd mounts /tmp (fstab above), a tree under the host's /tmp
# (a CI clone) is hidden from the guest (seen: "cannot open .../systemd_guest_checks.sh")
cp "$S/tests/daemon/systemd_guest_checks.sh" "$R/usr/local/libexec/mca-guest-checks.sh"
cat >"$R/usr/local/libexec/mca-guest-test" <<END
#!/bin/sh
sh /usr/local/libexec/mca-guest-checks.sh $S >/mca-results/result.txt 2>&1
rc=\$?
sync
echo MCA-GUEST-EXIT=\$rc >/dev/ttyS0
systemctl poweroff --force --no-block
END
chmod 755 "$R/usr/local/libexec/mca-guest-test"
cat >"$U/mca-guest-test.service" <<END
[Unit]
Description=mca: mcad under systemd (tests/daemon/systemd_guest_checks.sh)
After=basic.target systemd-journald.service
[Service]
Type=oneshot
ExecStart=/usr/local/libexec/mca-guest-test
END
cat >"$U/mca-guest.target" <<END
[Unit]
Description=mca systemd guest test
Requires=basic.target mca-guest-test.service
After=basic.target
AllowIsolate=yes
END
ln -s mca-guest.target "$U/default.target"
job=$OUT/prepare.sh
cat >"$job" <<END
#!/bin/sh
# runs in the guest's overlay root (chroot) before systemd: lay $R over it
set -e
cp -a "$R/." /
# a virtual machine, not the container the host is (systemd would detect "docker" from this file)
rm -f /.dockerenv
echo "MCA-GUEST: root prepared, starting systemd at \$(cut -d' ' -f1 /proc/uptime) s"
END
MCA_GUEST_SYSTEMD=$OUT/results MCA_GUEST_LOG=$OUT/console.log \
    sh "$S/tools/vcan-guest/run.sh" "$B/vcan-guest-cache" "$job" 900 >/dev/null
rc=$?
cat "$OUT/results/result.txt" 2>/dev/null
if [ -e "/$marker" ]; then
    echo "FAIL the guest wrote /$marker on the host (the overlay root must keep the host read-only)"
    rm -f "/$marker"
    rc=1
else
    echo "ok   host untouched: the guest's /$marker stayed in its overlay"
fi
echo "systemd_guest: guest run $(($(date +%s) - t0)) s, exit $rc"
if [ ! -s "$OUT/results/result.txt" ]; then
    echo "systemd_guest: FAIL: the guest left no result (console: $OUT/console.log)"
    exit 1
fi
exit $rc
