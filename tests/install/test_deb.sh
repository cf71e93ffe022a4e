#!/bin/sh
# SPDX-License-Identifier: MIT
# The Debian package: build it from the tree (tools/deb/build_deb.sh: its own configure with the
# prefix /usr, in BUILD_DIR/deb-build), check its control data and contents, unpack it into a scratch root
# (dpkg -x), run the unpacked mcad --check on every unpacked cell, have systemd-analyze verify the unit's
# instance mcad@cross_circles_sim, and run one whole sim cell from the unpacked tree the way the packaged unit
# does: its ExecStart line, with %i = cross_circles_sim.
# The whole run happens in a private mount and network namespace (unshare) where the package's /usr and
# /etc are laid over the real ones (read-only overlayfs): the unit's /usr/sbin/mcad and
# /etc/mca/cells/cross_circles_sim.yaml are then the package's files, mcad finds the scenario and the robots
# through its compiled-in search path and its DDS publisher in its compiled-in libexec folder, and DDS stays
# on the namespace's own loopback. Nothing outside the scratch root and BUILD_DIR/deb-build is written.
# usage: test_deb.sh BUILD_DIR SOURCE_DIR
set -eu
B=$(cd "$1" && pwd)
S=$(cd "$2" && pwd)
T=$(mktemp -d /tmp/mca-deb-XXXXXX)
trap 'rm -rf "$T"' EXIT
R=$T/root
fail=0
ok() { echo "ok   $1"; }
bad() { echo "FAIL $1"; fail=1; }
check() { # check DESCRIPTION COMMAND...
    d=$1
    shift
    if "$@" >/dev/null 2>&1; then ok "$d"; else bad "$d"; fi
}
t0=$(date +%s)
DEB=$(sh "$S/tools/deb/build_deb.sh" "$S" "$B/deb-build") || { echo "$DEB"; echo "FAIL building the package"; exit 1; }
[ -f "$DEB" ] || { echo "$DEB"; echo "FAIL no .deb"; exit 1; }
echo "built $(basename "$DEB") ($(du -k "$DEB" | cut -f1) kB) in $(($(date +%s) - t0)) s"

# control data
dpkg-deb --info "$DEB" >"$T/info"
field() { sed -n "s/^ $1: //p" "$T/info"; }
arch=$(dpkg --print-architecture)
check "Package: mca" test "$(field Package)" = mca
check "Version: $(field Version) (the project's, CMakeLists.txt)" \
    grep -q "^project(mca VERSION $(field Version) " "$S/CMakeLists.txt"
check "Architecture: $arch" test "$(field Architecture)" = "$arch"
check "Depends (dpkg-shlibdeps) names libc6, libcyaml1, libddsc0debian, libsystemd0: $(field Depends)" \
    sh -c "echo '$(field Depends)' | grep 'libc6' | grep 'libcyaml1' | grep 'libddsc0debian' | grep -q 'libsystemd0'"
check "Maintainer, Section, Description" test -n "$(field Maintainer)" -a -n "$(field Section)" -a -n "$(field Description)"

# contents
dpkg-deb --contents "$DEB" | awk '{print $6}' | sed 's|^\./|/|' >"$T/contents"
has() { grep -qx "$1" "$T/contents"; }
for f in /usr/sbin/mcad /usr/libexec/mca/mca-dds-bridge /usr/bin/mca-sim /usr/bin/mca-monitor /usr/bin/mca-record \
    /lib/systemd/system/mcad@.service /etc/mca/cells/cross_circles_sim.yaml /etc/mca/dds/loopback.xml \
    /usr/share/mca/robots/jaco2.urdf /usr/share/mca/scenarios/cross_circles.yaml /usr/include/mca/controller.h \
    /usr/share/doc/mca/daemon.md; do
    check "contains $f" has "$f"
done
check "no test build (mcad-test) and no test-only header (daemon_test.h)" sh -c "! grep -q 'mcad-test\|daemon_test.h' $T/contents"
check "nothing under /usr/etc, /usr/local or /usr/lib/systemd (FHS for a /usr package; Debian 12 units in /lib)" \
    sh -c "! grep -q '^/usr/etc\|^/usr/local\|^/usr/lib/systemd' $T/contents"
# every file in /etc is a dpkg conffile, and nothing else is
dpkg-deb --ctrl-tarfile "$DEB" | tar -xO ./conffiles >"$T/conffiles" 2>/dev/null || : >"$T/conffiles"
grep '^/etc/.*[^/]$' "$T/contents" | sort >"$T/etc-files"
check "conffiles: the $(wc -l <"$T/etc-files") files under /etc/mca, no others" sh -c "[ -s $T/etc-files ] && sort $T/conffiles | cmp -s - $T/etc-files"

# unpack into the scratch root
dpkg -x "$DEB" "$R"
U=$R/lib/systemd/system/mcad@.service
exec_start=$(sed -n 's/^ExecStart=//p' "$U")
check "the unit's ExecStart=$exec_start runs /usr/sbin/mcad on /etc/mca/cells/%i.yaml" \
    test "$exec_start" = "/usr/sbin/mcad /etc/mca/cells/%i.yaml"
doc=$(sed -n 's|^Documentation=file:||p' "$U")
check "the unit's Documentation=$doc is in the package" test -f "$R$doc"
check "the cell mcad@cross_circles_sim loads is in the package (etc/mca/cells/cross_circles_sim.yaml)" \
    test -f "$R/etc/mca/cells/cross_circles_sim.yaml"
check "mcad, mca-dds-bridge unpacked and executable" test -x "$R/usr/sbin/mcad" -a -x "$R/usr/libexec/mca/mca-dds-bridge"

# --check of every unpacked cell by the unpacked mcad, the shared files found through MCA_PATH in the scratch
# root. --check loads and checks the cell file only and opens no arm: the socketcan and canopen cells pass too
# without vcan0/vcan1 (they fail only when run).
n=0
for c in "$R"/etc/mca/cells/*.yaml; do
    [ -f "$c" ] || continue
    n=$((n + 1))
    name=$(basename "$c" .yaml)
    if MCA_PATH="$R/etc/mca:$R/usr/share/mca" "$R/usr/sbin/mcad" --check "$c" >"$T/check-$name.log" 2>&1 &&
        grep -q "^cell $name " "$T/check-$name.log" && grep -q "$R/usr/share/mca/.*\.urdf" "$T/check-$name.log"; then
        ok "mcad --check $name ($(grep -o 'backend [a-z]*' "$T/check-$name.log" | sort -u | tr '\n' ' ')from the scratch root)"
    else
        cat "$T/check-$name.log"
        bad "mcad --check $name"
    fi
done
check "$n installed cells checked (at least the 13 of config/cells)" test "$n" -ge "$(ls "$S"/config/cells/*.yaml | wc -l)" -a "$n" -gt 0

# one whole sim cell, as systemctl start mcad@cross_circles_sim would run it (ExecStart, %i substituted)
cmd=$(echo "$exec_start" | sed 's/%i/cross_circles_sim/g')
stop=$(printf '%.3f' "$(sed -n 's/^stop_after: *\([0-9.]*\).*/\1/p' "$R/etc/mca/cells/cross_circles_sim.yaml")")
u="unshare -mn"
[ "$(id -u)" = 0 ] || u="unshare -rmn" # not root: a user namespace as well
run_ns() { # run_ns COMMAND: in the namespace with the package's /usr and /etc laid over the real ones
    $u sh -c "ip link set lo up &&
        mount -t overlay mca-usr -o lowerdir=$R/usr:/usr /usr &&
        mount -t overlay mca-etc -o lowerdir=$R/etc:/etc /etc &&
        exec $1"
}
t1=$(date +%s)
if run_ns "test -x /usr/sbin/mcad -a -f /etc/mca/cells/cross_circles_sim.yaml" 2>/dev/null; then
    # systemd's own check of the instance: the unit's syntax and that its ExecStart is executable (outside
    # the namespace it is not: /usr/sbin/mcad exists only in the package)
    if command -v systemd-analyze >/dev/null; then
        if run_ns "env SYSTEMD_UNIT_PATH=$R/lib/systemd/system: systemd-analyze verify mcad@cross_circles_sim.service" \
            >"$T/verify.log" 2>&1 && ! grep -q . "$T/verify.log"; then
            ok "systemd-analyze verify mcad@cross_circles_sim.service over the unpacked package: no complaint"
        else
            cat "$T/verify.log"
            bad "systemd-analyze verify mcad@cross_circles_sim.service"
        fi
    else
        echo "note: no systemd-analyze here: the unit is not verified by systemd"
    fi
    run_ns "$cmd" >"$T/run.log" 2>&1 && rc=0 || rc=$?
    how="as the unit: $cmd, in a mount+network namespace over the unpacked package (DDS on its loopback)"
    grep -q "dds bridge: pid [0-9]* (/usr/libexec/mca/mca-dds-bridge)" "$T/run.log" ||
        { rc=${rc}-no-bridge; echo "no DDS publisher /usr/libexec/mca/mca-dds-bridge in the log"; }
else
    # no namespaces here: the unpacked mcad, MCA_PATH into the scratch root, no DDS (mcad looks for its
    # publisher in /usr/libexec/mca, which is not in the scratch root)
    MCA_PATH="$R/etc/mca:$R/usr/share/mca" "$R/usr/sbin/mcad" --no-dds "$R/etc/mca/cells/cross_circles_sim.yaml" \
        >"$T/run.log" 2>&1 && rc=0 || rc=$?
    how="the unpacked mcad with MCA_PATH into the scratch root and --no-dds (no namespaces available)"
fi
if [ "$rc" = 0 ] && grep -q "summary: state stopped," "$T/run.log" && grep -q "summary: faults: none" "$T/run.log" &&
    grep -q "stop requested at t = $stop s" "$T/run.log" && ! grep -q '^<[0-3]>' "$T/run.log"; then
    ok "whole cell cross_circles_sim ($(($(date +%s) - t1)) s) $how: exit 0, $(grep -o 'state stopped, ticks [0-9]*' "$T/run.log"), stopped at its stop_after $stop s, faults none, $(grep -o 'minimum distance [0-9.]* m' "$T/run.log")"
else
    cat "$T/run.log"
    bad "whole cell cross_circles_sim (exit $rc) $how"
fi
echo "total $(($(date +%s) - t0)) s"
[ $fail -eq 0 ] && echo PASSED || echo FAILED
exit $fail
