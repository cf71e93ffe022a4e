/* SPDX-License-Identifier: MIT */
/* Fuzz target: the CANopen receive paths of mca/canopen.h (issue 15) on a sequence of crafted classic
 * frames: the SDO server (mca-drivesim's: expedited and segmented, with a write callback), an SDO client in
 * a transfer (restarted as upload or download when one ends), and the master's receive path (TPDOs,
 * heartbeats, EMCYs, boot-ups; no socket). Record: kind byte, id (2 bytes, 11 bits), length byte (% 9),
 * that many data bytes; kind % 3 picks the receiver. Checks: every server answer is an 8-byte frame on
 * 0x580 + node; transfer lengths and positions stay within MCA_CO_SDO_MAX; an aborted transfer carries a
 * code; a latched fault names a known kind. */
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h> /* abort */
#include <string.h>

#include "mca/canopen.h"
#include "mca/err.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

#define CHECK(x)                                                                                             \
    do {                                                                                                     \
        if (!(x)) {                                                                                          \
            abort();                                                                                         \
        }                                                                                                    \
    } while (0)

static uint32_t u32v, map1;
static int8_t mode;
static uint16_t sw;
static char name[24];

static uint32_t written(void *user, const mca_co_od_entry_t *e) {
    (void)user;
    return (e->index == 0x1600 && map1 == 0xFFFFFFFFu) ? MCA_CO_ABORT_NO_MAP : 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    const mca_co_od_entry_t od[] = {
        {0x1000, 0, MCA_CO_ACC_RO, 4, 0, 0, 1, 0, &u32v},
        {0x1008, 0, MCA_CO_ACC_RW, sizeof(name), 1, 0, 1, 0, name},
        {0x1600, 1, MCA_CO_ACC_RW, 4, 0, 0, 1, 0, &map1},
        {0x6041, 0, MCA_CO_ACC_RO | MCA_CO_ACC_PDO, 2, 0, 0, 1, 0, &sw},
        {0x6060, 0, MCA_CO_ACC_RW, 1, 0, 1, 8, 9, &mode},
    };
    u32v = 0x00020192u;
    map1 = 0;
    mode = 9;
    sw = 0x0237;
    memset(name, 0, sizeof(name));
    memcpy(name, "mca-drivesim", 12);
    mca_co_sdo_server_t srv;
    CHECK(mca_co_sdo_server_init(&srv, 5, od, sizeof(od) / sizeof(od[0]), written, NULL) == MCA_OK);
    mca_co_sdo_client_t cli;
    mca_co_frame_t tx;
    const uint8_t payload[40] = "a segmented download of forty bytes....";
    CHECK(mca_co_sdo_upload_start(&cli, &tx, 5, 0x1008, 0) == MCA_OK);
    static mca_co_master_t m;
    memset(&m, 0, sizeof(m));
    mca_co_master_config_default(&m.cfg, 6, 1);
    for (int j = 0; j < m.cfg.n; j++) {
        m.d[j].cfg = m.cfg.drive[j];
    }
    m.fd = -1;
    m.phase = MCA_CO_PHASE_RUNNING;
    size_t i = 0;
    int restarts = 0;
    while (i < size) {
        const uint8_t kind = data[i++];
        mca_co_frame_t f;
        memset(&f, 0, sizeof(f));
        f.id = (uint16_t)((i < size ? data[i] : 0) | (i + 1 < size ? data[i + 1] : 0) << 8) & 0x7FF;
        i += 2;
        f.len = (uint8_t)((i < size ? data[i] : 0) % 9);
        i++;
        for (unsigned k = 0; k < f.len; k++, i++) {
            f.data[k] = i < size ? data[i] : 0;
        }
        switch (kind % 3) {
        case 0: {
            mca_co_frame_t ans;
            const int r = mca_co_sdo_server_rx(&srv, &f, &ans);
            CHECK(r == 0 || r == 1);
            if (r == 1) {
                CHECK(ans.id == 0x585 && ans.len == 8);
            }
            CHECK(srv.len <= MCA_CO_SDO_MAX && srv.pos <= MCA_CO_SDO_MAX);
            CHECK(mode == 8 || mode == 9);
            break;
        }
        case 1: {
            const mca_co_sdo_status_t st = mca_co_sdo_client_rx(&cli, &f, &tx);
            CHECK(cli.len <= MCA_CO_SDO_MAX && cli.pos <= MCA_CO_SDO_MAX);
            if (st == MCA_CO_SDO_ABORTED) {
                CHECK(cli.abort_code != 0 || cli.by_server);
            }
            if ((st == MCA_CO_SDO_DONE || st == MCA_CO_SDO_ABORTED) && restarts < 64) {
                restarts++;
                if (restarts % 2) {
                    CHECK(mca_co_sdo_download_start(&cli, &tx, 5, 0x1008, 0, payload, 1 + restarts % 39) ==
                          MCA_OK);
                } else {
                    CHECK(mca_co_sdo_upload_start(&cli, &tx, 5, 0x1008, 0) == MCA_OK);
                }
            }
            break;
        }
        default: {
            uint8_t node = 0, pdo = 0;
            const mca_co_kind_t k = mca_co_classify(f.id, &node, &pdo);
            CHECK(k >= MCA_CO_K_OTHER && k <= MCA_CO_K_HB && node <= 127 && pdo <= 4);
            mca_co_master_rx(&m, &f, (int64_t)i * 1000);
            CHECK(m.fault.kind <= MCA_CO_FAULT_NMT);
            char buf[200];
            mca_co_fault_describe(&m.fault, buf, sizeof(buf));
            CHECK(mca_co402_state(m.d[0].statusword) <= MCA_CO402_FAULT);
            break;
        }
        }
    }
    return 0;
}
