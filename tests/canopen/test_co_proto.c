/* SPDX-License-Identifier: MIT */
/* cmocka: the CANopen codec of mca/canopen.h without sockets: frame layouts (CiA 301 byte tables), the
 * SDO client against hand-written server answers and against the SDO server (expedited, segmented,
 * aborts), the CiA 402 state machine, and the master's receive path (fault latching). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>

#include "mca/can_sock.h" /* mca_can_frame_t */
#include "mca/canopen.h"
#include "mca/err.h"

static mca_co_frame_t fr(uint16_t id, uint8_t len, const uint8_t *d) {
    mca_co_frame_t f;
    memset(&f, 0, sizeof(f));
    f.id = id;
    f.len = len;
    memcpy(f.data, d, len);
    return f;
}

static void assert_bytes(const mca_co_frame_t *f, uint16_t id, uint8_t len, const uint8_t *want) {
    assert_int_equal(f->id, id);
    assert_int_equal(f->len, len);
    assert_memory_equal(f->data, want, len);
}

static void test_classify(void **state) {
    (void)state;
    uint8_t node = 99, pdo = 99;
    assert_int_equal(mca_co_classify(0x000, &node, &pdo), MCA_CO_K_NMT);
    assert_int_equal(node, 0);
    assert_int_equal(mca_co_classify(0x080, &node, &pdo), MCA_CO_K_SYNC);
    assert_int_equal(mca_co_classify(0x085, &node, &pdo), MCA_CO_K_EMCY);
    assert_int_equal(node, 5);
    assert_int_equal(mca_co_classify(0x185, &node, &pdo), MCA_CO_K_TPDO);
    assert_int_equal(pdo, 1);
    assert_int_equal(mca_co_classify(0x286, &node, &pdo), MCA_CO_K_TPDO);
    assert_int_equal(pdo, 2);
    assert_int_equal(node, 6);
    assert_int_equal(mca_co_classify(0x201, &node, &pdo), MCA_CO_K_RPDO);
    assert_int_equal(pdo, 1);
    assert_int_equal(mca_co_classify(0x50A, &node, &pdo), MCA_CO_K_RPDO);
    assert_int_equal(pdo, 4);
    assert_int_equal(mca_co_classify(0x48A, &node, &pdo), MCA_CO_K_TPDO);
    assert_int_equal(pdo, 4);
    assert_int_equal(mca_co_classify(0x581, &node, &pdo), MCA_CO_K_SDO_TX);
    assert_int_equal(mca_co_classify(0x67F, &node, &pdo), MCA_CO_K_SDO_RX);
    assert_int_equal(node, 127);
    assert_int_equal(mca_co_classify(0x701, &node, &pdo), MCA_CO_K_HB);
    assert_int_equal(mca_co_classify(0x100, &node, &pdo), MCA_CO_K_OTHER); /* TIME */
    assert_int_equal(mca_co_classify(0x7E5, &node, &pdo),
                     MCA_CO_K_OTHER); /* LSS, above the heartbeat range */
}

static void test_nmt_hb_emcy(void **state) {
    (void)state;
    mca_co_frame_t f;
    assert_int_equal(mca_co_nmt_encode(&f, MCA_CO_NMT_START, 3), MCA_OK);
    assert_bytes(&f, 0x000, 2, (const uint8_t[]){0x01, 0x03});
    assert_int_equal(mca_co_nmt_encode(&f, MCA_CO_NMT_RESET_COMM, 0), MCA_OK);
    assert_bytes(&f, 0x000, 2, (const uint8_t[]){0x82, 0x00});
    assert_int_equal(mca_co_nmt_encode(&f, MCA_CO_NMT_START, 128), MCA_EINVAL);
    assert_int_equal(mca_co_hb_encode(&f, 7, MCA_CO_NMT_PREOPERATIONAL), MCA_OK);
    assert_bytes(&f, 0x707, 1, (const uint8_t[]){0x7F});
    assert_int_equal(mca_co_hb_encode(&f, 0, 0), MCA_EINVAL);

    mca_co_emcy_t e = {.code = 0x2310, .reg = 0x03, .mfr = {1, 2, 3, 4, 5}};
    assert_int_equal(mca_co_emcy_encode(&f, 2, &e), MCA_OK);
    assert_bytes(&f, 0x082, 8, (const uint8_t[]){0x10, 0x23, 0x03, 1, 2, 3, 4, 5});
    mca_co_emcy_t d;
    assert_int_equal(mca_co_emcy_decode(&f, &d), MCA_OK);
    assert_int_equal(d.code, 0x2310);
    assert_int_equal(d.reg, 3);
    assert_memory_equal(d.mfr, e.mfr, 5);
    f.len = 7;
    assert_int_equal(mca_co_emcy_decode(&f, &d), MCA_EINVAL);
    assert_string_equal(mca_co_emcy_text(0x2310), "current");
    assert_string_equal(mca_co_emcy_text(0x8130), "life guard or heartbeat error");
    assert_string_equal(mca_co_emcy_text(0x4210), "temperature");
    assert_string_equal(mca_co_emcy_text(0x0000), "error reset or no error");
}

static void test_abort_text(void **state) {
    (void)state;
    assert_string_equal(mca_co_abort_text(0x06020000u), "object does not exist in the object dictionary");
    assert_string_equal(mca_co_abort_text(0x06010002u), "attempt to write a read only object");
    assert_string_equal(mca_co_abort_text(0x06090030u), "invalid value for parameter");
    assert_string_equal(mca_co_abort_text(0x05040000u), "SDO protocol timed out");
    assert_string_equal(mca_co_abort_text(0x12345678u), "unknown abort code");
}

/* client against answers written from the CiA 301 SDO tables */
static void test_sdo_client_expedited(void **state) {
    (void)state;
    mca_co_sdo_client_t c;
    mca_co_frame_t tx, rx;
    const uint16_t hb = 100;
    assert_int_equal(mca_co_sdo_download_start(&c, &tx, 5, 0x1017, 0, &hb, 2), MCA_OK);
    assert_bytes(&tx, 0x605, 8, (const uint8_t[]){0x2B, 0x17, 0x10, 0x00, 0x64, 0x00, 0, 0});
    rx = fr(0x586, 8, (const uint8_t[]){0x60, 0x17, 0x10, 0, 0, 0, 0, 0}); /* another node's answer */
    assert_int_equal(mca_co_sdo_client_rx(&c, &rx, &tx), MCA_CO_SDO_WAIT);
    rx = fr(0x585, 8, (const uint8_t[]){0x60, 0x17, 0x10, 0, 0, 0, 0, 0});
    assert_int_equal(mca_co_sdo_client_rx(&c, &rx, &tx), MCA_CO_SDO_DONE);

    const uint32_t cob = 0x80000185u;
    assert_int_equal(mca_co_sdo_download_start(&c, &tx, 5, 0x1800, 1, &cob, 4), MCA_OK);
    assert_bytes(&tx, 0x605, 8, (const uint8_t[]){0x23, 0x00, 0x18, 0x01, 0x85, 0x01, 0x00, 0x80});
    const uint8_t mode = 9;
    assert_int_equal(mca_co_sdo_download_start(&c, &tx, 5, 0x6060, 0, &mode, 1), MCA_OK);
    assert_int_equal(tx.data[0], 0x2F);

    assert_int_equal(mca_co_sdo_upload_start(&c, &tx, 5, 0x1000, 0), MCA_OK);
    assert_bytes(&tx, 0x605, 8, (const uint8_t[]){0x40, 0x00, 0x10, 0x00, 0, 0, 0, 0});
    rx = fr(0x585, 8, (const uint8_t[]){0x43, 0x00, 0x10, 0x00, 0x92, 0x01, 0x02, 0x00});
    assert_int_equal(mca_co_sdo_client_rx(&c, &rx, &tx), MCA_CO_SDO_DONE);
    assert_int_equal(c.len, 4);
    assert_memory_equal(c.data, ((const uint8_t[]){0x92, 0x01, 0x02, 0x00}), 4);

    /* 2-byte expedited answer (n = 2) */
    assert_int_equal(mca_co_sdo_upload_start(&c, &tx, 5, 0x6041, 0), MCA_OK);
    rx = fr(0x585, 8, (const uint8_t[]){0x4B, 0x41, 0x60, 0x00, 0x37, 0x00, 0xEE, 0xEE});
    assert_int_equal(mca_co_sdo_client_rx(&c, &rx, &tx), MCA_CO_SDO_DONE);
    assert_int_equal(c.len, 2);
    /* answer for another object: our abort (command specifier) */
    assert_int_equal(mca_co_sdo_upload_start(&c, &tx, 5, 0x6041, 0), MCA_OK);
    rx = fr(0x585, 8, (const uint8_t[]){0x4B, 0x64, 0x60, 0x00, 0x37, 0x00, 0, 0});
    assert_int_equal(mca_co_sdo_client_rx(&c, &rx, &tx), MCA_CO_SDO_ABORTED);
    assert_int_equal(c.by_server, 0);
    assert_bytes(&tx, 0x605, 8, (const uint8_t[]){0x80, 0x41, 0x60, 0x00, 0x01, 0x00, 0x04, 0x05});
}

static void test_sdo_client_segmented_upload(void **state) {
    (void)state;
    mca_co_sdo_client_t c;
    mca_co_frame_t tx, rx;
    assert_int_equal(mca_co_sdo_upload_start(&c, &tx, 1, 0x1008, 0), MCA_OK);
    rx = fr(0x581, 8, (const uint8_t[]){0x41, 0x08, 0x10, 0x00, 12, 0, 0, 0});
    assert_int_equal(mca_co_sdo_client_rx(&c, &rx, &tx), MCA_CO_SDO_SEND);
    assert_bytes(&tx, 0x601, 8, (const uint8_t[]){0x60, 0, 0, 0, 0, 0, 0, 0});
    rx = fr(0x581, 8, (const uint8_t[]){0x00, 'm', 'c', 'a', '-', 'd', 'r', 'i'});
    assert_int_equal(mca_co_sdo_client_rx(&c, &rx, &tx), MCA_CO_SDO_SEND);
    assert_bytes(&tx, 0x601, 8, (const uint8_t[]){0x70, 0, 0, 0, 0, 0, 0, 0});
    rx = fr(0x581, 8, (const uint8_t[]){0x15, 'v', 'e', 's', 'i', 'm', 0, 0}); /* toggle 1, n = 2, last */
    assert_int_equal(mca_co_sdo_client_rx(&c, &rx, &tx), MCA_CO_SDO_DONE);
    assert_int_equal(c.len, 12);
    assert_memory_equal(c.data, "mca-drivesim", 12);

    /* toggle not alternated: the client aborts with 0x05030000 */
    assert_int_equal(mca_co_sdo_upload_start(&c, &tx, 1, 0x1008, 0), MCA_OK);
    rx = fr(0x581, 8, (const uint8_t[]){0x41, 0x08, 0x10, 0x00, 12, 0, 0, 0});
    assert_int_equal(mca_co_sdo_client_rx(&c, &rx, &tx), MCA_CO_SDO_SEND);
    rx = fr(0x581, 8, (const uint8_t[]){0x10, 'm', 'c', 'a', '-', 'd', 'r', 'i'});
    assert_int_equal(mca_co_sdo_client_rx(&c, &rx, &tx), MCA_CO_SDO_ABORTED);
    assert_int_equal(c.abort_code, MCA_CO_ABORT_TOGGLE);
    assert_bytes(&tx, 0x601, 8, (const uint8_t[]){0x80, 0x08, 0x10, 0x00, 0x00, 0x00, 0x03, 0x05});

    /* the server aborts */
    assert_int_equal(mca_co_sdo_upload_start(&c, &tx, 1, 0x2222, 3), MCA_OK);
    rx = fr(0x581, 8, (const uint8_t[]){0x80, 0x22, 0x22, 0x03, 0x00, 0x00, 0x02, 0x06});
    assert_int_equal(mca_co_sdo_client_rx(&c, &rx, &tx), MCA_CO_SDO_ABORTED);
    assert_int_equal(c.by_server, 1);
    assert_int_equal(c.abort_code, MCA_CO_ABORT_NO_OBJECT);

    mca_co_sdo_client_timeout(&c, &tx);
    assert_int_equal(c.abort_code, MCA_CO_ABORT_TIMEOUT);
    assert_int_equal(tx.data[0], 0x80);
}

static void test_sdo_client_segmented_download(void **state) {
    (void)state;
    mca_co_sdo_client_t c;
    mca_co_frame_t tx, rx;
    const char *s = "JACO2 joint 1"; /* 13 bytes: segments of 7 and 6 */
    assert_int_equal(mca_co_sdo_download_start(&c, &tx, 2, 0x2002, 0, s, 13), MCA_OK);
    assert_bytes(&tx, 0x602, 8, (const uint8_t[]){0x21, 0x02, 0x20, 0x00, 13, 0, 0, 0});
    rx = fr(0x582, 8, (const uint8_t[]){0x60, 0x02, 0x20, 0x00, 0, 0, 0, 0});
    assert_int_equal(mca_co_sdo_client_rx(&c, &rx, &tx), MCA_CO_SDO_SEND);
    assert_bytes(&tx, 0x602, 8, (const uint8_t[]){0x00, 'J', 'A', 'C', 'O', '2', ' ', 'j'});
    rx = fr(0x582, 8, (const uint8_t[]){0x20, 0, 0, 0, 0, 0, 0, 0});
    assert_int_equal(mca_co_sdo_client_rx(&c, &rx, &tx), MCA_CO_SDO_SEND);
    assert_bytes(&tx, 0x602, 8, (const uint8_t[]){0x13, 'o', 'i', 'n', 't', ' ', '1', 0}); /* t1, n1, c */
    rx = fr(0x582, 8, (const uint8_t[]){0x30, 0, 0, 0, 0, 0, 0, 0});
    assert_int_equal(mca_co_sdo_client_rx(&c, &rx, &tx), MCA_CO_SDO_DONE);
    assert_int_equal(mca_co_sdo_download_start(&c, &tx, 2, 0x2002, 0, s, 0), MCA_EINVAL);
    assert_int_equal(mca_co_sdo_download_start(&c, &tx, 0, 0x2002, 0, s, 1), MCA_EINVAL);
}

/* ---- client against the server ---- */

typedef struct od_fixture {
    uint32_t devtype;
    int8_t mode;
    uint16_t ro;
    char name[24];
    uint32_t map;
    int written, reject;
    mca_co_od_entry_t od[5];
} od_fixture_t;

static uint32_t on_written(void *user, const mca_co_od_entry_t *e) {
    od_fixture_t *o = user;
    o->written++;
    if (e->index == 0x1600 && o->reject) {
        return MCA_CO_ABORT_NO_MAP;
    }
    return 0;
}

static void od_setup(od_fixture_t *o) {
    memset(o, 0, sizeof(*o));
    o->devtype = 0x00020192u;
    strcpy(o->name, "mca-drivesim");
    const mca_co_od_entry_t od[] = {
        {0x1000, 0, MCA_CO_ACC_RO, 4, 0, 0, 1, 0, &o->devtype},
        {0x1008, 0, MCA_CO_ACC_RW, sizeof(o->name), 1, 0, 1, 0, o->name},
        {0x1600, 1, MCA_CO_ACC_RW, 4, 0, 0, 1, 0, &o->map},
        {0x6041, 0, MCA_CO_ACC_RO | MCA_CO_ACC_PDO, 2, 0, 0, 1, 0, &o->ro},
        {0x6060, 0, MCA_CO_ACC_RW, 1, 0, 1, 8, 9, &o->mode},
    };
    memcpy(o->od, od, sizeof(od));
}

/* run one transfer between client and server; returns the final client status */
static mca_co_sdo_status_t run(mca_co_sdo_client_t *c, mca_co_sdo_server_t *s, mca_co_frame_t *tx) {
    for (int i = 0; i < 40; i++) {
        mca_co_frame_t ans;
        if (mca_co_sdo_server_rx(s, tx, &ans) != 1) {
            return MCA_CO_SDO_IDLE;
        }
        const mca_co_sdo_status_t st = mca_co_sdo_client_rx(c, &ans, tx);
        if (st != MCA_CO_SDO_SEND) {
            return st;
        }
    }
    return MCA_CO_SDO_IDLE;
}

static void test_sdo_client_server(void **state) {
    (void)state;
    od_fixture_t o;
    od_setup(&o);
    mca_co_sdo_server_t s;
    assert_int_equal(mca_co_sdo_server_init(&s, 4, o.od, 5, on_written, &o), MCA_OK);
    mca_co_sdo_client_t c;
    mca_co_frame_t tx;

    assert_int_equal(mca_co_sdo_upload_start(&c, &tx, 4, 0x1008, 0), MCA_OK);
    assert_int_equal(run(&c, &s, &tx), MCA_CO_SDO_DONE);
    assert_int_equal(c.len, 12);
    assert_memory_equal(c.data, "mca-drivesim", 12);

    const char *nm = "a longer device name!"; /* 21 bytes: 3 segments */
    assert_int_equal(mca_co_sdo_download_start(&c, &tx, 4, 0x1008, 0, nm, strlen(nm)), MCA_OK);
    assert_int_equal(run(&c, &s, &tx), MCA_CO_SDO_DONE);
    assert_string_equal(o.name, nm);
    assert_int_equal(mca_co_sdo_upload_start(&c, &tx, 4, 0x1008, 0), MCA_OK);
    assert_int_equal(run(&c, &s, &tx), MCA_CO_SDO_DONE);
    assert_int_equal(c.len, strlen(nm));

    const int8_t csp = 8, bad = 3;
    assert_int_equal(mca_co_sdo_download_start(&c, &tx, 4, 0x6060, 0, &csp, 1), MCA_OK);
    assert_int_equal(run(&c, &s, &tx), MCA_CO_SDO_DONE);
    assert_int_equal(o.mode, 8);
    assert_int_equal(mca_co_sdo_download_start(&c, &tx, 4, 0x6060, 0, &bad, 1), MCA_OK);
    assert_int_equal(run(&c, &s, &tx), MCA_CO_SDO_ABORTED);
    assert_int_equal(c.abort_code, MCA_CO_ABORT_VALUE);
    assert_int_equal(o.mode, 8); /* unchanged */

    const uint16_t w = 1;
    assert_int_equal(mca_co_sdo_download_start(&c, &tx, 4, 0x6041, 0, &w, 2), MCA_OK);
    assert_int_equal(run(&c, &s, &tx), MCA_CO_SDO_ABORTED);
    assert_int_equal(c.abort_code, MCA_CO_ABORT_READ_ONLY);
    assert_int_equal(mca_co_sdo_upload_start(&c, &tx, 4, 0x6042, 0), MCA_OK);
    assert_int_equal(run(&c, &s, &tx), MCA_CO_SDO_ABORTED);
    assert_int_equal(c.abort_code, MCA_CO_ABORT_NO_OBJECT);
    assert_int_equal(mca_co_sdo_upload_start(&c, &tx, 4, 0x1600, 2), MCA_OK);
    assert_int_equal(run(&c, &s, &tx), MCA_CO_SDO_ABORTED);
    assert_int_equal(c.abort_code, MCA_CO_ABORT_NO_SUB);
    /* wrong length for a 4-byte object */
    assert_int_equal(mca_co_sdo_download_start(&c, &tx, 4, 0x1600, 1, &w, 2), MCA_OK);
    assert_int_equal(run(&c, &s, &tx), MCA_CO_SDO_ABORTED);
    assert_int_equal(c.abort_code, MCA_CO_ABORT_TYPE_LOW);
    /* the application refuses a mapping: old value back */
    const uint32_t map = 0x60400010u;
    assert_int_equal(mca_co_sdo_download_start(&c, &tx, 4, 0x1600, 1, &map, 4), MCA_OK);
    assert_int_equal(run(&c, &s, &tx), MCA_CO_SDO_DONE);
    assert_int_equal(o.map, map);
    o.reject = 1;
    const uint32_t map2 = 0x12340020u;
    assert_int_equal(mca_co_sdo_download_start(&c, &tx, 4, 0x1600, 1, &map2, 4), MCA_OK);
    assert_int_equal(run(&c, &s, &tx), MCA_CO_SDO_ABORTED);
    assert_int_equal(c.abort_code, MCA_CO_ABORT_NO_MAP);
    assert_int_equal(o.map, map);

    /* a request for another node is not answered; a block transfer request is aborted */
    mca_co_frame_t req = fr(0x605, 8, (const uint8_t[]){0x40, 0, 0x10, 0, 0, 0, 0, 0}), ans;
    assert_int_equal(mca_co_sdo_server_rx(&s, &req, &ans), 0);
    req = fr(0x604, 8, (const uint8_t[]){0xA0, 0, 0x10, 0, 0, 0, 0, 0});
    assert_int_equal(mca_co_sdo_server_rx(&s, &req, &ans), 1);
    assert_int_equal(ans.id, 0x584);
    assert_int_equal(ans.data[0], 0x80);
    /* a segment without a transfer */
    req = fr(0x604, 8, (const uint8_t[]){0x60, 0, 0, 0, 0, 0, 0, 0});
    assert_int_equal(mca_co_sdo_server_rx(&s, &req, &ans), 1);
    assert_int_equal(ans.data[0], 0x80);
}

static void test_cia402_states(void **state) {
    (void)state;
    assert_int_equal(mca_co402_state(0x0000), MCA_CO402_NOT_READY);
    assert_int_equal(mca_co402_state(0x0250), MCA_CO402_SWITCH_ON_DISABLED);
    assert_int_equal(mca_co402_state(0x0231), MCA_CO402_READY_TO_SWITCH_ON);
    assert_int_equal(mca_co402_state(0x0233), MCA_CO402_SWITCHED_ON);
    assert_int_equal(mca_co402_state(0x1637), MCA_CO402_OPERATION_ENABLED);
    assert_int_equal(mca_co402_state(0x0617), MCA_CO402_QUICK_STOP_ACTIVE);
    assert_int_equal(mca_co402_state(0x021F), MCA_CO402_FAULT_REACTION_ACTIVE);
    assert_int_equal(mca_co402_state(0x0218), MCA_CO402_FAULT);
    for (int s = MCA_CO402_SWITCH_ON_DISABLED; s <= MCA_CO402_FAULT; s++) {
        assert_int_equal(mca_co402_state(mca_co402_statusword((mca_co402_state_t)s)), s);
    }
    assert_string_equal(mca_co402_state_name(MCA_CO402_OPERATION_ENABLED), "OPERATION_ENABLED");
}

/* master controlwords drive the drive-side machine to the goal; faults only reset when asked */
static void test_cia402_walk(void **state) {
    (void)state;
    mca_co402_state_t s = MCA_CO402_SWITCH_ON_DISABLED;
    uint16_t cw = 0, prev = 0;
    const mca_co402_state_t path[] = {MCA_CO402_READY_TO_SWITCH_ON, MCA_CO402_SWITCHED_ON,
                                      MCA_CO402_OPERATION_ENABLED};
    for (int i = 0; i < 3; i++) {
        cw = mca_co402_controlword(s, MCA_CO402_GOAL_ENABLED, 0, prev);
        s = mca_co402_drive_next(s, cw, prev);
        prev = cw;
        assert_int_equal(s, path[i]);
    }
    assert_int_equal(mca_co402_controlword(s, MCA_CO402_GOAL_ENABLED, 0, prev), 0x000F);
    cw = mca_co402_controlword(s, MCA_CO402_GOAL_QUICK_STOP, 0, prev);
    assert_int_equal(cw, 0x0002);
    s = mca_co402_drive_next(s, cw, prev);
    assert_int_equal(s, MCA_CO402_QUICK_STOP_ACTIVE);
    assert_int_equal(mca_co402_drive_next(s, 0x0002, 0x0002), MCA_CO402_QUICK_STOP_ACTIVE);
    /* back to enabled from quick stop: through SWITCH_ON_DISABLED */
    prev = cw;
    for (int i = 0; i < 4; i++) {
        cw = mca_co402_controlword(s, MCA_CO402_GOAL_ENABLED, 0, prev);
        s = mca_co402_drive_next(s, cw, prev);
        prev = cw;
    }
    assert_int_equal(s, MCA_CO402_OPERATION_ENABLED);

    /* goal SWITCHED_ON: up from SWITCH_ON_DISABLED, down from OPERATION_ENABLED (disable operation), and
       OPERATION_ENABLED is then one controlword away */
    s = MCA_CO402_SWITCH_ON_DISABLED;
    for (int i = 0; i < 3; i++) {
        cw = mca_co402_controlword(s, MCA_CO402_GOAL_SWITCHED_ON, 0, prev);
        s = mca_co402_drive_next(s, cw, prev);
        prev = cw;
    }
    assert_int_equal(s, MCA_CO402_SWITCHED_ON);
    cw = mca_co402_controlword(s, MCA_CO402_GOAL_ENABLED, 0, prev);
    assert_int_equal(mca_co402_drive_next(s, cw, prev), MCA_CO402_OPERATION_ENABLED);
    assert_int_equal(mca_co402_controlword(MCA_CO402_OPERATION_ENABLED, MCA_CO402_GOAL_SWITCHED_ON, 0, 0x0F),
                     0x0007);
    assert_int_equal(mca_co402_drive_next(MCA_CO402_OPERATION_ENABLED, 0x0007, 0x000F),
                     MCA_CO402_SWITCHED_ON);

    /* FAULT stays without the operator */
    s = MCA_CO402_FAULT;
    for (int i = 0; i < 5; i++) {
        cw = mca_co402_controlword(s, MCA_CO402_GOAL_ENABLED, 0, prev);
        assert_int_equal(cw & 0x80, 0);
        s = mca_co402_drive_next(s, cw, prev);
        prev = cw;
    }
    assert_int_equal(s, MCA_CO402_FAULT);
    /* with the reset: a rising edge of bit 7 (a 0 first if the last word had it) */
    prev = 0x80;
    cw = mca_co402_controlword(s, MCA_CO402_GOAL_ENABLED, 1, prev);
    assert_int_equal(cw, 0x0000);
    assert_int_equal(mca_co402_drive_next(s, 0x80, 0x80), MCA_CO402_FAULT); /* held bit: no edge */
    prev = cw;
    cw = mca_co402_controlword(s, MCA_CO402_GOAL_ENABLED, 1, prev);
    assert_int_equal(cw, 0x0080);
    assert_int_equal(mca_co402_drive_next(s, cw, prev), MCA_CO402_SWITCH_ON_DISABLED);
    /* disable voltage from any powered state */
    assert_int_equal(mca_co402_drive_next(MCA_CO402_OPERATION_ENABLED, 0x0000, 0x000F),
                     MCA_CO402_SWITCH_ON_DISABLED);
    assert_int_equal(mca_co402_drive_next(MCA_CO402_OPERATION_ENABLED, 0x0007, 0x000F),
                     MCA_CO402_SWITCHED_ON);
}

/* the master's receive path: which frames latch which named fault (no socket) */
static void test_master_rx_faults(void **state) {
    (void)state;
    static mca_co_master_t m;
    memset(&m, 0, sizeof(m));
    mca_co_master_config_default(&m.cfg, 2, 10);
    m.fd = -1;
    for (int j = 0; j < 2; j++) {
        m.d[j].cfg = m.cfg.drive[j];
    }
    m.phase = MCA_CO_PHASE_RUNNING;
    mca_co_frame_t f = fr(0x18A, 6, (const uint8_t[]){0x37, 0x02, 0x40, 0x42, 0x0F, 0x00}); /* 1000000 */
    mca_co_master_rx(&m, &f, 1000);
    double p = 0, v = 0, t = 0;
    assert_int_equal(mca_co_master_joint(&m, 0, &p, &v, &t), MCA_OK);
    assert_true(p == 1.0);
    f = fr(0x28B, 6, (const uint8_t[]){0xC0, 0xBD, 0xF0, 0xFF, 0xF4, 0x01}); /* -1000000, 500 */
    mca_co_master_rx(&m, &f, 1000);
    assert_int_equal(mca_co_master_joint(&m, 1, &p, &v, &t), MCA_OK);
    assert_true(v == -1.0);
    assert_true(t == 0.5);
    assert_int_equal(m.fault.kind, MCA_CO_FAULT_NONE);
    assert_int_equal(mca_co_master_all_enabled(&m), 0);
    f = fr(0x18B, 6, (const uint8_t[]){0x37, 0x02, 0, 0, 0, 0});
    mca_co_master_rx(&m, &f, 1000);
    assert_int_equal(mca_co_master_all_enabled(&m), 1);

    f = fr(0x08B, 8, (const uint8_t[]){0x10, 0x23, 0x03, 0, 0, 0, 0, 0});
    mca_co_master_rx(&m, &f, 1000);
    assert_int_equal(m.fault.kind, MCA_CO_FAULT_EMCY);
    assert_int_equal(m.fault.node, 11);
    assert_int_equal(m.fault.code, 0x2310);
    char buf[128];
    mca_co_fault_describe(&m.fault, buf, sizeof(buf));
    assert_string_equal(buf, "node 11: EMCY 0x2310 (current)");
    f = fr(0x18A, 6, (const uint8_t[]){0x08, 0x02, 0, 0, 0, 0}); /* FAULT: counted, first one kept */
    mca_co_master_rx(&m, &f, 1000);
    assert_int_equal(m.fault.kind, MCA_CO_FAULT_EMCY);
    assert_int_equal(m.faults, 2);

    mca_co_master_fault_reset(&m);
    assert_int_equal(m.fault.kind, MCA_CO_FAULT_NONE);
    m.fault_reset = 0;
    f = fr(0x70A, 1, (const uint8_t[]){0x00}); /* boot-up while running: the drive was reset */
    mca_co_master_rx(&m, &f, 1000);
    assert_int_equal(m.fault.kind, MCA_CO_FAULT_HEARTBEAT);
    assert_int_equal(m.fault.node, 10);
    memset(&m.fault, 0, sizeof(m.fault));
    f = fr(0x70B, 1, (const uint8_t[]){0x7F}); /* sent before the drive took the NMT start: no fault */
    mca_co_master_rx(&m, &f, 1000);
    assert_int_equal(m.fault.kind, MCA_CO_FAULT_NONE);
    f = fr(0x70B, 1, (const uint8_t[]){0x05});
    mca_co_master_rx(&m, &f, 1000);
    f = fr(0x70B, 1, (const uint8_t[]){0x7F}); /* pre-operational after OPERATIONAL: it left */
    mca_co_master_rx(&m, &f, 1000);
    assert_int_equal(m.fault.kind, MCA_CO_FAULT_NMT);
    memset(&m.fault, 0, sizeof(m.fault));
    f = fr(0x08C, 8, (const uint8_t[]){0x10, 0x23, 0x03, 0, 0, 0, 0, 0}); /* not our node */
    mca_co_master_rx(&m, &f, 1000);
    assert_int_equal(m.fault.kind, MCA_CO_FAULT_NONE);
    f = fr(0x08A, 8, (const uint8_t[]){0, 0, 0, 0, 0, 0, 0, 0}); /* error reset: no fault */
    mca_co_master_rx(&m, &f, 1000);
    assert_int_equal(m.fault.kind, MCA_CO_FAULT_NONE);
    assert_string_equal(mca_co_fault_name(MCA_CO_FAULT_PDO), "PDO_TIMEOUT");
    /* real-time entry points refuse a master without a socket */
    assert_int_equal(mca_co_master_tick(&m, 0), MCA_EINVAL);
    assert_int_equal(mca_co_master_set_target(&m, 2, 0.0), MCA_EINVAL);
}

static void test_master_open_bad(void **state) {
    (void)state;
    static mca_co_master_t m;
    mca_co_master_config_t cfg;
    mca_co_master_config_default(&cfg, 6, 1);
    cfg.drive[3].node = 0;
    assert_int_equal(mca_co_master_open(&m, &cfg), MCA_EINVAL);
    mca_co_master_config_default(&cfg, 6, 1);
    cfg.hb_timeout_ms = cfg.hb_period_ms;
    assert_int_equal(mca_co_master_open(&m, &cfg), MCA_EINVAL);
    mca_co_master_config_default(&cfg, 6, 1);
    cfg.mode = 3;
    assert_int_equal(mca_co_master_open(&m, &cfg), MCA_EINVAL);
}

/* Only classic 11-bit data frames are CANopen frames: an extended id masked to 11 bits would pass for one. */
static void test_frame_from_can(void **state) {
    (void)state;
    mca_can_frame_t c;
    memset(&c, 0, sizeof c);
    c.can_id = 0x185; /* TPDO1 of node 5 */
    c.len = 12;       /* an FD frame: cut to 8 */
    c.fd = 1;
    for (int i = 0; i < 12; i++) {
        c.data[i] = (uint8_t)(i + 1);
    }
    mca_co_frame_t f;
    assert_int_equal(mca_co_frame_from_can(&f, &c), 1);
    assert_int_equal(f.id, 0x185);
    assert_int_equal(f.len, 8);
    assert_int_equal(f.data[7], 8);
    const uint32_t flags[] = {0x80000000u /* EFF */, 0x40000000u /* RTR */, 0x20000000u /* ERR */};
    for (size_t k = 0; k < sizeof flags / sizeof flags[0]; k++) {
        memset(&f, 0xAB, sizeof f);
        c.can_id = 0x185 | flags[k];
        assert_int_equal(mca_co_frame_from_can(&f, &c), 0);
        assert_int_equal(f.id, 0xABAB); /* untouched */
    }
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_classify),
        cmocka_unit_test(test_nmt_hb_emcy),
        cmocka_unit_test(test_abort_text),
        cmocka_unit_test(test_sdo_client_expedited),
        cmocka_unit_test(test_sdo_client_segmented_upload),
        cmocka_unit_test(test_sdo_client_segmented_download),
        cmocka_unit_test(test_sdo_client_server),
        cmocka_unit_test(test_cia402_states),
        cmocka_unit_test(test_cia402_walk),
        cmocka_unit_test(test_master_rx_faults),
        cmocka_unit_test(test_master_open_bad),
        cmocka_unit_test(test_frame_from_can),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
