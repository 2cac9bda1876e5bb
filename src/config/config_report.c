/* Run-file reader, error reporting: every error names file, line, key, value
 * and what was expected (config_internal.h). */
#include <stdarg.h>
#include <stdio.h>
#include <string.h>
#include "config/config_internal.h"

int cd_cfg_fail(reader *r, int line, const char *fmt, ...)
{
    if (r->err && r->errlen) {
        int n = line > 0 ? snprintf(r->err, r->errlen, "%s:%d: ", r->file, line)
                         : snprintf(r->err, r->errlen, "%s: ", r->file);
        if (n >= 0 && (size_t)n < r->errlen) {
            va_list ap;
            va_start(ap, fmt);
            vsnprintf(r->err + n, r->errlen - (size_t)n, fmt, ap);
            va_end(ap);
        }
    }
    return -1;
}

/* The value as written, compact, for messages. */
void cd_cfg_render(yaml_document_t *d, yaml_node_t *v, char *buf, size_t n, int depth)
{
    size_t j = 0;
#define PUT(...) (j += (size_t)snprintf(buf + j, j < n ? n - j : 0, __VA_ARGS__))
    buf[0] = 0;
    if (!v) {
        PUT("(nothing)");
    } else if (v->type == YAML_SCALAR_NODE) {
        const char *q = v->data.scalar.style == YAML_SINGLE_QUOTED_SCALAR_STYLE   ? "'"
                        : v->data.scalar.style == YAML_DOUBLE_QUOTED_SCALAR_STYLE ? "\""
                                                                                  : "";
        if (!*q && !*sval(v)) PUT("(empty)");
        else PUT("%s%s%s", q, sval(v), q);
    } else if (depth > 2) {
        PUT(v->type == YAML_SEQUENCE_NODE ? "[...]" : "{...}");
    } else if (v->type == YAML_SEQUENCE_NODE) {
        PUT("[");
        for (yaml_node_item_t *it = v->data.sequence.items.start; it < v->data.sequence.items.top && j < n; it++) {
            char sub[VALLEN];
            cd_cfg_render(d, yaml_document_get_node(d, *it), sub, sizeof sub, depth + 1);
            PUT("%s%s", it == v->data.sequence.items.start ? "" : ", ", sub);
        }
        PUT("]");
    } else if (v->type == YAML_MAPPING_NODE) {
        PUT("{");
        for (yaml_node_pair_t *p = v->data.mapping.pairs.start; p < v->data.mapping.pairs.top && j < n; p++) {
            char sk[VALLEN], sv[VALLEN];
            cd_cfg_render(d, yaml_document_get_node(d, p->key), sk, sizeof sk, depth + 1);
            cd_cfg_render(d, yaml_document_get_node(d, p->value), sv, sizeof sv, depth + 1);
            PUT("%s%s: %s", p == v->data.mapping.pairs.start ? "" : ", ", sk, sv);
        }
        PUT("}");
    }
#undef PUT
    if (j >= n && n > 4) strcpy(buf + n - 4, "...");
}

void cd_cfg_join(char *buf, const char *a, const char *b) { snprintf(buf, PATHLEN, "%s%s%s", a, *a ? "." : "", b); }

/* "path = value: expected ... (label, unit)" plus an optional note. */
int cd_cfg_bad(reader *r, const cd_key *k, yaml_node_t *v, const char *path, const char *note)
{
    char val[VALLEN], exp[256];
    cd_cfg_render(r->doc, v, val, sizeof val, 0);
    cd_key_expect_text(k, exp, sizeof exp);
    int unit = strcmp(k->unit, "-") != 0 && strcmp(k->unit, "1") != 0;
    return cd_cfg_fail(r, line_of(v), "%s = %s: expected %s (%s%s%s)%s%s", path, val, exp, k->label, unit ? ", " : "",
                       unit ? k->unit : "", note ? "; " : "", note ? note : "");
}

int cd_cfg_unknown_key(reader *r, const char *sect, const char *epath, const char *name, yaml_node_t *v,
                       const cd_key *sel, int choice)
{
    char path[PATHLEN], val[VALLEN], cand[64], best[64] = "", list[512];
    int bestd = 3;
    cd_cfg_join(path, epath, name);
    cd_cfg_render(r->doc, v, val, sizeof val, 0);
    for (int i = 0; cd_key_child(sect, i, cand, sizeof cand); i++) {
        int d = cd_edit_distance(name, cand);
        if (d < bestd && d < (int)strlen(cand)) {
            bestd = d;
            strcpy(best, cand);
        }
    }
    if (best[0]) {
        char sug[PATHLEN];
        cd_cfg_join(sug, epath, best);
        return cd_cfg_fail(r, line_of(v), "%s = %s: unknown key; did you mean %s?", path, val, sug);
    }
    for (size_t k = 0; k < cd_config_nkeys; k++)
        if (strcmp(cd_key_leaf(&cd_config_keys[k]), name) == 0)
            return cd_cfg_fail(r, line_of(v), "%s = %s: unknown key here; did you mean %s?", path, val,
                               cd_config_keys[k].path);
    cd_key_known_list(sect, sel, choice, list, sizeof list);
    return cd_cfg_fail(r, line_of(v), "%s = %s: unknown key; expected one of the keys %s%s: %s", path, val,
                       *epath ? "of " : "at the top level", epath, list);
}
