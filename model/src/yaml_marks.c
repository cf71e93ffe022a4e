/* SPDX-License-Identifier: MIT */
/* Paths and lines of a YAML file's nodes, from libyaml's events; see mca/yaml_marks.h. Start-up only. */
#include "mca/yaml_marks.h"

#include <errno.h>
#include <limits.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <yaml.h>

#include "mca/err.h"
#include "mca/errbuf.h" /* mca_errbuf_printf */

enum { FR_MAP, FR_SEQ };

/* One open mapping or sequence. Its own path is cur[0..len) of the walk (the paths of the open collections
 * are prefixes of each other, so one buffer holds them all). */
struct frame {
    int kind;
    size_t len;
    int skip;       /* nothing recorded below (path too long, inside a complex key) */
    int want_value; /* mapping: the next node is the value of the key at cur[0..key_len) */
    size_t key_len;
    int key_skip;      /* mapping: that key's path was not recorded (too long, not a scalar) */
    unsigned long idx; /* sequence: index of the next entry */
};

struct walk {
    mca_yaml_marks_t *marks;
    char cur[MCA_YAML_MARKS_PATH_MAX];
    struct frame fr[MCA_YAML_MARKS_MAX_DEPTH];
    int depth;
};

/* Append fmt to the path cur[0..at): 1 and *len the new length, or 0 and *len = at when it does not fit
 * (only cur[at..] is written: the open collections' paths stay). */
static int put(struct walk *w, size_t at, size_t *len, const char *fmt, ...) {
    va_list ap;
    va_start(ap, fmt);
    const int n = vsnprintf(w->cur + at, sizeof w->cur - at, fmt, ap);
    va_end(ap);
    if (n < 0 || (size_t)n >= sizeof w->cur - at) {
        w->cur[at] = 0;
        *len = at;
        return 0;
    }
    *len = at + (size_t)n;
    return 1;
}

static int add(struct walk *w, size_t len, const yaml_mark_t *m) {
    mca_yaml_marks_t *mk = w->marks;
    if (mk->n == mk->cap) {
        if (mk->cap >= MCA_YAML_MARKS_MAX) {
            return MCA_ERANGE;
        }
        size_t cap = mk->cap ? mk->cap * 2 : 64;
        if (cap > MCA_YAML_MARKS_MAX) {
            cap = MCA_YAML_MARKS_MAX;
        }
        mca_yaml_mark_t *p = realloc(mk->mark, cap * sizeof *p);
        if (!p) {
            return MCA_ENOMEM;
        }
        mk->mark = p;
        mk->cap = cap;
    }
    mca_yaml_mark_t *e = &mk->mark[mk->n++];
    memcpy(e->path, w->cur, len);
    e->path[len] = 0;
    e->line = m->line < (size_t)INT_MAX ? (int)m->line + 1 : INT_MAX;
    return MCA_OK;
}

/* A node starts (scalar, alias, mapping or sequence): record its path when it is a key or a sequence
 * entry, and open a frame for a collection. */
static int on_node(struct walk *w, const yaml_event_t *ev) {
    const int coll = ev->type == YAML_MAPPING_START_EVENT || ev->type == YAML_SEQUENCE_START_EVENT;
    size_t len = 0;
    int skip = 0, rc = MCA_OK;
    if (w->depth > 0) {
        struct frame *f = &w->fr[w->depth - 1];
        if (f->kind == FR_MAP && !f->want_value) { /* a key */
            f->want_value = 1;
            if (ev->type == YAML_SCALAR_EVENT) {
                const int fits = put(w, f->len, &f->key_len, "%s%.*s", f->len ? "." : "",
                                     (int)ev->data.scalar.length, (const char *)ev->data.scalar.value);
                f->key_skip = f->skip || !fits;
                return f->key_skip ? MCA_OK : add(w, f->key_len, &ev->start_mark);
            }
            f->key_skip = 1; /* a complex key: neither it nor its value is recorded */
            f->key_len = f->len;
            len = f->len;
            skip = 1;
        } else if (f->kind == FR_MAP) { /* the value of the last key */
            f->want_value = 0;
            len = f->key_len;
            skip = f->key_skip;
        } else { /* a sequence entry */
            const int fits = put(w, f->len, &len, "[%lu]", f->idx++);
            skip = f->skip || !fits;
            if (!skip) {
                rc = add(w, len, &ev->start_mark);
            }
        }
    }
    if (coll && rc == MCA_OK) {
        if (w->depth == MCA_YAML_MARKS_MAX_DEPTH) {
            return MCA_EPARSE; /* stop reading: libyaml's scanner costs the depth per token */
        }
        struct frame *f = &w->fr[w->depth++];
        memset(f, 0, sizeof *f);
        f->kind = ev->type == YAML_MAPPING_START_EVENT ? FR_MAP : FR_SEQ;
        f->len = len;
        f->skip = skip;
    }
    return rc;
}

static int walk(yaml_parser_t *parser, const char *name, mca_yaml_marks_t *marks, char *err, size_t errlen) {
    struct walk *w = calloc(1, sizeof *w);
    if (!w) {
        mca_errbuf_printf(err, errlen, "%s: out of memory", name);
        return MCA_ENOMEM;
    }
    w->marks = marks;
    int rc = MCA_OK, done = 0;
    while (!done && rc == MCA_OK) {
        yaml_event_t ev;
        if (!yaml_parser_parse(parser, &ev)) {
            mca_errbuf_printf(err, errlen, "%s:%lu: %s%s%s", name,
                              (unsigned long)parser->problem_mark.line + 1,
                              parser->problem ? parser->problem : "YAML error", parser->context ? " " : "",
                              parser->context ? parser->context : "");
            rc = parser->error == YAML_MEMORY_ERROR ? MCA_ENOMEM : MCA_EPARSE;
            break;
        }
        switch (ev.type) {
        case YAML_SCALAR_EVENT:
        case YAML_ALIAS_EVENT:
        case YAML_MAPPING_START_EVENT:
        case YAML_SEQUENCE_START_EVENT:
            rc = on_node(w, &ev);
            if (rc == MCA_ERANGE) {
                mca_errbuf_printf(err, errlen, "%s:%lu: more than %d nodes", name,
                                  (unsigned long)ev.start_mark.line + 1, MCA_YAML_MARKS_MAX);
            } else if (rc == MCA_EPARSE) {
                mca_errbuf_printf(err, errlen, "%s:%lu: nested deeper than %d levels", name,
                                  (unsigned long)ev.start_mark.line + 1, MCA_YAML_MARKS_MAX_DEPTH);
            } else if (rc != MCA_OK) {
                mca_errbuf_printf(err, errlen, "%s: out of memory", name);
            }
            break;
        case YAML_MAPPING_END_EVENT:
        case YAML_SEQUENCE_END_EVENT:
            if (w->depth > 0) {
                w->depth--;
            }
            break;
        case YAML_DOCUMENT_END_EVENT: /* the first document only, as libcyaml loads */
        case YAML_STREAM_END_EVENT:
            done = 1;
            break;
        default:
            break;
        }
        yaml_event_delete(&ev);
    }
    free(w);
    return rc;
}

void mca_yaml_marks_free(mca_yaml_marks_t *marks) {
    if (marks) {
        free(marks->mark);
        memset(marks, 0, sizeof *marks);
    }
}

/* Parse with an input already set on parser (name for messages); frees the parser. */
static int load(yaml_parser_t *parser, const char *name, mca_yaml_marks_t *marks, char *err, size_t errlen) {
    memset(marks, 0, sizeof *marks);
    const int rc = walk(parser, name, marks, err, errlen);
    yaml_parser_delete(parser);
    if (rc != MCA_OK) {
        mca_yaml_marks_free(marks);
    }
    return rc;
}

int mca_yaml_marks_load(const char *path, mca_yaml_marks_t *marks, char *err, size_t errlen) {
    if (!path || !marks) {
        mca_errbuf_printf(err, errlen, "yaml marks: NULL argument");
        return MCA_EINVAL;
    }
    memset(marks, 0, sizeof *marks);
    FILE *f = fopen(path, "rb");
    if (!f) {
        mca_errbuf_printf(err, errlen, "%s: cannot open: %s", path, strerror(errno));
        return MCA_ENOENT;
    }
    yaml_parser_t parser;
    if (!yaml_parser_initialize(&parser)) {
        fclose(f);
        mca_errbuf_printf(err, errlen, "%s: out of memory", path);
        return MCA_ENOMEM;
    }
    yaml_parser_set_input_file(&parser, f);
    const int rc = load(&parser, path, marks, err, errlen);
    fclose(f);
    return rc;
}

int mca_yaml_marks_parse(const char *text, size_t len, mca_yaml_marks_t *marks, char *err, size_t errlen) {
    if (!text || !marks) {
        mca_errbuf_printf(err, errlen, "yaml marks: NULL argument");
        return MCA_EINVAL;
    }
    memset(marks, 0, sizeof *marks);
    yaml_parser_t parser;
    if (!yaml_parser_initialize(&parser)) {
        mca_errbuf_printf(err, errlen, "<string>: out of memory");
        return MCA_ENOMEM;
    }
    yaml_parser_set_input_string(&parser, (const unsigned char *)text, len);
    return load(&parser, "<string>", marks, err, errlen);
}

int mca_yaml_marks_line(const mca_yaml_marks_t *marks, const char *path) {
    if (!marks || !path) {
        return 0;
    }
    for (size_t i = 0; i < marks->n; i++) {
        if (strcmp(marks->mark[i].path, path) == 0) {
            return marks->mark[i].line;
        }
    }
    return 0;
}

int mca_yaml_marks_line_of(const mca_yaml_marks_t *marks, const char *fmt, ...) {
    char node[MCA_YAML_MARKS_PATH_MAX];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(node, sizeof node, fmt, ap);
    va_end(ap);
    return mca_yaml_marks_line_or_parent(marks, node);
}

int mca_yaml_marks_line_or_parent(const mca_yaml_marks_t *marks, const char *path) {
    if (!marks || !path) {
        return 0;
    }
    char p[MCA_YAML_MARKS_PATH_MAX];
    snprintf(p, sizeof p, "%s", path);
    for (;;) {
        const int line = mca_yaml_marks_line(marks, p);
        if (line > 0) {
            return line;
        }
        /* drop the last component: ".key" or "[i]" */
        char *cut = strrchr(p, '.');
        char *br = strrchr(p, '[');
        if (br && (!cut || br > cut)) {
            cut = br;
        }
        if (!cut || cut == p) {
            return 0;
        }
        *cut = 0;
    }
}
