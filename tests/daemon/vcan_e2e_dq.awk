# SPDX-License-Identifier: MIT
# vcan_e2e.sh phase A: max |dq| per arm between two CSVs with the q<arm>_<joint> columns of mca-sim/mcad,
# matched by tick (round(t / 1 ms)). First file: the reference (mca-sim, sim backend); second: mcad's
# --csv over SocketCAN, compared on its running rows (state 2) only.
# usage: awk -F, -f vcan_e2e_dq.awk REF.csv MCAD.csv
# prints: ok n_compared n_missing max0 tick0 joint0 max1 tick1 joint1 (joints 0-based within the arm)
FNR == 1 {
    for (i = 1; i <= NF; i++) {
        if ($i ~ /^q[0-9]+_[0-9]+$/) {
            split(substr($i, 2), p, "_")
            if (NR == 1) { rc[i] = p[1]; rj[i] = p[2] } else { cc[i] = p[1]; cj[i] = p[2]; col[p[1], p[2]] = i }
        }
        if (NR != 1 && $i == "state") cs = i
    }
    if (NR == 1) for (i in rc) rcol[rc[i], rj[i]] = i
    next
}
NR == FNR { k = int($1 * 1000 + 0.5); for (i in rc) r[k, rc[i], rj[i]] = $i; have[k] = 1; next }
{
    if (cs && $cs != 2) next
    k = int($1 * 1000 + 0.5)
    if (!(k in have)) { miss++; next }
    n++
    for (i in cc) {
        a = cc[i]; j = cj[i]
        x = $i - r[k, a, j]; if (x < 0) x = -x
        if (x > m[a] || !(a in m)) { m[a] = x; mk[a] = k; mj[a] = j }
    }
}
END {
    printf "%d %d %d", (n > 0), n + 0, miss + 0
    for (a = 0; a < 2; a++) printf " %.2e %d %d", m[a], mk[a], mj[a]
    printf "\n"
}
