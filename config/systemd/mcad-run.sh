#!/bin/sh
# Start mcad as a transient systemd service with the settings of mcad@.service (no unit file needed).
# usage: config/systemd/mcad-run.sh MCAD CELL [UNIT]     e.g. build/daemon/mcad config/cells/cross_circles_sim.yaml
# Stop (brakes to zero first): systemctl stop UNIT.   Status: systemctl status UNIT (STATUS= lines).
set -eu
MCAD=$(readlink -f "$1")
CELL=$(readlink -f "$2")
UNIT=${3:-mcad-$(basename "$CELL" .yaml | tr '_' '-')}
exec systemd-run --unit="$UNIT" \
    -p Type=notify -p NotifyAccess=main \
    -p WatchdogSec=2s -p TimeoutStartSec=30s -p TimeoutStopSec=10s -p KillSignal=SIGTERM -p Restart=no \
    -p CPUSchedulingPolicy=fifo -p CPUSchedulingPriority=1 -p LimitRTPRIO=99 \
    -p LimitMEMLOCK=infinity \
    -p NoNewPrivileges=yes -p ProtectSystem=full \
    -p "RestrictAddressFamilies=AF_UNIX AF_INET AF_INET6 AF_NETLINK AF_CAN" \
    "$MCAD" "$CELL"
# As mcad@.service, but without PrivateTmp= and ProtectHome=: a trial run's cell, CSV or build tree often
# lives under /tmp or a home directory, which those would hide or make read-only.
