#!/bin/bash
# SPDX-License-Identifier: MIT
# Bad cell files through the mcad binary, every kind daemon_cell (tests/daemon/test_cell.c) checks in the
# library: for each, both `mcad --check CELL` and `mcad CELL` must
#   - exit with status 2,
#   - print exactly one line on stderr, "<3>mcad: bad cell file: FILE:LINE[:COL]: FIELD: reason", whose
#     LINE is the line of the bad text (found here independently, with grep) and which names the field,
#   - start nothing: no other stderr line (no "cell ... arms", "ready", "running"), nothing on stdout.
# The good cell is test_cell.c's (a sim arm and a socketcan arm, inline task); each variant replaces one
# exact piece of it. Issue 16: the debug_* keys (test hooks) are bad cells for the production mcad; the
# test build MCAD_TEST (mcad-test) takes the same files. usage: test_bad_cell_cli.sh MCAD SOURCE_DIR [MCAD_TEST]
set -u
MCAD=$1 SRC=$2 MCAD_TEST=${3:-}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail=0 kinds=0

good="# test cell
name: cli-cell
task:
  duration: 3.5
scheme: mvn
d1: 0.04
d2: 0.15
solver:
  K: 12
  pdnn_max_steps: 321
arms:
  - name: left
    backend: sim
    urdf: $SRC/config/robots/pa10plus.urdf
    base_xyz: [0.0, -0.6, 0.1]
    base_rpy: [0.0, 0.0, 1.5]
    q0: [0.0, 0.3, 0.0, 0.8, 0.0, 0.5, 0.0, 0.0]
    dec_limit: 4.0
  - name: right
    backend: socketcan
    interface: vcan1
    id_base: 0x140
    urdf: $SRC/config/robots/pa10plus.urdf
    base_xyz: [0.0, 0.6, 0.0]
    q0: [0.1, 0.3, 0.0, 0.8, 0.0, 0.5, 0.0, 0.0]
    path: {kind: circle, radius: 0.1, period: 3.0, u: [1, 0, 0], v: [0, 0, 1]}
dds:
  enabled: false
  domain: 7
  publish_divisor: 4
rt:
  period_us: 2000
  priority: 70
  overrun_limit: 3
  lost_feedback_cycles: 6
stop_after: 1.5
"
printf '%s' "$good" > "$tmp/good.yaml"

# run_both NAME FILE LINE FIELD REASON: both modes, exit 2, the one message, nothing started
run_both() {
    local name=$1 file=$2 line=$3 field=$4 reason=$5 mode rc out bad=0
    kinds=$((kinds + 1))
    for mode in check run; do
        if [ $mode = check ]; then
            "$MCAD" --check "$file" > "$tmp/$name.$mode.out" 2> "$tmp/$name.$mode.err"
        else
            "$MCAD" --no-rt --stop-after 0.1 "$file" > "$tmp/$name.$mode.out" 2> "$tmp/$name.$mode.err"
        fi
        rc=$?
        local why=""
        [ $rc -eq 2 ] || why="exit status $rc, not 2"
        [ "$(wc -l < "$tmp/$name.$mode.err")" -eq 1 ] || why="$why; stderr has $(wc -l < "$tmp/$name.$mode.err") lines (something started?)"
        [ -s "$tmp/$name.$mode.out" ] && why="$why; stdout not empty"
        out=$(head -n 1 "$tmp/$name.$mode.err")
        case "$out" in
        "<3>mcad: bad cell file: $file:$line:"*) ;;
        *) why="$why; does not start with '<3>mcad: bad cell file: $file:$line:'" ;;
        esac
        [[ "$out" == *"$field"* ]] || why="$why; field '$field' not named"
        [[ "$out" == *"$reason"* ]] || why="$why; reason '$reason' missing"
        if [ -n "$why" ]; then
            echo "FAIL $name (mcad ${mode/check/--check}): ${why#; }"
            cat "$tmp/$name.$mode.out" "$tmp/$name.$mode.err"
            fail=1 bad=1
        fi
    done
    [ $bad -eq 1 ] || echo "ok   $name: $out"
}

# expect NAME FROM TO NEEDLE FIELD REASON [LINE_OFFSET]: the good cell with FROM replaced by TO; the
# message must name the line holding NEEDLE (plus LINE_OFFSET), FIELD and REASON
expect() {
    local name=$1 from=$2 to=$3 needle=$4 field=$5 reason=$6 off=${7:-0}
    [[ "$good" == *"$from"* ]] || { echo "FAIL $name: test bug, '$from' not in the good cell"; fail=1; return; }
    printf '%s' "${good/"$from"/"$to"}" > "$tmp/$name.yaml"
    local line
    line=$(grep -nF -m 1 -- "$needle" "$tmp/$name.yaml" | cut -d: -f1)
    [ -n "$line" ] || { echo "FAIL $name: test bug, '$needle' not in the variant"; fail=1; return; }
    run_both "$name" "$tmp/$name.yaml" $((line + off)) "$field" "$reason"
}

NL=$'\n'
URDF="$SRC/config/robots/pa10plus.urdf"
run_both missing_file "$tmp/no-such-cell.yaml" 0 "" "cannot open cell file"
# an empty or comment-only cell, or a cell whose scenario file is so: named, not a NULL dereference
: > "$tmp/empty.yaml"
run_both empty_cell "$tmp/empty.yaml" 0 "(document)" "empty document"
printf '# nothing but comments\n\n   # and blank lines\n' > "$tmp/comments.yaml"
run_both comment_only_cell "$tmp/comments.yaml" 0 "(document)" "empty document"
: > "$tmp/empty_scn.yaml"
expect empty_scenario "  duration: 3.5$NL" "  scenario: empty_scn.yaml$NL" "scenario: empty_scn" "task.scenario" \
    "$tmp/empty_scn.yaml:0: (document): empty document"
printf '# a scenario\n# still to be written\n' > "$tmp/comments_scn.yaml"
expect comment_only_scenario "  duration: 3.5$NL" "  scenario: comments_scn.yaml$NL" "scenario: comments_scn" \
    "task.scenario" "$tmp/comments_scn.yaml:0: (document): empty document"
expect yaml_syntax "[0.0, 0.6, 0.0]" "[0.0, 0.6, 0.0" "[0.0, 0.6, 0.0" "arms[1].base_xyz" "did not find expected"
expect wrong_type "priority: 70" "priority: high" "priority: high" "rt.priority" "Invalid INT value: 'high'"
expect wrong_type_in_arm "dec_limit: 4.0" "dec_limit: fast" "dec_limit: fast" "arms[0].dec_limit" "Invalid FLOAT value"
expect unknown_key "    dec_limit: 4.0$NL" "    dec_limit: 4.0$NL    colour: red$NL" "colour: red" \
    "arms[0].colour" "Unexpected key: colour"
expect unknown_top_key "stop_after: 1.5" "stop_afterwards: 1.5" "stop_afterwards" "stop_afterwards" "Unexpected key"
expect missing_required "  - name: left$NL    backend: sim$NL" "  - name: left$NL" "- name: left" \
    "arms[0].backend" "Missing required mapping field"
expect d1_ge_d2 "d1: 0.04" "d1: 0.15" "d1: 0.15" "d1/d2" "need 0 <= d1 < d2 (got d1 = 0.15, d2 = 0.15)"
expect missing_urdf "$URDF${NL}    base_xyz: [0.0, 0.6" "/nonexistent/pa11.urdf${NL}    base_xyz: [0.0, 0.6" \
    "pa11.urdf" "arms[1].urdf" "file '/nonexistent/pa11.urdf' not found"
expect unknown_backend "backend: socketcan" "backend: ethercat" "ethercat" "arms[1].backend" \
    "unknown backend 'ethercat' (known: sim, socketcan, canopen, replay)"
expect dof_mismatch "q0: [0.0, 0.3, 0.0, 0.8, 0.0, 0.5, 0.0, 0.0]" "q0: [0.0, 0.3, 0.0]" "q0: [0.0, 0.3, 0.0]" \
    "arms[0].q0" "3 values but"
expect q0_outside_limits "q0: [0.1, 0.3," "q0: [9.0, 0.3," "q0: [9.0" "arms[1].q0[0]: 9" "outside joint"
expect negative_period "period_us: 2000" "period_us: -1000" "period_us" "rt.period_us" "must be in 100..100000 us (got -1000)"
expect zero_period "period_us: 2000" "period_us: 0" "period_us" "rt.period_us" "must be in 100..100000 us (got 0)"
expect bad_priority "priority: 70" "priority: 150" "priority: 150" "rt.priority" "must be in 0..99"
expect scenario_missing "  duration: 3.5$NL" "  scenario: gone/cross.yaml$NL" "scenario: gone" "task.scenario" \
    "gone/cross.yaml' not found"
# a missing field names its enclosing mapping's line: the arm's entry
expect socketcan_no_interface "    interface: vcan1$NL" "" "- name: right" "arms[1].interface" \
    "required with backend socketcan"
expect dds_config_missing "  domain: 7$NL" "  domain: 7$NL  config: nowhere/cyclone.xml$NL" "config: nowhere" \
    "dds.config" "nowhere/cyclone.xml' not found"
expect unknown_scheme "scheme: mvn" "scheme: magic" "scheme: magic" "scheme" "unknown scheme 'magic' (known: mca-ts, mca, mvn, apf)"
# a URDF nested 50 000 deep would overflow the stack in TinyXML's recursive parser
{ printf '<?xml version="1.0"?>\n<robot name="deep">\n'; for ((i = 0; i < 50000; i++)); do printf '<a>'; done; } \
    > "$tmp/deep.urdf"
expect deep_urdf "$URDF${NL}    base_xyz: [0.0, -0.6" "$tmp/deep.urdf${NL}    base_xyz: [0.0, -0.6" "deep.urdf" \
    "arms[0].urdf" "deep.urdf: line 3: elements nested deeper than 256 levels"
# lines over 1023 characters (a reader that fgets would split them) must not shift the reported line numbers
long="# $(printf 'x%.0s' {1..3000})"
expect long_line_before_range_error "rt:$NL  period_us: 2000" "$long${NL}rt:$NL  period_us: -1000" "period_us: -1000" \
    "rt.period_us" "(got -1000)"
expect long_line_before_parse_error "rt:$NL  period_us: 2000$NL  priority: 70" \
    "$long${NL}rt:$NL  period_us: 2000$NL$long$NL  priority: high" "priority: high" "rt.priority" "Invalid INT value"
expect long_line_before_unknown_key "stop_after: 1.5" "$long${NL}$long${NL}stop_afterwards: 1.5" "stop_afterwards" \
    "stop_afterwards" "Unexpected key"
expect duplicate_arm "  - name: right" "  - name: left" "backend: socketcan" "arms[1].name" "'left' used twice" -1

# every number has a range a real cell can need (docs/daemon.md); out of it, the field, the line
# and the range are named and nothing starts
expect lost_feedback_huge "lost_feedback_cycles: 6" "lost_feedback_cycles: 2147483647" "lost_feedback_cycles" \
    "rt.lost_feedback_cycles" "must be in 1..1000 cycles (got 2147483647)"
expect lost_feedback_too_long "lost_feedback_cycles: 6" "lost_feedback_cycles: 600" "lost_feedback_cycles" \
    "rt.lost_feedback_cycles" "600 cycles of 0.002 s are 1.2 s without feedback, more than 1 s"
expect lost_feedback_zero "lost_feedback_cycles: 6" "lost_feedback_cycles: 0" "lost_feedback_cycles" \
    "rt.lost_feedback_cycles" "must be in 1..1000 cycles (got 0)"
expect overrun_huge "overrun_limit: 3" "overrun_limit: 2147483647" "overrun_limit" "rt.overrun_limit" \
    "must be in 1..3600000 periods (got 2147483647)"
expect overrun_too_long "overrun_limit: 3" "overrun_limit: 2000000" "overrun_limit" "rt.overrun_limit" \
    "2000000 periods of 0.002 s are 4000 s of overruns, more than 3600 s"
expect pdnn_budget_zero "overrun_limit: 3" "overrun_limit: 3${NL}  pdnn_budget_us: 0" "pdnn_budget_us" \
    "rt.pdnn_budget_us" "must be in 10..1000000 us (got 0)"
expect pdnn_budget_huge "overrun_limit: 3" "overrun_limit: 3${NL}  pdnn_budget_us: 5000000" "pdnn_budget_us" \
    "rt.pdnn_budget_us" "must be in 10..1000000 us (got 5000000)"
expect period_too_short "period_us: 2000" "period_us: 10" "period_us" "rt.period_us" "must be in 100..100000 us (got 10)"
expect solver_K_huge "K: 12" "K: 1e308" "K: 1e308" "solver.K" "must be in [0, 1000] 1/s (got 1e+308)"
expect solver_v_normal_huge "  K: 12$NL" "  K: 12$NL  v_normal: 1e308$NL" "v_normal" "solver.v_normal" \
    "must be in (0, 10] m/s (got 1e+308)"
expect solver_epsilon_huge "  K: 12$NL" "  K: 12$NL  epsilon: 1e308$NL" "epsilon" "solver.epsilon" \
    "must be in (0, 1000] 1/s (got 1e+308)"
expect pdnn_max_steps_huge "pdnn_max_steps: 321" "pdnn_max_steps: 2147483647" "pdnn_max_steps" \
    "solver.pdnn_max_steps" "must be in 1..20000 steps (got 2147483647)"
expect pdnn_tol_huge "  K: 12$NL" "  K: 12$NL  pdnn_tol: 5$NL" "pdnn_tol" "solver.pdnn_tol" "must be in (0, 0.01] (got 5)"
expect deadlock_time_huge "  K: 12$NL" "  K: 12$NL  deadlock_time: 1e9$NL" "deadlock_time" "solver.deadlock_time" \
    "must be in (0, 60] s (got 1000000000)"
expect base_xyz_huge "[0.0, -0.6, 0.1]" "[1e308, -0.6, 0.1]" "1e308" "arms[0].base_xyz[0]" \
    "must be in [-100, 100] m (got 1e+308)"
expect base_rpy_huge "[0.0, 0.0, 1.5]" "[0.0, 0.0, 150]" "[0.0, 0.0, 150]" "arms[0].base_rpy[2]" \
    "must be in [-6.28319, 6.28319] rad (got 150)"
expect dec_limit_tiny "dec_limit: 4.0" "dec_limit: 1e-12" "dec_limit" "arms[0].dec_limit" \
    "must be in [0.05, 100] rad/s^2 (got 1e-12)"
expect dec_limit_huge "dec_limit: 4.0" "dec_limit: 1e6" "dec_limit" "arms[0].dec_limit" \
    "must be in [0.05, 100] rad/s^2 (got 1000000)"
# a stop lasts at most 60 s: 0.05 rad/s^2 from a joint's velocity limit of 10 rad/s would take 200 s
sed 's/velocity="[^"]*"/velocity="10"/' "$URDF" > "$tmp/fast.urdf"
expect dec_limit_slow_stop "$URDF${NL}    base_xyz: [0.0, -0.6, 0.1]${NL}    base_rpy: [0.0, 0.0, 1.5]${NL}    q0: [0.0, 0.3, 0.0, 0.8, 0.0, 0.5, 0.0, 0.0]${NL}    dec_limit: 4.0" \
    "$tmp/fast.urdf${NL}    base_xyz: [0.0, -0.6, 0.1]${NL}    base_rpy: [0.0, 0.0, 1.5]${NL}    q0: [0.0, 0.3, 0.0, 0.8, 0.0, 0.5, 0.0, 0.0]${NL}    dec_limit: 0.05" \
    "dec_limit: 0.05" "arms[0].dec_limit" "0.05 rad/s^2 brakes joint 'S1' from its velocity limit 10 rad/s in 200 s, more than 60 s"
expect arm_priority_huge "    dec_limit: 4.0$NL" "    dec_limit: 4.0$NL    priority: 1e308$NL" "priority: 1e308" \
    "arms[0].priority" "must be in (0, 1000] (got 1e+308)"
expect noise_huge "    dec_limit: 4.0$NL" "    dec_limit: 4.0$NL    sim: {noise_pos: 5}$NL" "noise_pos" \
    "arms[0].sim.noise_pos" "must be in [0, 0.1] rad (got 5)"
sed '0,/velocity="[^"]*"/s//velocity="1e300"/' "$URDF" > "$tmp/velocity.urdf"
vline=$(grep -n -m 1 'velocity="1e300"' "$tmp/velocity.urdf" | cut -d: -f1)
jline=$(head -n "$vline" "$tmp/velocity.urdf" | grep -n '<joint' | tail -n 1 | cut -d: -f1)
expect urdf_velocity_huge "$URDF${NL}    base_xyz: [0.0, -0.6" "$tmp/velocity.urdf${NL}    base_xyz: [0.0, -0.6" "velocity.urdf" \
    "arms[0].urdf" "velocity.urdf: line $jline: joint 'S1': <limit velocity> must be in (0, 100] rad/s (got 1e+300)"
# two socketcan arms on one bus with one id block: the second is refused at its id_base
expect same_can_ids "    backend: sim$NL    urdf: $URDF" "    backend: socketcan$NL    interface: vcan1$NL    id_base: 0x140$NL    urdf: $URDF" \
    "q0: [0.1, 0.3" "arms[1].id_base" "0x140 on vcan1 is already arms[0]'s" -3
expect d2_huge "d2: 0.15" "d2: 1e308" "d2: 1e308" "d2" "must be in (0, 2] m (got 1e+308)"
expect duration_huge "duration: 3.5" "duration: 1e7" "duration: 1e7" "task.duration" "must be in (0, 3600] s (got 10000000)"
expect stop_after_huge "stop_after: 1.5" "stop_after: 1e9" "stop_after: 1e9" "stop_after" \
    "must be in [0, 86400] s (got 1000000000)"
expect path_radius_huge "radius: 0.1" "radius: 1e308" "radius: 1e308" "arms[1].path.radius" \
    "must be in (0, 10] m (got 1e+308)"
# the tick count at the cell's period: 3000 s at 100 us are 30 million ticks
good_saved=$good
good=${good/period_us: 2000/period_us: 100}
expect ticks_too_many "duration: 3.5" "duration: 3000" "duration: 3000" "task.duration" \
    "3000 s at a tick of 0.0001 s is 30000000 ticks, more than 3600000"
good=$good_saved
# a scenario's own range error, through the cell
sed -e 's/^duration: .*/duration: 1e7/' -e "s|\.\./robots/|$SRC/config/robots/|" "$SRC/config/scenarios/cross_circles.yaml" \
    > "$tmp/long_scn.yaml"
dline=$(grep -n '^duration:' "$tmp/long_scn.yaml" | cut -d: -f1)
expect scenario_duration_huge "  duration: 3.5$NL" "  scenario: long_scn.yaml$NL" "scenario: long_scn" "task.scenario" \
    "long_scn.yaml:$dline: duration: must be in (0, 3600] s (got 10000000)"
# production holds no test hooks. Each debug_* key, whatever its value, is refused by mcad at its
# line; the test build (mcad-test) checks the same file without complaint.
for hook in "debug_kill_after_ticks: 1500" "debug_kill_after_ticks: 0" "debug_stall_after_ticks: 400" \
    "debug_start_in_fault: true"; do
    key=${hook%%:*}
    expect "hook_${key}_${hook##* }" "stop_after: 1.5" "stop_after: 1.5$NL$hook   # a test hook" "$key:" "$key" \
        "$key: test hook: this mcad is the production build, which takes no debug_* keys"
    if [ -n "$MCAD_TEST" ]; then
        if "$MCAD_TEST" --check "$tmp/hook_${key}_${hook##* }.yaml" > "$tmp/hook_test.out" 2>&1; then
            echo "ok   mcad-test --check takes '$hook'"
        else
            echo "FAIL: mcad-test --check rejects '$hook':"; cat "$tmp/hook_test.out"; fail=1
        fi
    fi
done
# in range: two socketcan arms with one id block on different buses
printf '%s' "${good/"    backend: sim$NL"/"    backend: socketcan$NL    interface: vcan0$NL    id_base: 0x140$NL"}" > "$tmp/two_buses.yaml"
if ! "$MCAD" --check "$tmp/two_buses.yaml" > "$tmp/two_buses.out" 2>&1; then
    echo "FAIL: two socketcan arms, one id block on two buses, rejected:"; cat "$tmp/two_buses.out"; fail=1
fi

# usage: a --histogram path that cannot be written is refused before anything starts (exit 2, one line
# naming the path, no file left)
"$MCAD" --no-rt --histogram "$tmp/no/such/dir/h.txt" "$tmp/good.yaml" > "$tmp/hist.out" 2> "$tmp/hist.err"
rc=$?
want="<3>mcad: --histogram: cannot open '$tmp/no/such/dir/h.txt' for writing: No such file or directory"
if [ $rc -eq 2 ] && [ "$(cat "$tmp/hist.err")" = "$want" ] && [ ! -s "$tmp/hist.out" ]; then
    echo "ok   --histogram into a missing folder: exit 2, one line, nothing started"
else
    echo "FAIL: --histogram into a missing folder: exit $rc, stderr:"; cat "$tmp/hist.err"; fail=1
fi

# the good cell itself passes the check (so the failures above are the variants')
if ! "$MCAD" --check "$tmp/good.yaml" > "$tmp/good.out" 2>&1; then
    echo "FAIL: good cell rejected:"; cat "$tmp/good.out"; fail=1
fi
echo "$kinds kinds of bad cell, each through mcad --check and mcad"
exit $fail
