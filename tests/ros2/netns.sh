#!/bin/sh
# SPDX-License-Identifier: MIT
# Run a command in a network namespace of its own that has only lo, with multicast on: the ROS 2 tests'
# DDS traffic (Cyclone and Fast DDS both discover by multicast) stays inside it, and parallel tests or
# other DDS programs on the machine neither see it nor disturb it.
# usage: netns.sh COMMAND [ARG...]
if [ "$(id -u)" != 0 ]; then
    echo "SKIP: a network namespace needs root (unshare -n)"
    exit 77
fi
exec unshare -n sh -c 'ip link set lo up && ip link set lo multicast on && ip route add 224.0.0.0/4 dev lo &&
exec "$@"' netns.sh "$@"
