/* SPDX-License-Identifier: MIT */
/** @file mca/controller.h
 * One controller tick for N arms: forward kinematics, Jacobians, arm-to-arm distances, the QP of the
 * MCA scheme (or the MVN / APF baselines), the LVI-PDNN solve and run-time fault detection.
 * It is THE function the daemon's 1 kHz loop and mca-sim both call.
 *
 * Use (start-up, then every tick):
 *     mca_controller_config_t cfg;
 *     mca_controller_config_from_scenario(&cfg, &scenario, MCA_SCHEME_MCA, err, sizeof err); // or fill
 *     (mca_controller_config_from_scenario is the model library's, mca/scenario.h)
 *     void *mem = malloc(mca_controller_size());         // ~1.6 MB: not on a stack; core never allocates
 *     mca_controller_t *ctrl;
 *     mca_controller_create(mem, mca_controller_size(), &cfg, &ctrl);
 *     loop: mca_controller_tick(ctrl, t, q, qdot, &info);  // q[a], qdot[a]: arm a's joints
 *
 * Task time: the first tick after init/reset anchors the paths (frame "start") at the arms' current
 * end-effector positions and sets task time 0 = its t. Path time is t - t_start.
 *
 * Faults: any of NaN input/output, PDNN not converged beyond fault_residual, contradicting joint bounds,
 * a distance below d1, a distance predicted to cross d1 within the next tick, or an equality residual
 * ||G phi - alpha||_inf above eq_tol (the contradiction of Section VI-E: tracking and avoidance cannot
 * both hold; the PDNN's "fake attractor") make the tick command ZERO velocity for all arms and return
 * MCA_EFAULT with info->fault / info->fault_why naming the cause (mca_ctrl_fault_format). The fault LATCHES:
 * every later tick commands zero (and reports the same fault) until mca_controller_clear_fault(). The braking
 * profile itself is the arm's / daemon's job.
 *
 * Context: mca_controller_config_from_scenario() (mca_model), mca_controller_create(), _init() and _plan()
 * are start-up only (URDF parsing allocates). mca_controller_tick(), _reset(), _clear_fault(), the setters
 * and the getters are real-time safe: no allocation, no I/O, no locks; compute time is measured with
 * CLOCK_MONOTONIC. The state is opaque: what may change while running has a setter, what callers read a
 * getter.
 */
#ifndef MCA_CONTROLLER_H
#define MCA_CONTROLLER_H

#include <stddef.h>
#include <stdint.h>

#include "mca/apf.h"
#include "mca/armdist.h"
#include "mca/bodyrows.h"
#include "mca/chain.h"
#include "mca/coord.h"
#include "mca/path_rate.h"
#include "mca/limits.h"
#include "mca/path.h"
#include "mca/pdnn.h"
#include "mca/qp.h"
#include "mca/scheme.h"
#include "mca/track.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum mca_scheme_kind {
    MCA_SCHEME_MCA = 0, /**< QP (25)-(28) with collision rows, solved by the LVI-PDNN */
    MCA_SCHEME_MVN = 1, /**< QP (25)-(27), no collision rows */
    MCA_SCHEME_APF = 2, /**< artificial potential field baseline (40)-(46) */
    /** MCA with path-time scaling (docs/scheme.md "mca-ts"): per arm a path clock tau_a advancing at a rate
     *  sigma_a that is a QP variable, elastic tracking (a heavily weighted slack), stoppability-bounded
     *  collision rows, priorities and a named deadlock resolution. The default for cells. */
    MCA_SCHEME_MCA_TS = 3,
} mca_scheme_kind_t;

/** Short constant name of a scheme ("mca", "mvn", "apf", "mca-ts"); "unknown" otherwise. */
const char *mca_scheme_name(int scheme);

/** Scheme from its name. @retval MCA_OK, MCA_EINVAL (unknown name) */
int mca_scheme_from_name(const char *name, mca_scheme_kind_t *out);

/** Path-time scaling parameters (mca-ts only; defaults in mca_controller_default_config()). */
typedef struct mca_timescale_params {
    double w_sigma; /**< weight of (sigma - target)^2 against |qdot|^2 (1e2) */
    double w_slack; /**< quadratic weight of the tracking slack |e|^2 (1e3) */
    double w_tube;  /**< quadratic weight of the slack of a path with a tube (1e3) */
    double w_path;  /**< exact (L1) weight of the slack |e|_1: the path before its timing (1e4; docs/scheme.md
                         "The path first" derives the bound it must exceed) */
    double sigma_max; /**< most path rate when catching up (1.5; 1: never faster than the path) */
    double priority[MCA_MAX_ARMS]; /**< higher keeps its path; lower yields first and backs off (1) */
    double deadlock_time;  /**< every moving arm's sigma below deadlock_sigma this long: deadlock [s] (0.5) */
    double deadlock_sigma; /**< (0.05) */
    double back_off_time;  /**< the yielding arm runs its path backwards this long [s] (1.0) */
    double d1_margin; /**< the rows brake towards d1 + d1_margin (at most halfway to d2) [m] (0.005): what
                           the arms overshoot the rows by (rate limits, a capped solve, a turning normal)
                           stays above d1, where the distance fault still is */
    int coordinate; /**< 1: mca_controller_plan orders the arms where their fixed paths meet (mca/coord.h) (1)
                     */
    double dec_limit[MCA_MAX_ARMS]; /**< least joint deceleration of each arm for the stoppability bound
                                         [rad/s^2] (0: bound off) */
} mca_timescale_params_t;

/** Deadlock state (info->deadlock). */
typedef enum mca_deadlock_state {
    MCA_DEADLOCK_NONE = 0,
    MCA_DEADLOCK_BACK_OFF = 1, /**< the lowest-priority blocked arm runs its path backwards */
    MCA_DEADLOCK_WAIT = 2,     /**< it then holds (sigma <= 0) until the others have moved on */
} mca_deadlock_state_t;

/** Run-time fault codes (info->fault). */
typedef enum mca_ctrl_fault {
    MCA_CTRL_FAULT_NONE = 0,
    MCA_CTRL_FAULT_NAN = 1,            /**< non-finite joint input, QP data or solver output */
    MCA_CTRL_FAULT_NOT_CONVERGED = 2,  /**< PDNN residual above fault_residual at its step cap */
    MCA_CTRL_FAULT_INFEASIBLE = 3,     /**< joint bounds contradict (arm beyond a limit) */
    MCA_CTRL_FAULT_DISTANCE = 4,       /**< distance below d1, or predicted below d1 next tick */
    MCA_CTRL_FAULT_FAKE_ATTRACTOR = 5, /**< equality residual above eq_tol: tracking contradicts avoidance */
    MCA_CTRL_FAULT_INPUT = 6,          /**< bad call (NULL pointers, solver error) */
    /* 7 was pdnn-time-budget: running out of the budget is no fault (mca_budget_hit_t) */
    MCA_CTRL_FAULT_LAST = MCA_CTRL_FAULT_INPUT, /**< the highest code */
} mca_ctrl_fault_t;

/** How the PDNN's budget ran out in a tick (info->pdnn_budget_hit). Not a fault: the tick commands a repaired
 *  answer (mca-ts: repair_capped; mca: the iterate scaled into the collision rows and the joint box). */
typedef enum mca_budget_hit {
    MCA_BUDGET_NONE = 0,
    MCA_BUDGET_TIME = 1,  /**< the wall clock: pdnn_budget_ns from the tick's start */
    MCA_BUDGET_STEPS = 2, /**< the step budget pdnn_budget_steps, below the step cap */
} mca_budget_hit_t;

/** Short constant name of a fault code ("fake-attractor", ...). */
const char *mca_ctrl_fault_name(int fault);

/** Why a fault latched, in detail. */
typedef enum mca_ctrl_why {
    MCA_WHY_NONE = 0,
    MCA_WHY_NULL_JOINTS,   /**< a NULL joint array; i[0] arm */
    MCA_WHY_NONFINITE_Q,   /**< i[0] arm */
    MCA_WHY_DISTANCES,     /**< the distance computation failed */
    MCA_WHY_BELOW_D1,      /**< x[0] distance, x[1] d1; i[0..3] arm, link, arm, link */
    MCA_WHY_BELOW_D1_NEXT, /**< as MCA_WHY_BELOW_D1, predicted for the next tick */
    MCA_WHY_APF_SINGULAR,  /**< APF: singular Jacobian */
    MCA_WHY_BOUNDS,        /**< the joint bounds contradict (a joint beyond its limit) */
    MCA_WHY_ASSEMBLY,      /**< i[0] the MCA error code of the QP assembly */
    MCA_WHY_PDNN_INPUT,    /**< the PDNN rejected the QP (non-finite data) */
    MCA_WHY_PDNN_OUTPUT,   /**< the PDNN's output is not finite */
    MCA_WHY_TRACKING, /**< not converged, tracking off: x[0] residual, x[1] ||G phi - alpha||, x[2] min d;
                         i[0] steps */
    MCA_WHY_NOT_CONVERGED,   /**< x[0] residual, x[1] the fault threshold; i[0] steps */
    MCA_WHY_EQ_RESIDUAL,     /**< x[0] ||G phi - alpha||, x[1] eq_tol */
    MCA_WHY_INJECTED,        /**< latched from outside the tick (mca_controller_raise_fault): i[0] the fault,
                                x[0] the time given */
    MCA_WHY_BELOW_CLEARANCE, /**< a link inside a fixed body's clearance: x[0] distance, x[1] clearance;
                                i[0..2] arm, link, body */
    MCA_WHY_BELOW_CLEARANCE_NEXT, /**< as MCA_WHY_BELOW_CLEARANCE, predicted for the next tick */
    MCA_WHY_SELF_BELOW_D1,        /**< two links of one arm below d1: x[0] distance, x[1] d1; i[0..2] arm,
                                     link, other link */
    MCA_WHY_SELF_BELOW_D1_NEXT,   /**< as MCA_WHY_SELF_BELOW_D1, predicted for the next tick */
} mca_ctrl_why_t;

/** A fault's cause as a code and numbers: the tick fills it without formatting anything (no text on the
 *  1 kHz path); mca_ctrl_fault_format() makes the text where formatting is allowed. */
typedef struct mca_ctrl_fault_why {
    int why; /**< mca_ctrl_why_t */
    int i[4];
    double x[3];
} mca_ctrl_fault_why_t;

/** The text of a fault's cause (not real-time: log drainers, summaries, tools). Returns buf. */
const char *mca_ctrl_fault_format(const mca_ctrl_fault_why_t *why, char *buf, size_t len);

typedef struct mca_controller_config {
    int n_arms;                      /**< 1..MCA_MAX_ARMS */
    mca_chain_t chain[MCA_MAX_ARMS]; /**< copied; base placement set */
    mca_path_t path[MCA_MAX_ARMS];   /**< desired end-effector path of each arm (copied) */
    mca_scheme_kind_t scheme;
    mca_scheme_params_t sp; /**< d1, d2, K, epsilon, collision form, ... */
    mca_pdnn_params_t pdnn;
    mca_apf_params_t apf;
    mca_dist_method_t dist_method; /**< MCA_DIST_CLOSED (default, exact) or MCA_DIST_LSDM */
    double dt; /**< tick period [s] (prediction of the next distance, APF D terms); MCA_CONTROLLER_DT */
    double fault_residual;     /**< PDNN residual that is a fault at the step cap (1e-6) */
    double eq_tol;             /**< ||G phi - alpha||_inf that is a fault [m/s] (1e-4) */
    int fault_distance;        /**< 1: distance < d1 (measured or predicted) is a fault (MCA) */
    mca_timescale_params_t ts; /**< mca-ts only */
    int64_t pdnn_budget_ns; /**< wall time the PDNN may use from the start of a tick (0: none); running out is
                                 a budget event (MCA_BUDGET_TIME), a braking tick's the keep-direction
                                 fallback. mcad: rt.pdnn_budget_us (half the period); mca-sim: none */
    int n_bodies; /**< fixed bodies of the cell (tables, fixtures, cups): every link they do not allow keeps
                       their clearance through rows of its own (mca/bodyrows.h); 0: none (the arms only) */
    mca_fixed_body_t body[MCA_MAX_BODIES];
    int body_rows; /**< 1 (default): the bodies' rows and their distance fault; 0: bodies measured only (the
                        comparison run of what happens without them: mca-sim --no-body-rows) */
    mca_self_pairs_t self[MCA_MAX_ARMS]; /**< each arm's self pairs (mca/bodyrows.h): link pairs of one arm
                                              kept d1 apart by rows in the bodies' slots; all 0: none */
    int self_rows; /**< 1 (default): the self pairs' rows and their distance fault; 0: measured only (the
                        comparison run: mca-sim --no-self-rows) */
    int pdnn_budget_steps; /**< the same budget in steps (0: none; mca_pdnn_budget_steps): a solve stops at
                                min(pdnn.max_steps, this); stopping here before the cap is a budget event
                                (MCA_BUDGET_STEPS), deterministic. mcad and mca-sim alike. Not under the
                                scheme mca, whose step limit stays its cap (the paper's figures) */
    int max_tracks; /**< streamed bodies (mca/track.h) the controller keeps slots for, after the fixed bodies
                         (0: none); they arrive through mca_controller_set_tracks */
    mca_ssm_params_t ssm; /**< their speed and separation monitoring (mca_ssm_default) */
} mca_controller_config_t;

/** Wall time of one PDNN step [ns] on the largest QPs the shipped tasks build, measured on the development VM
 *  (docs/pdnn.md "Step budget": bench_tick steps, the worst of every task, scheme and form, least of 3 runs:
 *  707 ns, hui under mca-ts). The step budget is a time budget divided by this. */
#define MCA_PDNN_STEP_NS 700

/** The step budget of a time budget [ns]: budget_ns / MCA_PDNN_STEP_NS, at least 1 (0: none for 0). */
int mca_pdnn_budget_steps(int64_t budget_ns);

/** The step budget a solve under @p cfg stops at before its cap (0: none): cfg->pdnn_budget_steps when it
 *  is below pdnn.max_steps, except under the scheme mca (its cap stays its step limit). */
int mca_controller_step_budget(const mca_controller_config_t *cfg);

/** The default tick period [s]: 1 kHz (mca_controller_default_config, mca_scenario_defaults). */
#define MCA_CONTROLLER_DT 0.001

/** Defaults for everything but chains and paths (MCA scheme, normal form, closed-form distances). */
void mca_controller_default_config(mca_controller_config_t *cfg);

/** Some arm of cfg has self pairs (cfg->self, mca/bodyrows.h). Context: any. */
int mca_controller_has_self(const mca_controller_config_t *cfg);

/** Report of one tick. */
typedef struct mca_tick_info {
    double t;      /**< the tick's t */
    double task_t; /**< t - t_start */
    int n_arms;
    /* distances (all pairs of arms; the global minimum) */
    double min_distance;       /**< surface distance [m] (+INF with one arm) */
    int min_arm_a, min_link_a; /**< critical pair: arm/link with P */
    int min_arm_b, min_link_b; /**< arm/link with E */
    double min_p[3], min_e[3];
    double link_distance[MCA_MAX_ARMS][MCA_MAX_LINKS]; /**< per link: closest link of any other arm */
    /* fixed bodies: the arm-body pair of least margin d - clearance (body_arm -1: none) */
    double body_distance;    /**< its surface distance [m] (+INF: no pair) */
    double body_margin;      /**< d - the body's clearance [m] (+INF: no pair); below 0 is a distance fault */
    int body_arm, body_link; /**< the link */
    int body_index;          /**< the body (cfg.body[]) */
    int body_kind;           /**< its mca_body_kind_t (mca_body_kind_name) */
    double body_p[3], body_q[3]; /**< witness on the link's axis, on the body */
    /* self pairs: the pair of least distance (self_arm -1: none) */
    double self_distance;    /**< its surface distance [m] (+INF: no pair); below d1 is a distance fault */
    int self_arm, self_link; /**< the arm and the pair's outer link */
    int self_other;          /**< the pair's inner link */
    double brake;            /**< smallest S(d) over the links (1: free) */
    int active_rows;         /**< collision rows with a finite bound */
    int binding_rows;        /**< collision rows at their bound (U phi >= beta - 1e-9) */
    /* solver */
    int pdnn_steps;
    int pdnn_exact_solves; /**< the polish's exact active-set solves (docs/pdnn.md) */
    double pdnn_residual;
    int pdnn_converged;
    int pdnn_budget_hit; /**< mca_budget_hit_t: the solve stopped at the budget (time or steps) this tick
                              before its tolerance; the command is the repaired answer when the residual is
                              above fault_residual. Never a fault by itself */
    double eq_residual;  /**< ||G phi - alpha||_inf [m/s] (of the solver's answer, before any repair) */
    /* tracking */
    double ee[MCA_MAX_ARMS][3]; /**< actual end effector */
    double ee_desired[MCA_MAX_ARMS][3];
    double ee_error[MCA_MAX_ARMS]; /**< |r_d - r| [m] */
    /* path time (mca-ts; the other schemes: tau = task_t, sigma = 1) */
    double tau[MCA_MAX_ARMS];   /**< path clock of each arm [s] */
    double sigma[MCA_MAX_ARMS]; /**< path rate commanded this tick */
    double slack;               /**< largest |tracking slack| this tick [m/s] */
    double
        path_error[MCA_MAX_ARMS]; /**< the tool tip's distance to its path's curve [m] (mca_path_distance) */
    double tube[MCA_MAX_ARMS];    /**< the path tube's radius at the arm's clock [m] (mca-ts) */
    int exact_met;                /**< exact waypoints met so far (all arms) */
    int exact_missed;             /**< exact waypoints missed so far: the tool tip was farther than
                                       exact_tol while the clock was on the point */
    double exact_error_max;       /**< the largest tool-tip distance to an exact point while on it [m] */
    int paths_done;               /**< 1: every arm's path clock has reached its path's end */
    int deadlock;                 /**< mca_deadlock_state_t */
    int deadlock_arm;             /**< the arm that backs off (-1: none) */
    int deadlocks;                /**< deadlocks detected since the task started */
    /* outcome */
    int fault;                      /**< mca_ctrl_fault_t */
    mca_ctrl_fault_why_t fault_why; /**< its cause (text: mca_ctrl_fault_format) */
    int brake_fallback;             /**< braking: 1 when this tick used the scale-the-whole-vector fallback */
    int64_t compute_ns;             /**< CLOCK_MONOTONIC time spent in the tick */
} mca_tick_info_t;

/** The controller's state: opaque (its fields are core's, core/src/controller__state.h). The caller provides
 *  its storage, mca_controller_size() bytes aligned for any type (malloc's, or static storage aligned with
 *  _Alignas(max_align_t)), at start-up: core never allocates (core.rt_symbols checks it), and a daemon that
 *  locks its memory takes the state into the lock with the rest of what it allocated before mlockall. */
typedef struct mca_controller mca_controller_t;

/** An upper bound of mca_controller_size() [bytes]: 1.7 MB. The state is about 1.6 MB (1 633 544 bytes on
 *  x86-64: the two QPs and PDNNs, the tick's and the braking's, are most of it), so never on a stack;
 *  controller.c checks at compile time that the state lies between 90 % of this bound and the bound, so this
 *  figure stays the size to plan for (docs/architecture.md). */
#define MCA_CONTROLLER_SIZE_MAX 1700000

/** Bytes of storage a controller needs (sizeof its state, at most MCA_CONTROLLER_SIZE_MAX). */
size_t mca_controller_size(void);

/**
 * A controller in the caller's storage, initialised from @p cfg (mca_controller_init). Start-up only.
 * Nothing inside owns a resource: to destroy it, the caller frees (or reuses) its storage.
 * @param storage  at least mca_controller_size() bytes, aligned for any type
 * @param[out] out  the controller (== storage), NULL on error
 * @retval MCA_OK, MCA_EINVAL (NULL, size too small, storage misaligned, or mca_controller_init's reasons)
 */
int mca_controller_create(void *storage, size_t size, const mca_controller_config_t *cfg,
                          mca_controller_t **out);

/** Copy the whole state of @p src into @p dst (a created controller, or storage as mca_controller_create's,
 *  which then holds a controller): a scratch copy to warm code on or to branch a run from (RT safe: a memcpy
 *  of mca_controller_size() bytes, no allocation). */
void mca_controller_copy(mca_controller_t *dst, const mca_controller_t *src);

/* ---- what a caller reads (getters; RT safe, no copies) */

/** The configuration the controller runs (cfg as mca_controller_init adjusted it: the scheme's collision
 *  rows, the bodies' slots, mca-ts's form; the setters below change it while running). */
const mca_controller_config_t *mca_controller_get_config(const mca_controller_t *ctrl);

/** 1 once a tick anchored the paths (task time runs), 0 before the first tick after init / reset. */
int mca_controller_started(const mca_controller_t *ctrl);

/** Arm @p arm's kinematics as of the last tick / observe / brake (NULL: arm out of range). */
const mca_kin_t *mca_controller_kin(const mca_controller_t *ctrl, int arm);

/** The arm-to-arm distances of the last tick / observe / brake: [a][b] for a < b (mca/armdist.h). */
const mca_arm_distances_t (*mca_controller_distances(const mca_controller_t *ctrl))[MCA_MAX_ARMS];

/** Every kind of pair but the arm pairs (mca_controller_distances) at the last tick's kinematics: what a
 *  monitor shows and a summary counts. */
typedef struct mca_pair_nearest {
    int n_bodies; /**< bodies now: [0, n_fixed) the cell's fixed bodies, [n_fixed, n_bodies) streamed ones */
    int n_fixed;
    mca_body_nearest_t
        body[MCA_MAX_BODIES];              /**< per body its closest link it does not allow (valid 0: none) */
    mca_self_nearest_t self[MCA_MAX_ARMS]; /**< per arm its self pair of least distance (valid 0: none) */
} mca_pair_nearest_t;

/**
 * Each body's closest link and each arm's closest self pair as the last tick / observe / brake measured them
 * (mca_body_nearest_each, mca_self_nearest: the report's body_* and self_* fields are the least of these).
 * RT safe (a copy).
 * @retval MCA_OK, MCA_EINVAL (NULL)
 */
int mca_controller_pair_nearest(const mca_controller_t *ctrl, mca_pair_nearest_t *out);

/** mca-ts: arm @p arm's path-rate limit from mca_controller_plan (n = 0: none; NULL: arm out of range). */
const mca_path_rate_t *mca_controller_path_rate(const mca_controller_t *ctrl, int arm);

/** mca-ts: who passes first where fixed paths meet, from mca_controller_plan (empty without a plan). */
const mca_coord_t *mca_controller_coord(const mca_controller_t *ctrl);

/** Initialise (or re-initialise, with a new configuration) a created controller, or storage as
 *  mca_controller_create's (which then holds one; create also checks the storage): every field from @p cfg,
 *  the task restarted. Start-up only.
 *  @retval MCA_OK, MCA_EINVAL (NULL, n_arms out of range, d1 >= d2, non-positive dt, ...) */
int mca_controller_init(mca_controller_t *ctrl, const mca_controller_config_t *cfg);

/**
 * mca-ts: each path-first arm's path-rate limit (sigma's own stop bound, mca/path_rate.h) and, with
 * ts.coordinate, the order in which arms on fixed paths pass each other (mca/coord.h), from the configuration
 * the task starts at (the paths are anchored as the first tick will anchor them). Call it after
 * mca_controller_init (or _reset) and before the first tick; without it no path rate is limited by the
 * path's curvature, the arms are not ordered and deadlocks are left to the back-off. Start-up only: work is
 * caller's scratch (sizeof about 3 MB).
 * @retval MCA_OK (nothing to plan included), MCA_EINVAL
 */
int mca_controller_plan(mca_controller_t *ctrl, const double *const q[MCA_MAX_ARMS], mca_coord_work_t *work);

/** Restart the task: next tick re-anchors paths, clears warm start, memory and any fault. RT safe. */
void mca_controller_reset(mca_controller_t *ctrl);

/**
 * Velocity of arm @p arm's streamed reference from the next tick on (its path must be MCA_PATH_STREAM):
 * the reference moves by sigma v dt per tick, sigma the arm's path rate (mca-ts: below 1 while it yields,
 * negative while it backs off a deadlock; the other schemes: 1). RT safe.
 * @retval MCA_OK, MCA_EINVAL (NULL, arm out of range, not a stream, non-finite v)
 */
int mca_controller_stream(mca_controller_t *ctrl, int arm, const double v[3]);

/** What a streamed target asks of its arm (mca_controller_stream_target). */
typedef enum mca_stream_kind {
    MCA_STREAM_HOLD = 0,  /**< no target, or none recent enough: the reference stands still */
    MCA_STREAM_TWIST = 1, /**< x is the reference's velocity [m/s] */
    MCA_STREAM_POSE = 2,  /**< x is a position the reference approaches [m] */
} mca_stream_kind_t;

/** The streamed targets' law (mcad: the cell's task.stream). */
typedef struct mca_stream_law {
    double pose_gain; /**< a pose is approached at pose_gain x (x - reference) [1/s] */
    double max_speed; /**< no reference velocity beyond this [m/s] */
} mca_stream_law_t;

/**
 * The streamed targets' control law, then mca_controller_stream (RT safe): arm @p arm's reference velocity
 * from its target: a twist as it is; a pose approached at law->pose_gain x the gap from where the reference
 * is now (hold until the first tick anchored the paths); a hold, or any non-finite x: zero; the result
 * scaled down to at most law->max_speed (the target's source is not trusted with either).
 * @param x  the target (not read for MCA_STREAM_HOLD)
 * @retval MCA_OK, MCA_EINVAL (as mca_controller_stream; NULL law, x NULL unless a hold)
 */
int mca_controller_stream_target(mca_controller_t *ctrl, int arm, mca_stream_kind_t kind, const double x[3],
                                 const mca_stream_law_t *law);

/** The PDNN's wall-time budget from the start of a tick [ns] (cfg.pdnn_budget_ns; 0: none), from the next
 *  tick on: mcad gives its loop half the period once it runs in real time. RT safe.
 *  @retval MCA_OK, MCA_EINVAL (NULL, negative) */
int mca_controller_set_pdnn_budget(mca_controller_t *ctrl, int64_t budget_ns);

/** S_p's arm terms under cfg (mca/track.h): v_r the fastest point of any arm, T_s the longest stop at the
 *  arms' ts.dec_limit (0 without one). Any context. */
void mca_controller_ssm_arms(const mca_controller_config_t *cfg, double *arm_speed, double *t_stop);

/**
 * The streamed bodies at time t (the tick's clock): each track becomes a body of the rows with the
 * protective separation S_p as its clearance, grown while stale (mca_track_body). Call every tick before
 * mca_controller_tick (or _brake): a stale track grows with t. n = 0 removes them. RT safe (copies).
 * @retval MCA_OK
 * @retval MCA_EINVAL  NULL, n above cfg.max_tracks, a track not usable: the bodies stay as they were
 */
int mca_controller_set_tracks(mca_controller_t *ctrl, const mca_track_t *tracks, int n, double t);

/** Clear a latched fault (keeps the task clock and anchors). RT safe. */
void mca_controller_clear_fault(mca_controller_t *ctrl);

/**
 * One tick (real-time safe).
 * @param t     time [s] (any origin; monotonic)
 * @param q     q[a]: joint positions of arm a (chain dof values)
 * @param[out] qdot  qdot[a]: commanded joint velocities (zero on fault)
 * @param[out] info  tick report (may be NULL)
 * @retval MCA_OK      qdot is the scheme's command
 * @retval MCA_EFAULT  fault (new or latched): qdot is zero, info->fault says why
 * @retval MCA_EINVAL  NULL pointers (qdot zeroed where possible)
 */
int mca_controller_tick(mca_controller_t *ctrl, double t, const double *const q[MCA_MAX_ARMS],
                        double *const qdot[MCA_MAX_ARMS], mca_tick_info_t *info);

/**
 * Kinematics and distances only, no QP, no command, no fault raised (real-time safe): what a braking or
 * stopped controller still measures. Updates info->t, task_t, n_arms, ee, min_distance with its arms,
 * links and points P/E, and link_distance (and mca_controller_kin, _distances); every other field of info is
 * left as it was (the last tick's solver figures stay readable).
 * @retval MCA_OK, MCA_EINVAL (NULL pointers, non-finite joint position: info's distances untouched)
 */
int mca_controller_observe(mca_controller_t *ctrl, double t, const double *const q[MCA_MAX_ARMS],
                           mca_tick_info_t *info);

/**
 * One braking tick (real-time safe): the velocities closest to zero inside the deceleration box
 * v_last +- dec_limit dt, the joint limits and the collision rows (mca and mca-ts; none for the baselines),
 * solved by the PDNN. When that QP has no answer (the box and the rows contradict, or the solver misses its
 * tolerance) each arm keeps its direction of motion: its whole velocity vector is scaled by one factor so
 * that no joint changes by more than dec_limit dt. Works whatever the fault latched.
 * @param v_last     v_last[a]: the velocity commanded last tick
 * @param dec_limit  dec_limit[a][j] [rad/s^2] (> 0)
 * @param[out] qdot  this tick's command
 * @param[out] info  distances (as mca_controller_observe) and info->brake_fallback
 * @retval 1 every commanded velocity is zero (at rest), 0 still braking, MCA_EINVAL (NULL, non-finite q)
 */
int mca_controller_brake(mca_controller_t *ctrl, double t, const double *const q[MCA_MAX_ARMS],
                         const double *const v_last[MCA_MAX_ARMS],
                         const double *const dec_limit[MCA_MAX_ARMS], double *const qdot[MCA_MAX_ARMS],
                         mca_tick_info_t *info);

/**
 * The keep-direction stop of one arm (RT safe): out = f v with one factor f in [0, 1) for the whole vector,
 * the largest such that no joint changes by more than dec[j] dt, so the joint slowest to stop sets it and
 * the arm reaches rest within ceil(max_j |v_j| / (dec_j dt)) calls. A joint with dec[j] <= 0 (no limit) may
 * stop at once. Any non-finite v[j]: every joint 0 (no direction to keep). out may alias v.
 */
void mca_brake_scale_arm(const double *v, const double *dec, double dt, int dof, double *out);

/**
 * Measured joint velocities for the next tick (mca-ts; RT safe). The next command then stays within
 * dec_limit dt of what each joint really does, not of the last command, so an arm that could not follow a
 * command is not assumed to have. Used by one tick, then forgotten (without it: the last command).
 */
void mca_controller_set_velocity(mca_controller_t *ctrl, const double *const v[MCA_MAX_ARMS]);

/** Latch a fault from outside the tick at time t (a test's injected fault; cause MCA_WHY_INJECTED). RT safe.
 */
void mca_controller_raise_fault(mca_controller_t *ctrl, int code, double t);

/** Last QP assembled and the PDNN's phi (for --dump-qp; not meaningful for APF). */
const mca_qp_t *mca_controller_last_qp(const mca_controller_t *ctrl, const double **phi);

#ifdef __cplusplus
}
#endif
#endif
