/* SPDX-License-Identifier: MIT */
/* Scenario and cell files through libcyaml, errors named by file, line and field; see mca/yaml_load.h. */
#include "mca/yaml_load.h"

#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <yaml.h>

#include "mca/scheme.h" /* MCA_FORM_* */
#include "mca/err.h"
#include "mca/errbuf.h"
#include "mca/yaml_marks.h"

/* libcyaml reports a load error as an error line ("Load: Invalid INT value: 'x'") followed by a backtrace,
 * innermost first: "in mapping field 'priority' (line: 12, column: 13)", "in sequence entry '1' (...)"
 * (1-based entry count), "in mapping (...)". Lines/columns are 1-based and are those of the last event
 * read. Keep the error text and the frames; parse_error() turns them into "FILE:LINE:COL: field". */
enum frame_kind { FR_FIELD, FR_ENTRY, FR_MAPPING };
struct log_state {
    char what[256];
    int have_what;
    int n;
    struct {
        enum frame_kind kind;
        char name[48];
        int entry; /* 0-based sequence index */
        int line, col;
    } fr[10]; /* innermost first */
};

static void log_collect(cyaml_log_t level, void *ctx, const char *fmt, va_list args) {
    struct log_state *s = ctx;
    if (level < CYAML_LOG_ERROR) {
        return;
    }
    char line[256];
    vsnprintf(line, sizeof line, fmt, args);
    size_t n = strlen(line);
    while (n && (line[n - 1] == '\n' || line[n - 1] == ' ')) {
        line[--n] = 0;
    }
    const char *p = line;
    if (strncmp(p, "Load: ", 6) == 0) {
        p += 6;
    }
    while (*p == ' ') {
        p++;
    }
    int kind = -1;
    if (strncmp(p, "in mapping field '", 18) == 0) {
        kind = FR_FIELD;
    } else if (strncmp(p, "in sequence entry '", 19) == 0) {
        kind = FR_ENTRY;
    } else if (strncmp(p, "in mapping", 10) == 0) {
        kind = FR_MAPPING;
    } else if (strncmp(p, "in ", 3) == 0 || strncmp(p, "Backtrace:", 10) == 0) {
        return;
    } else {
        if (!s->have_what && *p) {
            snprintf(s->what, sizeof s->what, "%s", p);
            s->have_what = 1;
        }
        return;
    }
    if (s->n >= 10) {
        return;
    }
    s->fr[s->n].kind = (enum frame_kind)kind;
    s->fr[s->n].name[0] = 0;
    s->fr[s->n].entry = 0;
    if (kind == FR_FIELD) {
        const char *name = p + 18;
        const char *q = strchr(name, '\'');
        snprintf(s->fr[s->n].name, sizeof s->fr[0].name, "%.*s", q ? (int)(q - name) : 0, name);
    } else if (kind == FR_ENTRY) {
        s->fr[s->n].entry = atoi(p + 19) - 1;
    }
    s->fr[s->n].line = s->fr[s->n].col = 0;
    const char *lp = strstr(p, "(line: ");
    if (lp) {
        sscanf(lp, "(line: %d, column: %d)", &s->fr[s->n].line, &s->fr[s->n].col);
    }
    s->n++;
}

/* Message for a libcyaml load failure. */
static void parse_error(const char *path, struct log_state *ls, cyaml_err_t cerr, char *err, size_t errlen) {
    int first = 0; /* innermost frame that belongs to the field path */
    int line = ls->n ? ls->fr[0].line : 0, col = ls->n ? ls->fr[0].col : 0;
    char extra[64] = "";
    const char *missing = "Missing required mapping field: ";
    const char *unexpected = "Unexpected key: ";
    if (strncmp(ls->what, missing, strlen(missing)) == 0) {
        /* the innermost named frame is the last field read, a sibling: the mapping is the next frame */
        if (ls->n && ls->fr[0].kind == FR_FIELD) {
            first = 1;
        }
        snprintf(extra, sizeof extra, "%s", ls->what + strlen(missing));
        line = first < ls->n ? ls->fr[first].line : 0;
        col = first < ls->n ? ls->fr[first].col : 0;
    } else if (strncmp(ls->what, unexpected, strlen(unexpected)) == 0) {
        if (ls->n && ls->fr[0].kind == FR_MAPPING) {
            first = 1;
        }
        snprintf(extra, sizeof extra, "%s", ls->what + strlen(unexpected));
    }
    char field[256] = "";
    for (int i = ls->n - 1; i >= first; i--) {
        const size_t fl = strlen(field);
        if (ls->fr[i].kind == FR_ENTRY) {
            snprintf(field + fl, sizeof field - fl, "[%d]", ls->fr[i].entry);
        } else if (ls->fr[i].kind == FR_FIELD) {
            snprintf(field + fl, sizeof field - fl, "%s%s", fl ? "." : "", ls->fr[i].name);
        }
    }
    if (extra[0]) {
        const size_t fl = strlen(field);
        snprintf(field + fl, sizeof field - fl, "%s%s", fl ? "." : "", extra);
    }
    if (strncmp(ls->what, unexpected, strlen(unexpected)) == 0) {
        /* the key's own line (the file is YAML, only the key is not in the schema) */
        mca_yaml_marks_t marks = {.mark = NULL};
        if (mca_yaml_marks_load(path, &marks, NULL, 0) == MCA_OK) {
            const int l = mca_yaml_marks_line(&marks, field);
            if (l > 0) {
                line = l;
                col = 0;
            }
        }
        mca_yaml_marks_free(&marks);
    }
    char pos[32];
    if (col > 0) {
        snprintf(pos, sizeof pos, "%d:%d", line, col);
    } else {
        snprintf(pos, sizeof pos, "%d", line);
    }
    if (err && errlen) {
        snprintf(err, errlen, "%s:%s: %s: %s (%s)", path, pos, field[0] ? field : "(document)",
                 ls->have_what ? ls->what : "invalid", cyaml_strerror(cerr));
    }
}

static const cyaml_config_t free_cfg = {
    .mem_fn = cyaml_mem,
    .log_level = CYAML_LOG_ERROR,
    .flags = CYAML_CFG_DEFAULT,
};

/* MCA_EPARSE (err set) when the document opens more than MCA_YAML_MAX_DEPTH collections at once, found by
 * reading events only up to that depth. A syntax error is libcyaml's to name (in its words, with the field):
 * MCA_OK then. */
static int depth_check(const char *path, FILE *fp, char *err, size_t errlen) {
    yaml_parser_t parser;
    if (!yaml_parser_initialize(&parser)) {
        mca_errbuf_printf(err, errlen, "%s: out of memory", path);
        return MCA_ENOMEM;
    }
    yaml_parser_set_input_file(&parser, fp);
    int rc = MCA_OK, depth = 0, done = 0;
    while (!done && rc == MCA_OK) {
        yaml_event_t ev;
        if (!yaml_parser_parse(&parser, &ev)) {
            break;
        }
        if (ev.type == YAML_MAPPING_START_EVENT || ev.type == YAML_SEQUENCE_START_EVENT) {
            if (++depth > MCA_YAML_MAX_DEPTH) {
                mca_errbuf_printf(err, errlen, "%s:%lu: nested deeper than %d levels", path,
                                  (unsigned long)ev.start_mark.line + 1, MCA_YAML_MAX_DEPTH);
                rc = MCA_EPARSE;
            }
        } else if (ev.type == YAML_MAPPING_END_EVENT || ev.type == YAML_SEQUENCE_END_EVENT) {
            depth--;
        } else if (ev.type == YAML_DOCUMENT_END_EVENT || ev.type == YAML_STREAM_END_EVENT) {
            done = 1; /* the first document only, as libcyaml loads */
        }
        yaml_event_delete(&ev);
    }
    yaml_parser_delete(&parser);
    return rc;
}

const cyaml_schema_value_t mca_yaml_float_entry = {CYAML_VALUE_FLOAT(CYAML_FLAG_DEFAULT, double)};
const cyaml_strval_t mca_yaml_form_strings[2] = {
    {"componentwise", MCA_FORM_COMPONENTWISE},
    {"normal", MCA_FORM_NORMAL},
};

int mca_yaml_load(const char *path, const char *what, const cyaml_schema_value_t *schema, void **data,
                  mca_yaml_marks_t *marks, char *err, size_t errlen) {
    if (!path || !schema || !data || !marks) {
        mca_errbuf_printf(err, errlen, "yaml load: NULL argument");
        return MCA_EINVAL;
    }
    *data = NULL;
    memset(marks, 0, sizeof *marks);
    FILE *fp = fopen(path, "r");
    if (!fp) {
        mca_errbuf_printf(err, errlen, "%s:0: cannot open %s file: %s", path, what ? what : "YAML",
                          strerror(errno));
        return MCA_ENOENT;
    }
    const int drc = depth_check(path, fp, err, errlen);
    fclose(fp);
    if (drc != MCA_OK) {
        return drc;
    }
    struct log_state ls;
    memset(&ls, 0, sizeof ls);
    const cyaml_config_t cfg = {
        .log_fn = log_collect,
        .log_ctx = &ls,
        .mem_fn = cyaml_mem,
        .log_level = CYAML_LOG_ERROR,
        .flags = CYAML_CFG_DEFAULT,
    };
    cyaml_data_t *raw = NULL;
    const cyaml_err_t cerr = cyaml_load_file(path, &cfg, schema, &raw, NULL);
    if (cerr != CYAML_OK) {
        parse_error(path, &ls, cerr, err, errlen);
        return MCA_EPARSE;
    }
    if (!raw) {
        /* a valid YAML stream with no document: libcyaml returns OK and no data */
        mca_errbuf_printf(
            err, errlen,
            "%s:0: (document): empty document (no YAML mapping: the file is empty or only comments)", path);
        return MCA_EPARSE;
    }
    *data = raw;
    /* where each node is (libcyaml keeps no positions); lines are 0 if the file cannot be read again */
    (void)mca_yaml_marks_load(path, marks, NULL, 0);
    return MCA_OK;
}

void mca_yaml_free(const cyaml_schema_value_t *schema, void *data) {
    if (schema && data) {
        cyaml_free(&free_cfg, schema, data, 0);
    }
}
