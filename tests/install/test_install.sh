#!/bin/sh
# SPDX-License-Identifier: MIT
# cmake --install into a fresh prefix, then what a user and an outside project do with it:
# the files where FHS puts them, the unit with the prefix's paths, the installed mcad checking an installed
# cell that reaches the shared scenarios and robots through the search path, and an outside CMake project
# that finds the package (find_package(mca)), builds against the installed headers and static libraries
# and runs. The install is relocatable: the installed mcad, without MCA_PATH, finds its files and its DDS
# publisher relative to its own executable and runs a cell with DDS on.
# usage: test_install.sh BUILD_DIR SOURCE_DIR
set -eu
B=$(cd "$1" && pwd)
S=$(cd "$2" && pwd)
T=$(mktemp -d /tmp/mca-install-XXXXXX)
trap 'rm -rf "$T"' EXIT
P=$T/prefix
fail=0
check() { # check DESCRIPTION COMMAND...
    d=$1
    shift
    if "$@" >/dev/null 2>&1; then echo "ok   $d"; else echo "FAIL $d"; fail=1; fi
}
cmake --install "$B" --prefix "$P" >"$T/install.log" 2>&1 || { cat "$T/install.log"; echo "FAIL cmake --install"; exit 1; }
echo "installed $(find "$P" -type f | wc -l) files under $P"
check "sbin/mcad" test -x "$P/sbin/mcad"
check "bin/mca-sim, bin/mca-monitor, bin/mca-record, bin/mca-geom" test -x "$P/bin/mca-sim" -a -x "$P/bin/mca-monitor" -a -x "$P/bin/mca-record" -a -x "$P/bin/mca-geom"
check "libexec/mca/mca-dds-bridge (mcad's DDS publisher process)" test -x "$P/libexec/mca/mca-dds-bridge"
check "no test build installed (mcad-test)" test ! -e "$P/sbin/mcad-test" -a ! -e "$P/bin/mcad-test"
check "include/mca/controller.h, dds_bridge.h, ros2.h" test -f "$P/include/mca/controller.h" -a -f "$P/include/mca/dds_bridge.h" -a -f "$P/include/mca/ros2.h"
check "no test-only header (daemon_test.h)" test ! -e "$P/include/mca/daemon_test.h"
check "lib*/libmca_core.a, libmca_model.a and the CMake package" sh -c "ls $P/lib*/libmca_core.a $P/lib*/libmca_model.a $P/lib*/cmake/mca/mcaConfig.cmake"
check "include/mca/path.h (core), scenario.h, urdf.h, qp_dump.h (model)" test -f "$P/include/mca/path.h" -a -f "$P/include/mca/scenario.h" -a -f "$P/include/mca/urdf.h" -a -f "$P/include/mca/qp_dump.h"
# the exported real-time core carries none of the loaders' dependencies (an RT user links no YAML or URDF parser); mca::model brings them
core_links() {
    b=$(sed -n '/^set_target_properties(mca::core /,/^)/p' "$P"/lib*/cmake/mca/mcaTargets.cmake)
    m=$(sed -n '/^set_target_properties(mca::model /,/^)/p' "$P"/lib*/cmake/mca/mcaTargets.cmake)
    g=$(sed -n '/^set_target_properties(mca::geom /,/^)/p' "$P"/lib*/cmake/mca/mcaTargets.cmake)
    y=$(sed -n '/^set_target_properties(mca::body /,/^)/p' "$P"/lib*/cmake/mca/mcaTargets.cmake)
    echo "$b" | grep -q 'INTERFACE_LINK_LIBRARIES' && ! echo "$b" | grep -qi 'cyaml\|urdf\|Threads\|ccd' &&
        echo "$m" | grep -q 'INTERFACE_LINK_LIBRARIES.*mca::core.*CYAML.*urdfdom' &&
        echo "$g" | grep -q 'INTERFACE_LINK_LIBRARIES.*mca::core.*ccd' &&
        echo "$y" | grep -q 'INTERFACE_LINK_LIBRARIES.*mca::core' && ! echo "$y" | grep -qi 'ccd'
}
check "mca::core links no libcyaml, urdfdom, Threads or libccd; mca::model links mca::core, libcyaml, urdfdom; mca::geom mca::core, libccd; mca::body mca::core and no libccd" core_links
check "etc/mca/cells, etc/mca/dds" test -f "$P/etc/mca/cells/cup_stacking_sim.yaml" -a -f "$P/etc/mca/dds/loopback.xml"
check "share/mca/robots, scenarios, ros2" test -f "$P/share/mca/robots/jaco2.urdf" -a -f "$P/share/mca/scenarios/cup_stacking.yaml" -a -f "$P/share/mca/ros2/mca.rviz"
check "share/doc/mca" test -f "$P/share/doc/mca/daemon.md"
check "etc/mca/dds/secure.xml; share/mca/security/make_security.sh makes the signed files from the installed templates" \
    sh -c "test -f $P/etc/mca/dds/secure.xml && $P/share/mca/security/make_security.sh $T/sec && test -s $T/sec/permissions.p7s -a -s $T/sec/governance_open.p7s -a -s $T/sec/mcad/cert.pem"
check "lib/systemd/system/mcad@.service" test -f "$P/lib/systemd/system/mcad@.service"
# the unit names the paths of the build's install prefix (the --prefix here only moves the files)
prefix=$(sed -n 's/^CMAKE_INSTALL_PREFIX:PATH=//p' "$B/CMakeCache.txt")
check "the unit starts $prefix/sbin/mcad" grep -q "^ExecStart=$prefix/sbin/mcad " "$P/lib/systemd/system/mcad@.service"
# an installed cell in etc/mca/cells names ../scenarios/...: found in share/mca by the search path
if MCA_PATH="$P/etc/mca:$P/share/mca" "$P/sbin/mcad" --check "$P/etc/mca/cells/cup_stacking_sim.yaml" >"$T/check.log" 2>&1 &&
    grep -q "$P/share/mca/scenarios/../robots/jaco2.urdf\|$P/share/mca/robots/jaco2.urdf" "$T/check.log"; then
    echo "ok   installed mcad --check installed cell (scenario and robots from share/mca)"
else
    cat "$T/check.log"
    echo "FAIL installed mcad --check installed cell"
    fail=1
fi
# relocatable: without MCA_PATH the installed mcad finds the cell's scenario and robots through its own prefix
# (P/sbin/mcad -> P/etc/mca, P/share/mca; not the build's configured prefix) ...
if env -u MCA_PATH "$P/sbin/mcad" --check "$P/etc/mca/cells/cross_circles_sim.yaml" >"$T/reloc.log" 2>&1 &&
    grep -q "$P/share/mca/scenarios/" "$T/reloc.log"; then
    echo "ok   installed mcad --check without MCA_PATH: scenario from its own prefix's share/mca"
else
    cat "$T/reloc.log"
    echo "FAIL installed mcad --check without MCA_PATH (search path relative to the executable)"
    fail=1
fi
# ... and runs the cell with DDS on, its publisher started from P/libexec/mca (not next to mcad, not the
# configured prefix's libexec/mca)
if env -u MCA_PATH "$P/sbin/mcad" --no-rt --stop-after 1 "$P/etc/mca/cells/cross_circles_sim.yaml" \
    >"$T/run.log" 2>&1 &&
    grep -q "dds bridge: pid [0-9]* ($P/libexec/mca/mca-dds-bridge)" "$T/run.log" &&
    grep -q "summary: state stopped" "$T/run.log" && grep -q "summary: faults: none" "$T/run.log" &&
    ! grep -q "^<[0-3]>" "$T/run.log"; then
    echo "ok   installed mcad runs an installed cell from its prefix with DDS on (bridge from P/libexec/mca), exit 0"
else
    tail -30 "$T/run.log"
    echo "FAIL installed mcad run from its prefix with DDS on"
    fail=1
fi
# an outside project
if cmake -S "$S/tests/install/consumer" -B "$T/consumer" -DCMAKE_PREFIX_PATH="$P" >"$T/consumer.log" 2>&1 &&
    cmake --build "$T/consumer" >>"$T/consumer.log" 2>&1 &&
    "$T/consumer/consumer" "$P/share/mca/robots/jaco2.urdf" "$P/share/mca/scenarios/cup_stacking.yaml" \
        >>"$T/consumer.log" 2>&1 &&
    tail -1 "$T/consumer.log" | grep -q "^consumer: ok: .* 20 ticks of 2 arms"; then
    echo "ok   outside project: find_package(mca), mca::model (URDF, scenario) + mca::core (ticks) + mca::dds, built and ran: $(tail -1 "$T/consumer.log")"
else
    tail -30 "$T/consumer.log"
    echo "FAIL outside project with find_package(mca)"
    fail=1
fi
[ $fail -eq 0 ] && echo PASSED || echo FAILED
exit $fail
