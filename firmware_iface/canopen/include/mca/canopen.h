/* SPDX-License-Identifier: MIT */
/** @file mca/canopen.h
 * CANopen (CiA 301 subset) and the CiA 402 drive profile, on SocketCAN (classic CAN, 11-bit ids):
 * one header for the whole module. Three layers:
 *
 *  1. Pure codec (no socket, no clock; host unit tests): NMT, SYNC, heartbeat, EMCY frames; the SDO
 *     client and SDO server as state machines that turn one received frame into at most one frame to
 *     send (expedited and segmented transfers, abort codes with their CiA 301 text); PDO mapping entries;
 *     the CiA 402 statusword decoder and the controlword that moves a drive one step towards the wanted
 *     state.
 *  2. The object dictionary table (mca_co_od_entry_t) an SDO server reads and writes (mca-drivesim).
 *  3. The master (mca_co_master_t, caller-owned storage): NMT, SDO and PDO configuration at start-up
 *     (blocking, bounded by timeouts), then a non-blocking cyclic tick that reads TPDOs, heartbeats and
 *     EMCYs, watches for faults, and sends the RPDOs and the SYNC.
 *
 * COB-ids (predefined connection set): NMT 0x000, SYNC 0x080, EMCY 0x080+node, TPDOk 0x180+0x100(k-1)+node,
 * RPDOk 0x200+0x100(k-1)+node, SDO server->client 0x580+node, client->server 0x600+node, heartbeat
 * 0x700+node. Multi-byte values are little-endian.
 *
 * Context: the codec functions are real-time safe (no allocation, no I/O). mca_co_master_open/start/
 * close, mca_co_sdo_upload/download and mca_co_nmt_send are start-up/shut-down only (they block up to
 * their timeout); mca_co_master_tick and the set/get functions are real-time safe (non-blocking socket
 * calls, no allocation, no locks). Returns: MCA_OK (0) or a negative mca_retcode (mca/err.h).
 */
#ifndef MCA_CANOPEN_H
#define MCA_CANOPEN_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/** Most drives (nodes) one master runs on one bus. */
#define MCA_CO_MAX_NODES 8

/* ---- frames and ids ---------------------------------------------------------------------------- */

/** One classic CAN frame (standard id, 0..8 bytes). */
typedef struct mca_co_frame {
    uint16_t id; /**< 11-bit COB-id */
    uint8_t len; /**< 0..8 */
    uint8_t data[8];
} mca_co_frame_t;

enum {
    MCA_CO_COB_NMT = 0x000,
    MCA_CO_COB_SYNC = 0x080,
    MCA_CO_COB_EMCY = 0x080,
    MCA_CO_COB_TPDO1 = 0x180,
    MCA_CO_COB_RPDO1 = 0x200,
    MCA_CO_COB_TPDO2 = 0x280,
    MCA_CO_COB_RPDO2 = 0x300,
    MCA_CO_COB_SDO_TX = 0x580, /**< server -> client */
    MCA_CO_COB_SDO_RX = 0x600, /**< client -> server */
    MCA_CO_COB_HB = 0x700,
};

/** NMT command specifiers. */
enum mca_co_nmt_cmd {
    MCA_CO_NMT_START = 0x01,
    MCA_CO_NMT_STOP = 0x02,
    MCA_CO_NMT_PREOP = 0x80,
    MCA_CO_NMT_RESET_NODE = 0x81,
    MCA_CO_NMT_RESET_COMM = 0x82,
};

/** NMT states as a heartbeat carries them. */
enum mca_co_nmt_state {
    MCA_CO_NMT_BOOTUP = 0x00,
    MCA_CO_NMT_STOPPED = 0x04,
    MCA_CO_NMT_OPERATIONAL = 0x05,
    MCA_CO_NMT_PREOPERATIONAL = 0x7F,
};

/** What a received frame is, from its COB-id alone (mca_co_classify). */
typedef enum mca_co_kind {
    MCA_CO_K_OTHER = 0,
    MCA_CO_K_NMT,
    MCA_CO_K_SYNC,
    MCA_CO_K_EMCY,
    MCA_CO_K_TPDO, /**< pdo = 1..4 */
    MCA_CO_K_RPDO, /**< pdo = 1..4 */
    MCA_CO_K_SDO_TX,
    MCA_CO_K_SDO_RX,
    MCA_CO_K_HB,
} mca_co_kind_t;

/** Kind, node (1..127; 0 for NMT/SYNC) and PDO number (1..4) of COB-id @p id. */
mca_co_kind_t mca_co_classify(uint16_t id, uint8_t *node, uint8_t *pdo);

struct mca_can_frame; /* mca/can_sock.h */

/**
 * The CANopen frame in a received SocketCAN frame: a classic data frame with an 11-bit id (payload cut to
 * 8 bytes). Error, extended-id and remote frames are no CANopen frame (a 29-bit id masked to 11 bits would
 * pass for one). @retval 1 filled @retval 0 not a CANopen frame (*f untouched)
 */
int mca_co_frame_from_can(mca_co_frame_t *f, const struct mca_can_frame *c);

/** NMT command @p cmd to @p node (0 = all). @retval MCA_OK, MCA_EINVAL (NULL, node > 127) */
int mca_co_nmt_encode(mca_co_frame_t *f, uint8_t cmd, uint8_t node);
/** Heartbeat / boot-up (state MCA_CO_NMT_BOOTUP) of @p node. @retval MCA_OK, MCA_EINVAL */
int mca_co_hb_encode(mca_co_frame_t *f, uint8_t node, uint8_t state);

/** One emergency message. */
typedef struct mca_co_emcy {
    uint16_t code;  /**< error code (0x0000: error reset / no error) */
    uint8_t reg;    /**< error register (0x1001) */
    uint8_t mfr[5]; /**< manufacturer-specific bytes */
} mca_co_emcy_t;

/** @retval MCA_OK, MCA_EINVAL (NULL, node 0 or > 127) */
int mca_co_emcy_encode(mca_co_frame_t *f, uint8_t node, const mca_co_emcy_t *e);
/** @retval MCA_OK, MCA_EINVAL (NULL, not 8 bytes) */
int mca_co_emcy_decode(const mca_co_frame_t *f, mca_co_emcy_t *e);
/** Short text of an EMCY error code by its class ("current", "voltage", "temperature", "device
 *  hardware", "monitoring", "communication", ...); never NULL. */
const char *mca_co_emcy_text(uint16_t code);

/* ---- SDO --------------------------------------------------------------------------------------- */

/** SDO abort codes (CiA 301) used here. */
enum {
    MCA_CO_ABORT_TOGGLE = 0x05030000u,
    MCA_CO_ABORT_TIMEOUT = 0x05040000u,
    MCA_CO_ABORT_CMD = 0x05040001u,
    MCA_CO_ABORT_NO_MEM = 0x05040005u,
    MCA_CO_ABORT_ACCESS = 0x06010000u,
    MCA_CO_ABORT_WRITE_ONLY = 0x06010001u,
    MCA_CO_ABORT_READ_ONLY = 0x06010002u,
    MCA_CO_ABORT_NO_OBJECT = 0x06020000u,
    MCA_CO_ABORT_NO_MAP = 0x06040041u,
    MCA_CO_ABORT_MAP_LEN = 0x06040042u,
    MCA_CO_ABORT_TYPE_LEN = 0x06070010u,
    MCA_CO_ABORT_TYPE_HIGH = 0x06070012u,
    MCA_CO_ABORT_TYPE_LOW = 0x06070013u,
    MCA_CO_ABORT_NO_SUB = 0x06090011u,
    MCA_CO_ABORT_VALUE = 0x06090030u,
    MCA_CO_ABORT_GENERAL = 0x08000000u,
    MCA_CO_ABORT_STATE = 0x08000022u,
};

/** CiA 301 text of an SDO abort code ("object does not exist in the object dictionary", ...); an unknown
 *  code gives "unknown abort code". Never NULL. */
const char *mca_co_abort_text(uint32_t code);

/** Longest value one SDO transfer carries here (visible strings, domains). */
#define MCA_CO_SDO_MAX 64

typedef enum mca_co_sdo_status {
    MCA_CO_SDO_IDLE = 0,
    MCA_CO_SDO_SEND = 1, /**< a frame to send was written; then wait for the answer */
    MCA_CO_SDO_WAIT = 2, /**< the frame given was not for this transfer: keep waiting */
    MCA_CO_SDO_DONE = 3, /**< transfer complete (upload: data/len hold the value) */
    MCA_CO_SDO_ABORTED =
        4, /**< aborted: by the server (abort frame) or by us (a frame to send was written) */
} mca_co_sdo_status_t;

/** SDO client transfer state (one transfer at a time per server). */
typedef struct mca_co_sdo_client {
    uint8_t node;
    uint8_t upload; /**< 1 upload (read), 0 download (write) */
    uint16_t index;
    uint8_t sub;
    uint8_t toggle;
    uint8_t segmented;
    mca_co_sdo_status_t status;
    uint32_t abort_code; /**< when ABORTED */
    uint8_t by_server;   /**< 1: the server aborted, 0: we did */
    uint8_t data[MCA_CO_SDO_MAX];
    size_t len; /**< download: bytes to send; upload: bytes received */
    size_t pos; /**< bytes transferred so far (segmented) */
} mca_co_sdo_client_t;

/** Start a download of @p len bytes (1..MCA_CO_SDO_MAX; expedited up to 4, else segmented) and write the
 *  first request into @p tx. @retval MCA_OK, MCA_EINVAL (NULL, node, len) */
int mca_co_sdo_download_start(mca_co_sdo_client_t *c, mca_co_frame_t *tx, uint8_t node, uint16_t index,
                              uint8_t sub, const void *data, size_t len);
/** Start an upload and write its first request into @p tx. @retval MCA_OK, MCA_EINVAL */
int mca_co_sdo_upload_start(mca_co_sdo_client_t *c, mca_co_frame_t *tx, uint8_t node, uint16_t index,
                            uint8_t sub);
/** Feed one received frame; writes the next request into @p tx when the result is SEND (or ABORTED by
 *  us: then @p tx holds our abort frame). Frames that are not this server's SDO answers give WAIT. */
mca_co_sdo_status_t mca_co_sdo_client_rx(mca_co_sdo_client_t *c, const mca_co_frame_t *rx,
                                         mca_co_frame_t *tx);
/** Give up (timeout): status ABORTED with MCA_CO_ABORT_TIMEOUT, our abort frame into @p tx. */
void mca_co_sdo_client_timeout(mca_co_sdo_client_t *c, mca_co_frame_t *tx);

/* ---- object dictionary (for an SDO server) ------------------------------------------------------ */

enum {
    MCA_CO_ACC_RO = 1, /**< read only */
    MCA_CO_ACC_WO = 2,
    MCA_CO_ACC_RW = 3,
    MCA_CO_ACC_PDO = 4, /**< may be mapped into a PDO */
};

/** One object dictionary entry: the value lives at @p ptr (size bytes; a string up to size). */
typedef struct mca_co_od_entry {
    uint16_t index;
    uint8_t sub;
    uint8_t access; /**< MCA_CO_ACC_* */
    uint8_t size;   /**< bytes: 1, 2, 4, or a string/domain capacity */
    uint8_t is_str; /**< 1: visible string (upload length = strlen up to size) */
    int8_t is_signed;
    int64_t min, max; /**< integer range checked on download (min > max: no check) */
    void *ptr;
} mca_co_od_entry_t;

/** The entry (index, sub) of @p od, or NULL (and *abort: NO_OBJECT or NO_SUB). */
const mca_co_od_entry_t *mca_co_od_find(const mca_co_od_entry_t *od, size_t n, uint16_t index, uint8_t sub,
                                        uint32_t *abort);

/** Called by the SDO server after a download changed an entry (e.g. a PDO mapping); returns 0 or an abort
 *  code, in which case the old value is put back. */
typedef uint32_t (*mca_co_od_written_fn)(void *user, const mca_co_od_entry_t *e);

/** SDO server state (one per node). */
typedef struct mca_co_sdo_server {
    uint8_t node;
    const mca_co_od_entry_t *od;
    size_t n_od;
    mca_co_od_written_fn written;
    void *user;
    uint8_t active; /**< 1 during a segmented transfer */
    uint8_t upload;
    uint8_t toggle;
    const mca_co_od_entry_t *e;
    uint8_t buf[MCA_CO_SDO_MAX];
    size_t len, pos;
} mca_co_sdo_server_t;

/** @retval MCA_OK, MCA_EINVAL */
int mca_co_sdo_server_init(mca_co_sdo_server_t *s, uint8_t node, const mca_co_od_entry_t *od, size_t n_od,
                           mca_co_od_written_fn written, void *user);
/** Serve one request frame addressed to this node (id 0x600+node). @return 1 if @p tx holds the answer,
 *  0 if the frame was not for this server, MCA_EINVAL on NULL. */
int mca_co_sdo_server_rx(mca_co_sdo_server_t *s, const mca_co_frame_t *rx, mca_co_frame_t *tx);

/* ---- PDO mapping -------------------------------------------------------------------------------- */

/** Mapping entry value (0x1600.. / 0x1A00.. subs): index << 16 | sub << 8 | bits. */
static inline uint32_t mca_co_map_entry(uint16_t index, uint8_t sub, uint8_t bits) {
    return (uint32_t)index << 16 | (uint32_t)sub << 8 | bits;
}

/* ---- CiA 402 -------------------------------------------------------------------------------------- */

/** Objects of the drive profile used here. */
enum {
    MCA_CO402_CONTROLWORD = 0x6040,
    MCA_CO402_STATUSWORD = 0x6041,
    MCA_CO402_MODE = 0x6060,
    MCA_CO402_MODE_DISPLAY = 0x6061,
    MCA_CO402_POSITION_ACTUAL = 0x6064,
    MCA_CO402_VELOCITY_ACTUAL = 0x606C,
    MCA_CO402_TORQUE_ACTUAL = 0x6077,
    MCA_CO402_TARGET_POSITION = 0x607A,
    MCA_CO402_INTERP_PERIOD = 0x60C2, /**< sub1 value (u8), sub2 index (i8): period = value * 10^index s */
    MCA_CO402_TARGET_VELOCITY = 0x60FF,
    MCA_CO402_ERROR_CODE = 0x603F,
    MCA_CO402_SUPPORTED_MODES = 0x6502,
};

/** Modes of operation (0x6060) used here. */
enum {
    MCA_CO402_MODE_CSP = 8, /**< cyclic synchronous position */
    MCA_CO402_MODE_CSV = 9, /**< cyclic synchronous velocity */
};

/** CiA 402 drive states, from the statusword. */
typedef enum mca_co402_state {
    MCA_CO402_NOT_READY = 0,
    MCA_CO402_SWITCH_ON_DISABLED,
    MCA_CO402_READY_TO_SWITCH_ON,
    MCA_CO402_SWITCHED_ON,
    MCA_CO402_OPERATION_ENABLED,
    MCA_CO402_QUICK_STOP_ACTIVE,
    MCA_CO402_FAULT_REACTION_ACTIVE,
    MCA_CO402_FAULT,
} mca_co402_state_t;

/** Controlword commands (bits 0..3 and 7). */
enum {
    MCA_CO402_CW_DISABLE_VOLTAGE = 0x0000,
    MCA_CO402_CW_QUICK_STOP = 0x0002,
    MCA_CO402_CW_SHUTDOWN = 0x0006,
    MCA_CO402_CW_SWITCH_ON = 0x0007,
    MCA_CO402_CW_ENABLE_OPERATION = 0x000F,
    MCA_CO402_CW_FAULT_RESET = 0x0080,
};

/** Statusword bits used. */
enum {
    MCA_CO402_SW_FAULT = 1u << 3,
    MCA_CO402_SW_WARNING = 1u << 7,
    MCA_CO402_SW_REMOTE = 1u << 9,
    MCA_CO402_SW_TARGET_REACHED = 1u << 10,
};

/** Drive state named by a statusword (CiA 402 table: masks 0x4F / 0x6F). */
mca_co402_state_t mca_co402_state(uint16_t statusword);
/** Constant name ("OPERATION_ENABLED", ...); never NULL. */
const char *mca_co402_state_name(mca_co402_state_t s);
/** Statusword a drive in state @p s reports (bits 0..6, voltage enabled (bit 4) from SWITCHED_ON on). */
uint16_t mca_co402_statusword(mca_co402_state_t s);

/** What the master wants of a drive. */
typedef enum mca_co402_goal {
    MCA_CO402_GOAL_DISABLED = 0,    /**< switch-on disabled (voltage off) */
    MCA_CO402_GOAL_ENABLED = 1,     /**< operation enabled */
    MCA_CO402_GOAL_QUICK_STOP = 2,  /**< quick stop (from OPERATION_ENABLED), else disabled */
    MCA_CO402_GOAL_SWITCHED_ON = 3, /**< switched on, operation disabled ("ready": one controlword from
                                         OPERATION_ENABLED; from OPERATION_ENABLED the drive stops with its
                                         disable-operation ramp) */
} mca_co402_goal_t;

/**
 * The controlword that moves a drive in state @p s one transition towards @p goal. FAULT is left only
 * when @p fault_reset is set (the operator asked), with the fault-reset bit (the caller sends a 0 bit
 * first to make the rising edge: @p prev_cw is the last controlword sent).
 */
uint16_t mca_co402_controlword(mca_co402_state_t s, mca_co402_goal_t goal, int fault_reset, uint16_t prev_cw);

/** Drive-side state machine (the emulator's): the state after controlword @p cw in state @p s.
 *  FAULT_REACTION_ACTIVE and NOT_READY are left by the drive itself, not by a controlword. */
mca_co402_state_t mca_co402_drive_next(mca_co402_state_t s, uint16_t cw, uint16_t prev_cw);

/* ---- the master --------------------------------------------------------------------------------- */

/** Named faults of a bus/arm (mca_co_master_t.fault). */
typedef enum mca_co_fault_kind {
    MCA_CO_FAULT_NONE = 0,
    MCA_CO_FAULT_DRIVE = 1,     /**< a drive reports FAULT or FAULT_REACTION_ACTIVE (statusword) */
    MCA_CO_FAULT_EMCY = 2,      /**< an emergency message with a non-zero code */
    MCA_CO_FAULT_HEARTBEAT = 3, /**< a heartbeat missed its consumer time, or an unexpected boot-up */
    MCA_CO_FAULT_PDO = 4,       /**< a TPDO not refreshed within pdo_timeout_cycles SYNCs */
    MCA_CO_FAULT_SDO = 5,       /**< an SDO abort or timeout at start-up */
    MCA_CO_FAULT_BUS = 6,       /**< socket error / bus-off */
    MCA_CO_FAULT_NMT = 7,       /**< a node left OPERATIONAL, or did not boot */
} mca_co_fault_kind_t;

/** Constant name ("DRIVE_FAULT", "EMCY", "HEARTBEAT", ...); never NULL. */
const char *mca_co_fault_name(unsigned kind);

/** The first fault latched (later ones are counted, not overwritten). */
typedef struct mca_co_fault {
    uint8_t kind;  /**< mca_co_fault_kind_t */
    uint8_t node;  /**< the node concerned (0: the bus) */
    uint32_t code; /**< EMCY code, SDO abort code, statusword, ... */
} mca_co_fault_t;

/** Per-drive configuration. */
typedef struct mca_co_drive_config {
    uint8_t node;        /**< 1..127 */
    double pos_scale;    /**< position counts per rad (0x6064 / 0x607A) */
    double vel_scale;    /**< velocity counts per rad/s (0x606C / 0x60FF) */
    double torque_scale; /**< torque counts per N m (0x6077), 0: not mapped */
} mca_co_drive_config_t;

typedef struct mca_co_master_config {
    char iface[16];
    int n; /**< drives, 1..MCA_CO_MAX_NODES */
    mca_co_drive_config_t drive[MCA_CO_MAX_NODES];
    int mode;                /**< MCA_CO402_MODE_CSV or MCA_CO402_MODE_CSP */
    uint32_t sync_period_us; /**< SYNC period = interpolation period (0x60C2 = value us, index -6) */
    uint16_t hb_period_ms;   /**< heartbeat producer time written to each drive (0x1017) */
    uint16_t hb_timeout_ms;  /**< heartbeat consumer time (> hb_period_ms) */
    int pdo_timeout_cycles;  /**< SYNCs without a fresh TPDO1 before MCA_CO_FAULT_PDO, >= 1 */
    int sdo_timeout_ms;      /**< per SDO request at start-up */
    int boot_timeout_ms;     /**< waiting for boot-ups after the NMT reset */
} mca_co_master_config_t;

/** Defaults: CSV, SYNC 4 ms (the bus-load table of docs/canopen.md: six drives at 1 Mbit/s classic CAN),
 *  heartbeat 100 ms produced / 350 ms consumed, PDO timeout 5 SYNCs, SDO 200 ms, boot 2 s, scales
 *  1e6 counts per rad and per rad/s (the drive emulator's units). */
void mca_co_master_config_default(mca_co_master_config_t *cfg, int n, uint8_t first_node);

/** One drive, as the master sees it. */
typedef struct mca_co_drive {
    mca_co_drive_config_t cfg;
    uint8_t nmt;         /**< last heartbeat state */
    int64_t hb_ns;       /**< time of the last heartbeat */
    uint8_t booted;      /**< a boot-up was seen since the reset */
    uint8_t op_seen;     /**< an OPERATIONAL heartbeat was seen since the NMT start (a heartbeat the drive
                              sent before it took the start may still arrive: not a fault) */
    uint16_t statusword; /**< from TPDO1 */
    int32_t pos_counts, vel_counts;
    int16_t torque_counts;
    uint64_t tpdo1_sync, tpdo2_sync; /**< SYNC count at the last TPDO1/2 */
    uint64_t tpdo1_rx, tpdo2_rx;     /**< TPDOs received */
    uint16_t cw;                     /**< last controlword sent */
    double target;                   /**< velocity [rad/s] (CSV) or position [rad] (CSP) */
    mca_co_emcy_t emcy;              /**< newest EMCY */
    uint64_t emcy_rx;
} mca_co_drive_t;

typedef enum mca_co_master_phase {
    MCA_CO_PHASE_CLOSED = 0,
    MCA_CO_PHASE_OPEN = 1,    /**< socket open: NMT and SDO allowed */
    MCA_CO_PHASE_RUNNING = 2, /**< configured, nodes OPERATIONAL: cyclic tick only */
} mca_co_master_phase_t;

/** The master. Caller-owned storage; mca_co_master_*() write it. */
typedef struct mca_co_master {
    mca_co_master_config_t cfg;
    int fd;
    mca_co_master_phase_t phase;
    mca_co402_goal_t goal;
    int fault_reset; /**< the operator asked for a fault reset */
    mca_co_drive_t d[MCA_CO_MAX_NODES];
    uint64_t syncs; /**< SYNCs sent */
    int64_t last_rx_ns;
    int64_t start_ns;     /**< time of the NMT start (CLOCK_MONOTONIC) */
    mca_co_fault_t fault; /**< first latched fault (kind NONE: none) */
    uint64_t faults;      /**< faults seen (the first is latched) */
    uint64_t rx_frames, rx_unknown, tx_frames, tx_again, bus_errors;
    char err[256]; /**< start-up error text */
} mca_co_master_t;

/** Open the socket on cfg->iface (start-up). @retval MCA_OK, MCA_EINVAL, MCA_ENOTSUP (no SocketCAN),
 *  MCA_ENOENT (no such interface), MCA_EIO; the reason in m->err. */
int mca_co_master_open(mca_co_master_t *m, const mca_co_master_config_t *cfg);

/** Send one NMT command (OPEN phase only). @retval MCA_OK, MCA_ESTATE, MCA_EIO, MCA_EINVAL */
int mca_co_nmt_send(mca_co_master_t *m, uint8_t cmd, uint8_t node);

/**
 * Blocking SDO transfers (OPEN phase only; each request waits up to cfg.sdo_timeout_ms). Other frames
 * received meanwhile (boot-ups, heartbeats, EMCYs) are processed as by the tick.
 * @param[out] abort the abort code when MCA_EIO (0 on a socket error); may be NULL
 * @retval MCA_OK, MCA_EINVAL, MCA_ESTATE (RUNNING), MCA_EIO (aborted: m->err names node, object and the
 *         abort text), MCA_ETIMEDOUT (no answer; the client sent an abort)
 */
int mca_co_sdo_download(mca_co_master_t *m, uint8_t node, uint16_t index, uint8_t sub, const void *data,
                        size_t len, uint32_t *abort);
int mca_co_sdo_upload(mca_co_master_t *m, uint8_t node, uint16_t index, uint8_t sub, void *buf, size_t cap,
                      size_t *len, uint32_t *abort);

/**
 * Start-up (blocking): NMT reset communication of every drive and wait for their boot-ups; check the
 * device type (0x1000: profile 402); write the heartbeat producer time, the PDO layout (RPDO1 =
 * controlword + target velocity (CSV) or target position (CSP); TPDO1 = statusword + position actual;
 * TPDO2 = velocity actual + torque actual; all synchronous, type 1), the mode (0x6060) and the
 * interpolation period (0x60C2); NMT start; phase RUNNING. On error the fault is latched (SDO abort ->
 * MCA_CO_FAULT_SDO with the node and abort code) and m->err says what failed.
 * @retval MCA_OK, MCA_ESTATE (not OPEN), MCA_ETIMEDOUT (no boot-up), MCA_EIO (SDO abort / socket), MCA_EINVAL
 */
int mca_co_master_start(mca_co_master_t *m);

/** What the drives should be (real-time safe): the tick sends the controlwords that get them there. */
void mca_co_master_set_goal(mca_co_master_t *m, mca_co402_goal_t goal);
/** Ask for a fault reset (operator action): the next ticks send the fault-reset edge to drives in FAULT,
 *  and the latched master fault is cleared. */
void mca_co_master_fault_reset(mca_co_master_t *m);
/** This cycle's setpoint of drive @p j: [rad/s] in CSV, [rad] in CSP. @retval MCA_OK, MCA_EINVAL */
int mca_co_master_set_target(mca_co_master_t *m, int j, double target);

/**
 * One cycle (real-time safe, RUNNING only): drain received frames (TPDOs, heartbeats, EMCYs, boot-ups),
 * check heartbeat and PDO timeouts, then send each drive's RPDO1 and one SYNC.
 * @param[in] now_ns CLOCK_MONOTONIC
 * @retval MCA_OK      sent, no fault latched
 * @retval MCA_EFAULT  a fault is latched (m->fault); the RPDOs and SYNC were still sent
 * @retval MCA_EAGAIN  the transmit queue was full (counted in tx_again)
 * @retval MCA_EIO     socket error
 * @retval MCA_ESTATE  not RUNNING
 */
int mca_co_master_tick(mca_co_master_t *m, int64_t now_ns);

/** Drain received frames only (no send; real-time safe). @return frames processed, or MCA_EIO */
int mca_co_master_poll(mca_co_master_t *m, int64_t now_ns);

/** Feedback of drive @p j in SI units (from its newest TPDOs). @retval MCA_OK, MCA_EINVAL */
int mca_co_master_joint(const mca_co_master_t *m, int j, double *pos, double *vel, double *torque);

/** 1 when every drive reports OPERATION_ENABLED. */
int mca_co_master_all_enabled(const mca_co_master_t *m);

/** Handle one received frame (the tick does this; exposed for tests). */
void mca_co_master_rx(mca_co_master_t *m, const mca_co_frame_t *f, int64_t now_ns);

/** Stop the nodes (NMT stop if RUNNING is left) and close the socket (shut-down). NULL-safe. */
void mca_co_master_close(mca_co_master_t *m);

/** One line describing the latched fault ("node 3: EMCY 0x2310 current ..."), into buf. */
void mca_co_fault_describe(const mca_co_fault_t *f, char *buf, size_t len);

/** Open a classic CAN raw socket on @p iface, non-blocking, standard data frames and bus-off/error
 *  frames, kernel time stamps (start-up). Used by the master and the drive emulator.
 *  @retval MCA_OK, MCA_EINVAL, MCA_ENOTSUP, MCA_ENOENT, MCA_EIO */
int mca_co_sock_open(int *fd, const char *iface, char *err, size_t errlen);

/* ---- the arm backend (mca/arm.h) ------------------------------------------------------------------ */

struct mca_arm;

/**
 * Open the `canopen` backend of mca/arm.h: one arm = the drives of @p cfg on one bus, joint j = drive j
 * (start-up: allocates, and runs mca_co_master_open + mca_co_master_start, blocking up to their timeouts).
 * The controller writes every @p ctrl_period_us; the backend sends the RPDOs and a SYNC every
 * cfg->sync_period_us / ctrl_period_us writes (an integer >= 1: e.g. 1 kHz control over a 4 ms SYNC) and
 * holds the newest setpoint in between. The open brings every drive to SWITCHED_ON (= READY). Command
 * flags: every joint SERVO_ENABLE|BRAKE_RELEASE -> OPERATION ENABLED (one controlword: taken at the next
 * SYNC with its setpoint); otherwise -> SWITCHED_ON (disable operation: the drive stops on its ramp);
 * while a fault is latched -> quick stop (every drive of the arm brakes at its quick-stop deceleration);
 * CLEAR_FAULT on any joint -> fault reset (the operator).
 * CSV: target velocity = cmd velocity; CSP: target position = the integral of cmd velocity from the
 * position at enable. Feedback is new when every drive's TPDO1 and TPDO2 were refreshed since the last
 * feedback; state SERVOING (all enabled), BRAKING (not all enabled and still moving), FAULT (a fault
 * latched and stopped: fault_code MCA_ARM_FAULT_DRIVE/EMCY/HEARTBEAT/PDO/SDO/NMT/BUS), READY otherwise.
 * @param[out] err the reason on failure (node, object, abort text; may be NULL)
 * @retval MCA_OK, MCA_EINVAL (configuration, period ratio), MCA_ENOMEM, and mca_co_master_open/start codes
 */
int mca_canopen_backend_open(struct mca_arm **arm, const mca_co_master_config_t *cfg, uint32_t ctrl_period_us,
                             char *err, size_t errlen);

/** The latched CANopen fault of a `canopen` arm in words ("node 3: EMCY 0x2310 (current)"; "no fault");
 *  non-real-time (the daemon's report). @retval MCA_OK, MCA_EINVAL (NULL or not a canopen arm) */
int mca_canopen_backend_fault(const struct mca_arm *arm, char *buf, size_t len);

/** The master of a `canopen` arm (tests, tools), or NULL. */
const mca_co_master_t *mca_canopen_backend_master(const struct mca_arm *arm);

#ifdef __cplusplus
}
#endif
#endif
