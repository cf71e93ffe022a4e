/* SPDX-License-Identifier: MIT */
/* The arm backends mcad knows, one folder each (daemon/backends/NAME/) and one line in the registry
 * (backends.c, MCA_BACKENDS), which gives each its id: its place on that line. Each names itself as cell
 * files do
 * ("backend: NAME"), reads and checks its keys of a cell arm, opens the arm and says what the daemon must
 * know of it; its own section of a cell arm comes with its schema. The cell reader builds the arm schema from
 * the table and looks a backend up by name, the daemon by id; neither switches on names nor knows sections.
 * Private to mca_daemon (cell.c, the daemon's rooms daemon*.c, mcad_main.c). Start-up only, but fault_detail
 * (main thread). */
#ifndef MCA_DAEMON__BACKENDS_H
#define MCA_DAEMON__BACKENDS_H

#include <cyaml/cyaml.h>
#include <stddef.h>

#include "mca/arm.h"
#include "mca/cell.h"
#include "mca/chain.h"
#include "mca/errbuf.h"     /* mca_errbuf_at */
#include "mca/scenario.h"   /* mca_check_ctx_t */
#include "mca/yaml_marks.h" /* mca_yaml_marks_line_of */

/* Most backends the table may hold (the cell's arm schema has room for each one's section). */
#define MCA_BACKEND_MAX 8

/* An arm's backend keys as the cell gives them (NULL: not in the file). */
typedef struct mca_backend_keys {
    const char *interface;
    const long long *id_base;
    const void *section; /* the backend's own section as libcyaml loaded it (its section_fields) */
} mca_backend_keys_t;

/* What a backend's open gets from the daemon. */
typedef struct mca_backend_open_args {
    const mca_cell_t *cell;
    int arm;                               /* index in the cell */
    const mca_chain_t *chain;              /* the arm's model */
    const double *fb_lo, *fb_hi, *fb_vmax; /* the daemon's plausible feedback per joint (its check) */
    int virtual_time;                      /* the driver's virtual time (mca/daemon_drive.h) */
    int ideal;                             /* the driver's ideal arm: follows its command exactly (sim) */
} mca_backend_open_args_t;

/* What a backend does with its arm's interface (the cell's bus clash check, whatever the arms' order). */
typedef enum mca_backend_bus {
    MCA_BUS_NONE = 0,  /* opens no bus (the sim: an interface key is only kept) */
    MCA_BUS_ID_BLOCKS, /* shares its bus, one CAN id block per arm (socketcan) */
    MCA_BUS_OWNED,     /* its bus is its alone, with no arm of any backend beside it (canopen) */
} mca_backend_bus_t;

typedef struct mca_backend_def {
    const char *name;      /* as in cell files */
    mca_backend_bus_t bus; /* its arm's bus: which other arms may share it */
    const char *section;   /* its own mapping in a cell arm ("sim", "canopen"; NULL: none): only with it */
    const cyaml_schema_field_t *section_fields; /* the section's schema: the cell's arm schema takes it */
    size_t section_size;                        /* what libcyaml allocates for it */
    /* check and set arm `a`'s backend keys into cell->arm[a] (arms 0..a-1 are set: bus clashes) */
    int (*read)(const mca_check_ctx_t *c, mca_cell_t *cell, int a, const mca_backend_keys_t *k);
    int (*open)(mca_arm_t **arm, const mca_backend_open_args_t *o, char *err, size_t errlen);
    /* optional (NULL: none): */
    double (*feedback_margin)(const mca_cell_arm_t *ca);  /* added to the position check's margin [rad] */
    int (*reported_joints)(const mca_arm_t *arm, int *n); /* the arm's own joint count once it says it
                                                              (MCA_OK; MCA_EAGAIN: not yet): wait for it */
    int (*fault_detail)(const mca_arm_t *arm, char *buf, size_t len); /* what the arm's fault is about */
    void (*describe)(const mca_cell_arm_t *ca, int n_joints, char *buf, size_t len); /* for mcad --check */
} mca_backend_def_t;

/* The backend named `name`, or NULL. */
const mca_backend_def_t *mca_backend_find(const char *name);

/* The backend of id `id`, or NULL when no backend has it. */
const mca_backend_def_t *mca_backend_get(mca_cell_backend_t id);

/* A backend's id (as in mca_cell_arm_t.backend): its place in the registry. */
mca_cell_backend_t mca_backend_id(const mca_backend_def_t *be);

/* The bus keys every CAN backend shares, for a backend's read: the interface copied (when given) and the id
 * block checked and copied (when given): MCA_OK or MCA_ECONFIG "FILE:LINE: arms[N].id_base: ...". */
int mca_backend_bus_keys(const mca_check_ctx_t *c, mca_cell_t *cell, int a, const mca_backend_keys_t *k);

/* Arm a's bus against every earlier arm's (arms 0..a-1 are read), by what the two backends say of their bus
 * (mca_backend_bus_t), never by which of them comes first: MCA_OK or MCA_ECONFIG naming arm a's field. */
int mca_backend_bus_check(const mca_check_ctx_t *c, const mca_cell_t *cell, int a);

/* A backend's read fails with "FILE:LINE: message" (c: its mca_check_ctx_t *); MCA_BE_LINE(...) is the line
 * of a printf-formatted field path ("arms[1].canopen.sync_us"), or of its nearest enclosing node;
 * MCA_BE_CHECK is the one range check (mca_check_range). */
#define MCA_BE_LINE(...) mca_yaml_marks_line_of(c->marks, __VA_ARGS__)
#define MCA_BE_FAIL(code, line, ...)                                                                         \
    do {                                                                                                     \
        mca_errbuf_at(c->err, c->errlen, c->file, (line), __VA_ARGS__);                                      \
        return (code);                                                                                       \
    } while (0)
#define MCA_BE_CHECK(range, v, ...)                                                                          \
    do {                                                                                                     \
        int rc_ = mca_check_range(c, (range), (v), __VA_ARGS__);                                             \
        if (rc_ != MCA_OK) {                                                                                 \
            return rc_;                                                                                      \
        }                                                                                                    \
    } while (0)

/* Every arm's backend id is one of the table's (a cell changed in code after its file was read may hold any
 * value): MCA_OK, or MCA_ECONFIG with "FILE:LINE: arms[N].backend: unknown backend id ID (known: ...)" in
 * err, LINE that of the arm's backend key in cell->source (0 when the file cannot be read). Start-up. */
int mca_backend_check_ids(const mca_cell_t *cell, char *err, size_t errlen);

/* The known names, ", "-separated ("sim, socketcan, canopen, replay"), for messages. */
void mca_backend_names(char *buf, size_t len);

/* Every backend in turn: i from 0 until NULL. */
const mca_backend_def_t *mca_backend_at(size_t i);

#endif
