/* Private to the run-file reader: config.c (loading the YAML document and
 * walking it against the key table), config_value.c (reading and checking
 * one value) and config_report.c (error messages).  The key table itself is
 * in config_schema.h / config_schema.c. */
#ifndef CD_CONFIG_INTERNAL_H
#define CD_CONFIG_INTERNAL_H
#include <stddef.h>
#include <string.h>
#include <yaml.h>
#include "config/config.h"
#include "config/config_schema.h"

#define MAX_KEYS 96 /* >= cd_config_nkeys (checked in cd_config_defaults) */
#define PATHLEN  256
#define VALLEN   96

typedef struct {
    const char *file;
    char *err;
    size_t errlen;
    yaml_document_t *doc;
    void *base[CD_TGT_COUNT];    /* where rows of each target are stored now */
    yaml_node_t *seen[MAX_KEYS]; /* value given for each cd_config / scratch row */
    cd_config_scratch scratch;
} reader;

/* ---- nodes -------------------------------------------------------------- */

static inline int line_of(const yaml_node_t *v) { return v ? (int)v->start_mark.line + 1 : 0; }

static inline const char *sval(const yaml_node_t *v) { return (const char *)v->data.scalar.value; }

static inline int is_plain(const yaml_node_t *v)
{
    return v->type == YAML_SCALAR_NODE && v->data.scalar.style == YAML_PLAIN_SCALAR_STYLE;
}

static inline int is_null(const yaml_node_t *v)
{
    static const char *const nulls[] = {"", "~", "null", "Null", "NULL"};
    if (!is_plain(v)) return 0;
    for (size_t i = 0; i < sizeof nulls / sizeof nulls[0]; i++)
        if (strcmp(sval(v), nulls[i]) == 0) return 1;
    return 0;
}

/* ---- error reporting: config_report.c ----------------------------------- */

/* "file:line: " and the message into r->err; returns -1. */
int cd_cfg_fail(reader *r, int line, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;
/* The value as written, compact, for messages. */
void cd_cfg_render(yaml_document_t *d, yaml_node_t *v, char *buf, size_t n, int depth);
/* a.b into buf (PATHLEN); just b when a is "". */
void cd_cfg_join(char *buf, const char *a, const char *b);
/* "path = value: expected ... (label, unit)" plus an optional note. */
int cd_cfg_bad(reader *r, const cd_key *k, yaml_node_t *v, const char *path, const char *note);
/* An unknown key name in section sect: a near miss, the same key elsewhere,
 * or the keys that are known here. */
int cd_cfg_unknown_key(reader *r, const char *sect, const char *epath, const char *name, yaml_node_t *v,
                       const cd_key *sel, int choice);

/* ---- values: config_value.c --------------------------------------------- */

/* Reads one value into its place; *choice gets an enum's index. */
int cd_cfg_convert(reader *r, const cd_key *k, yaml_node_t *v, void *base, const char *path, int *choice);

#endif
