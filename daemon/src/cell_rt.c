/* SPDX-License-Identifier: MIT */
/* The cell's real-time section: the loop's period, priority, CPU and limits, and the task's tick count at
 * that period (see cell__load.h). Start-up only. */
#include <math.h>
#include <stdio.h>
#include <unistd.h>

#include "mca/err.h"
#include "mca/errbuf.h" /* mca_errbuf_at */
#include "mca/scenario.h"
#include "mca/yaml_marks.h"

#include "cell__load.h"

static const mca_range_t r_rt_priority = {"priority", 0, 99, 0, 1, "(0 = SCHED_OTHER)"};
/* overruns: real arms need 3-10; arms in virtual time (the sim backend, lockstep emulators on an emulated
 * CPU) tolerate any stall, so up to the longest task's tick count (an hour of periods) */
static const mca_range_t r_overrun_limit = {"overrun_limit", 1, MCA_SCENARIO_MAX_TICKS, 0, 1, "periods"};
#define CELL_MAX_OVERRUN_S 3600.0
/* the PDNN's time per tick: from 10 us up to 1 s (an emulated CPU; a real loop wants half its period) */
static const mca_range_t r_pdnn_budget_us = {"pdnn_budget_us", 10, 1000000, 0, 1, "us"};
/* lost feedback: the arm is blind while these pass; at most 1000 cycles and 1 s */
static const mca_range_t r_lost_feedback_cycles = {"lost_feedback_cycles", 1, 1000, 0, 1, "cycles"};
#define CELL_MAX_LOST_FEEDBACK_S 1.0

int mcad_cell_read_rt(const mca_check_ctx_t ctx, const struct raw_cell *raw, mca_cell_t *cell) {
    int rc = MCA_OK;
    mca_scenario_t *scn = &cell->scn;
    /* real time */
    mca_cell_rt_t *rt = &cell->rt;
    rt->period_ns = 1000000;
    rt->priority = 80;
    rt->cpu = -1;
    rt->overrun_limit = 10;
    rt->lost_feedback_cycles = 10;
    rt->lock_memory = 1;
    rt->dma_latency = 1;
    if (raw->rt) {
        const struct raw_rt *r = raw->rt;
        if (r->period_us) {
            /* the loop period is the controller's dt: the scenario's dt range, in us */
            const mca_range_t *dt = mca_scenario_range("dt");
            const mca_range_t r_period_us = {"period_us", llround(dt->lo * 1e6), llround(dt->hi * 1e6), 0, 1,
                                             "us"};
            CHECK(&r_period_us, (double)*r->period_us, "rt.period_us");
            rt->period_ns = *r->period_us * 1000;
        }
        if (r->priority) {
            CHECK(&r_rt_priority, *r->priority, "rt.priority");
            rt->priority = *r->priority;
        }
        if (r->cpu) {
            const long ncpu = sysconf(_SC_NPROCESSORS_CONF);
            if (*r->cpu < -1 || (ncpu > 0 && *r->cpu >= ncpu)) {
                FAIL(MCA_ECONFIG, LINE("rt.cpu"), "rt.cpu: must be -1 (none) or 0..%ld (got %d)", ncpu - 1,
                     *r->cpu);
            }
            rt->cpu = *r->cpu;
        }
        const double period_s = (double)rt->period_ns * 1e-9;
        if (r->overrun_limit) {
            CHECK(&r_overrun_limit, *r->overrun_limit, "rt.overrun_limit");
            if (*r->overrun_limit * period_s > CELL_MAX_OVERRUN_S) {
                FAIL(MCA_ECONFIG, LINE("rt.overrun_limit"),
                     "rt.overrun_limit: %d periods of %g s are %g s of overruns, more than %g s",
                     *r->overrun_limit, period_s, *r->overrun_limit * period_s, CELL_MAX_OVERRUN_S);
            }
            rt->overrun_limit = *r->overrun_limit;
        }
        if (r->pdnn_budget_us) {
            CHECK(&r_pdnn_budget_us, (double)*r->pdnn_budget_us, "rt.pdnn_budget_us");
            rt->pdnn_budget_ns = *r->pdnn_budget_us * 1000;
        }
        if (r->lost_feedback_cycles) {
            CHECK(&r_lost_feedback_cycles, *r->lost_feedback_cycles, "rt.lost_feedback_cycles");
            if (*r->lost_feedback_cycles * period_s > CELL_MAX_LOST_FEEDBACK_S + 1e-12) {
                FAIL(MCA_ECONFIG, LINE("rt.lost_feedback_cycles"),
                     "rt.lost_feedback_cycles: %d cycles of %g s are %g s without feedback, more than %g s",
                     *r->lost_feedback_cycles, period_s, *r->lost_feedback_cycles * period_s,
                     CELL_MAX_LOST_FEEDBACK_S);
            }
            rt->lost_feedback_cycles = *r->lost_feedback_cycles;
        }
        if (r->lock_memory) {
            rt->lock_memory = *r->lock_memory;
        }
        if (r->dma_latency) {
            rt->dma_latency = *r->dma_latency;
        }
    }
    if (rt->pdnn_budget_ns == 0) {
        rt->pdnn_budget_ns = rt->period_ns / 2; /* the default: half the period */
    }
    if (cell->dds.priority > 0 && cell->dds.priority >= rt->priority) {
        /* the publisher must never delay the loop it publishes for (also when both share a CPU) */
        FAIL(MCA_ECONFIG, LINE("dds.priority"), "dds.priority: %d must be below rt.priority (%d%s)",
             cell->dds.priority, rt->priority, rt->priority == 0 ? ", SCHED_OTHER" : "");
    }
    /* the controller's prediction uses the loop period */
    scn->params.dt = (double)rt->period_ns * 1e-9;
    {
        /* the task's tick count at this period (the scenario checked it at its own dt) */
        char why[160];
        if (mca_scenario_check_duration(scn->duration, scn->params.dt, why, sizeof why) != MCA_OK) {
            FAIL(MCA_ECONFIG, LINE("%s", raw->task.duration ? "task.duration" : "task.scenario"),
                 "task.duration: %s", why);
        }
    }
out:
    return rc;
}
