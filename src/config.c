/* Run-file reader: YAML 1.1 loaded with libyaml's document API, then walked
 * against the key table in config_schema.c.  Every value is checked for
 * type and range; every error names file, line, key, value and what was
 * expected. */
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <yaml.h>
#include "config.h"
#include "config_schema.h"

#define MAX_KEYS 96 /* >= cd_config_nkeys (checked in cd_config_defaults) */
#define PATHLEN 256
#define VALLEN 96

typedef struct {
    const char *file;
    char *err;
    size_t errlen;
    yaml_document_t *doc;
    void *base[CD_TGT_COUNT];         /* where rows of each target are stored now */
    yaml_node_t *seen[MAX_KEYS];      /* value given for each cd_config / scratch row */
    cd_config_scratch scratch;
} reader;

static int fail(reader *r, int line, const char *fmt, ...)
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

static int line_of(const yaml_node_t *v) { return v ? (int)v->start_mark.line + 1 : 0; }

static const char *sval(const yaml_node_t *v) { return (const char *)v->data.scalar.value; }

static int is_plain(const yaml_node_t *v)
{
    return v->type == YAML_SCALAR_NODE && v->data.scalar.style == YAML_PLAIN_SCALAR_STYLE;
}

static int is_null(const yaml_node_t *v)
{
    static const char *const nulls[] = {"", "~", "null", "Null", "NULL"};
    if (!is_plain(v))
        return 0;
    for (size_t i = 0; i < sizeof nulls / sizeof nulls[0]; i++)
        if (strcmp(sval(v), nulls[i]) == 0)
            return 1;
    return 0;
}

/* The value as written, compact, for messages. */
static void render(yaml_document_t *d, yaml_node_t *v, char *buf, size_t n, int depth)
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
        if (!*q && !*sval(v))
            PUT("(empty)");
        else
            PUT("%s%s%s", q, sval(v), q);
    } else if (depth > 2) {
        PUT(v->type == YAML_SEQUENCE_NODE ? "[...]" : "{...}");
    } else if (v->type == YAML_SEQUENCE_NODE) {
        PUT("[");
        for (yaml_node_item_t *it = v->data.sequence.items.start; it < v->data.sequence.items.top && j < n; it++) {
            char sub[VALLEN];
            render(d, yaml_document_get_node(d, *it), sub, sizeof sub, depth + 1);
            PUT("%s%s", it == v->data.sequence.items.start ? "" : ", ", sub);
        }
        PUT("]");
    } else if (v->type == YAML_MAPPING_NODE) {
        PUT("{");
        for (yaml_node_pair_t *p = v->data.mapping.pairs.start; p < v->data.mapping.pairs.top && j < n; p++) {
            char sk[VALLEN], sv[VALLEN];
            render(d, yaml_document_get_node(d, p->key), sk, sizeof sk, depth + 1);
            render(d, yaml_document_get_node(d, p->value), sv, sizeof sv, depth + 1);
            PUT("%s%s: %s", p == v->data.mapping.pairs.start ? "" : ", ", sk, sv);
        }
        PUT("}");
    }
#undef PUT
    if (j >= n && n > 4)
        strcpy(buf + n - 4, "...");
}

static void join(char *buf, const char *a, const char *b)
{
    snprintf(buf, PATHLEN, "%s%s%s", a, *a ? "." : "", b);
}

/* ---- scalars ----------------------------------------------------------- */

/* Copies s without YAML 1.1 digit separators; 0 if it has characters that
 * cannot be part of a decimal number (hex, inf, nan, words) or a leading 0. */
static int number_text(const char *s, char *buf, size_t n)
{
    size_t j = 0;
    const char *digits = s + (*s == '+' || *s == '-');
    if (digits[0] == '0' && digits[1] >= '0' && digits[1] <= '9')
        return 0; /* 010: octal in YAML 1.1, refused rather than misread */
    for (; *s; s++) {
        if (*s == '_')
            continue;
        if (!strchr("0123456789+-.eE", *s) || j + 1 >= n)
            return 0;
        buf[j++] = *s;
    }
    buf[j] = 0;
    return j > 0;
}

static int parse_real(const char *s, double *out)
{
    char b[128], *end;
    if (!number_text(s, b, sizeof b))
        return 0;
    errno = 0;
    *out = strtod(b, &end);
    return *end == 0 && errno != ERANGE && isfinite(*out);
}

static int parse_int(const char *s, long long *out)
{
    char b[128], *end;
    double x;
    if (!number_text(s, b, sizeof b))
        return 0;
    errno = 0;
    *out = strtoll(b, &end, 10);
    if (*end == 0 && errno == 0)
        return 1;
    /* 1e6 steps: a real with an integer value */
    if (!parse_real(s, &x) || x != floor(x) || fabs(x) >= 9.2e18)
        return 0;
    *out = (long long)x;
    return 1;
}

static int parse_uint(const char *s, unsigned long long *out)
{
    char b[128], *end;
    double x;
    if (!number_text(s, b, sizeof b) || strchr(b, '-'))
        return 0;
    errno = 0;
    *out = strtoull(b, &end, 10);
    if (*end == 0 && errno == 0)
        return 1;
    if (!parse_real(s, &x) || x != floor(x) || x >= 18446744073709551616.0)
        return 0;
    *out = (unsigned long long)x;
    return 1;
}

static int parse_bool(const char *s, int *out)
{
    static const char *const yes[] = {"true", "True", "TRUE", "yes", "Yes", "YES", "on", "On", "ON", "y", "Y"};
    static const char *const no[] = {"false", "False", "FALSE", "no", "No", "NO", "off", "Off", "OFF", "n", "N"};
    for (size_t i = 0; i < sizeof yes / sizeof yes[0]; i++) {
        if (strcmp(s, yes[i]) == 0) return *out = 1, 1;
        if (strcmp(s, no[i]) == 0) return *out = 0, 1;
    }
    return 0;
}

static int in_range(const cd_key *k, double x)
{
    if (k->lo_kind == '(' && !(x > k->lo)) return 0;
    if (k->lo_kind == '[' && !(x >= k->lo)) return 0;
    if (k->hi_kind == ')' && !(x < k->hi)) return 0;
    if (k->hi_kind == ']' && !(x <= k->hi)) return 0;
    return 1;
}

/* "path = value: expected ... (label, unit)" plus an optional note. */
static int bad(reader *r, const cd_key *k, yaml_node_t *v, const char *path, const char *note)
{
    char val[VALLEN], exp[256];
    render(r->doc, v, val, sizeof val, 0);
    cd_key_expect_text(k, exp, sizeof exp);
    int unit = strcmp(k->unit, "-") != 0 && strcmp(k->unit, "1") != 0;
    return fail(r, line_of(v), "%s = %s: expected %s (%s%s%s)%s%s", path, val, exp, k->label, unit ? ", " : "",
                unit ? k->unit : "", note ? "; " : "", note ? note : "");
}

static int number_item(yaml_document_t *d, yaml_node_item_t id, double *out)
{
    yaml_node_t *e = yaml_document_get_node(d, id);
    return e && is_plain(e) && parse_real(sval(e), out);
}

static int read_segments(reader *r, const cd_key *k, yaml_node_t *v, cd_species_config *sp, const char *path)
{
    if (v->type != YAML_SEQUENCE_NODE)
        return bad(r, k, v, path, NULL);
    long n = v->data.sequence.items.top - v->data.sequence.items.start;
    if (n < k->min_items || n > k->max_items)
        return bad(r, k, v, path, NULL);
    for (long i = 0; i < n; i++) {
        yaml_node_t *s = yaml_document_get_node(r->doc, v->data.sequence.items.start[i]);
        double x[7];
        int ok = s->type == YAML_SEQUENCE_NODE && s->data.sequence.items.top - s->data.sequence.items.start == 7;
        for (int c = 0; ok && c < 7; c++)
            ok = number_item(r->doc, s->data.sequence.items.start[c], &x[c]);
        if (!ok || !(x[6] > 0)) {
            char val[VALLEN];
            render(r->doc, s, val, sizeof val, 0);
            return fail(r, line_of(s), "%s[%ld] = %s: expected [ax, ay, az, bx, by, bz, radius], 7 numbers with radius > 0 (segment axis ends and radius, m)",
                        path, i, val);
        }
        for (int c = 0; c < 3; c++) {
            sp->seg_a[i][c] = x[c];
            sp->seg_b[i][c] = x[3 + c];
        }
        sp->seg_radius[i] = x[6];
    }
    sp->n_segments = (int)n;
    return 0;
}

/* Reads one value into its place; *choice gets an enum's index. */
static int convert(reader *r, const cd_key *k, yaml_node_t *v, void *base, const char *path, int *choice)
{
    char *dst = (char *)base + k->offset;
    long long i;
    double x;
    int b;
    if (k->type == CD_KT_SEGMENTS)
        return read_segments(r, k, v, (cd_species_config *)base, path);
    if (k->type == CD_KT_VEC3) {
        double u[3], norm;
        if (v->type != YAML_SEQUENCE_NODE || v->data.sequence.items.top - v->data.sequence.items.start != 3)
            return bad(r, k, v, path, NULL);
        for (int c = 0; c < 3; c++)
            if (!number_item(r->doc, v->data.sequence.items.start[c], &u[c]))
                return bad(r, k, v, path, NULL);
        norm = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
        if (k->flags & CD_KF_UNIT) {
            if (!(norm > 0))
                return bad(r, k, v, path, NULL);
            for (int c = 0; c < 3; c++)
                u[c] /= norm;
        }
        memcpy(dst, u, sizeof u);
        return 0;
    }
    if (v->type != YAML_SCALAR_NODE)
        return bad(r, k, v, path, NULL);
    const char *s = is_null(v) ? "" : sval(v);
    switch (k->type) {
    case CD_KT_STRING:
        if ((k->flags & CD_KF_NONEMPTY) && !*s)
            return bad(r, k, v, path, NULL);
        if (strlen(s) >= k->size) {
            char note[64];
            snprintf(note, sizeof note, "at most %zu characters", k->size - 1);
            return bad(r, k, v, path, note);
        }
        strcpy(dst, s);
        return 0;
    case CD_KT_ENUM: {
        int c = cd_key_choice_index(k->choices, s);
        if (c < 0) {
            char note[64] = "", *tried = NULL;
            int best = 3;
            for (const char *p = k->choices; *p;) {
                size_t len = strcspn(p, "|");
                char w[32];
                snprintf(w, sizeof w, "%.*s", (int)len, p);
                int dist = cd_edit_distance(s, w);
                if (dist < best && dist < (int)strlen(w)) {
                    best = dist;
                    snprintf(note, sizeof note, "did you mean %s?", w);
                    tried = note;
                }
                p += len + (p[len] == '|');
            }
            return bad(r, k, v, path, tried);
        }
        if (k->size)
            strcpy(dst, s);
        else
            *(int *)dst = c;
        *choice = c;
        return 0;
    }
    case CD_KT_BOOL:
        if (!is_plain(v) || !parse_bool(s, &b))
            return bad(r, k, v, path, NULL);
        *(int *)dst = b;
        return 0;
    case CD_KT_INT:
        if (!is_plain(v) || !parse_int(s, &i) || !in_range(k, (double)i))
            return bad(r, k, v, path, NULL);
        if (k->size == sizeof(int)) {
            if (i < -2147483647LL - 1 || i > 2147483647LL)
                return bad(r, k, v, path, NULL);
            *(int *)dst = (int)i;
        } else if (k->size == sizeof(long)) {
            *(long *)dst = (long)i;
        } else {
            *(long long *)dst = i;
        }
        return 0;
    case CD_KT_UINT:
        if (!is_plain(v) || !parse_uint(s, (unsigned long long *)dst))
            return bad(r, k, v, path, NULL);
        return 0;
    case CD_KT_REAL:
        if (!is_plain(v) || !parse_real(s, &x) || !in_range(k, x))
            return bad(r, k, v, path, NULL);
        *(double *)dst = x;
        return 0;
    default:
        return bad(r, k, v, path, NULL);
    }
}

/* ---- mappings ---------------------------------------------------------- */

static int read_map(reader *r, const char *sect, const char *epath, yaml_node_t *map, int line);

static int unknown_key(reader *r, const char *sect, const char *epath, const char *name, yaml_node_t *v,
                       const cd_key *sel, int choice)
{
    char path[PATHLEN], val[VALLEN], cand[64], best[64] = "", list[512];
    int bestd = 3;
    join(path, epath, name);
    render(r->doc, v, val, sizeof val, 0);
    for (int i = 0; cd_key_child(sect, i, cand, sizeof cand); i++) {
        int d = cd_edit_distance(name, cand);
        if (d < bestd && d < (int)strlen(cand)) {
            bestd = d;
            strcpy(best, cand);
        }
    }
    if (best[0]) {
        char sug[PATHLEN];
        join(sug, epath, best);
        return fail(r, line_of(v), "%s = %s: unknown key; did you mean %s?", path, val, sug);
    }
    for (size_t k = 0; k < cd_config_nkeys; k++)
        if (strcmp(cd_key_leaf(&cd_config_keys[k]), name) == 0)
            return fail(r, line_of(v), "%s = %s: unknown key here; did you mean %s?", path, val, cd_config_keys[k].path);
    cd_key_known_list(sect, sel, choice, list, sizeof list);
    return fail(r, line_of(v), "%s = %s: unknown key; expected one of the keys %s%s: %s", path, val,
                *epath ? "of " : "at the top level", epath, list);
}

static void apply_default(const cd_key *k, void *base);

static int read_list(reader *r, const cd_key *k, const char *path, yaml_node_t *v)
{
    char item_sect[PATHLEN], item_path[PATHLEN + 16];
    if (is_null(v) && k->min_items == 0)
        return 0;
    if (v->type != YAML_SEQUENCE_NODE)
        return bad(r, k, v, path, NULL);
    long n = v->data.sequence.items.top - v->data.sequence.items.start;
    if (n < k->min_items || n > k->max_items)
        return bad(r, k, v, path, NULL);
    snprintf(item_sect, sizeof item_sect, "%s[]", k->path);
    char *items = (char *)r->base[k->target] + k->offset;
    for (long i = 0; i < n; i++) {
        yaml_node_t *item = yaml_document_get_node(r->doc, v->data.sequence.items.start[i]);
        void *dst = items + (size_t)i * k->item_size;
        memset(dst, 0, k->item_size);
        for (size_t q = 0; q < cd_config_nkeys; q++)
            if (cd_config_keys[q].target == k->item_target)
                apply_default(&cd_config_keys[q], dst);
        r->base[k->item_target] = dst;
        snprintf(item_path, sizeof item_path, "%.200s[%ld]", path, i);
        if (item->type != YAML_MAPPING_NODE) {
            char val[VALLEN], list[512];
            render(r->doc, item, val, sizeof val, 0);
            cd_key_known_list(item_sect, NULL, -1, list, sizeof list);
            return fail(r, line_of(item), "%s = %s: expected a mapping with keys %s (%s)", item_path, val, list, k->label);
        }
        if (read_map(r, item_sect, item_path, item, line_of(item)) != 0)
            return -1;
    }
    *(int *)((char *)r->base[CD_TGT_CONFIG] + k->count_offset) = (int)n;
    return 0;
}

static yaml_node_t *lookup(yaml_document_t *d, yaml_node_t *map, const char *name, yaml_node_t **key)
{
    if (!map || map->type != YAML_MAPPING_NODE)
        return NULL;
    for (yaml_node_pair_t *p = map->data.mapping.pairs.start; p < map->data.mapping.pairs.top; p++) {
        yaml_node_t *kn = yaml_document_get_node(d, p->key);
        if (kn->type == YAML_SCALAR_NODE && strcmp(sval(kn), name) == 0) {
            if (key) *key = kn;
            return yaml_document_get_node(d, p->value);
        }
    }
    return NULL;
}

/* One mapping of keys: sect names its rows ("" top level, "material",
 * "particles[]"), epath is its place for messages ("particles[0]"), line
 * where it starts.  map NULL: the section is absent (only required keys are
 * checked). */
static int read_map(reader *r, const char *sect, const char *epath, yaml_node_t *map, int line)
{
    yaml_node_t *seen[MAX_KEYS] = {0};
    char path[PATHLEN], full[PATHLEN], val[VALLEN], name[64];
    const cd_key *sel = NULL;
    int choice = -1;

    for (size_t i = 0; i < cd_config_nkeys; i++)
        if (cd_key_in_section(&cd_config_keys[i], sect) && (cd_config_keys[i].flags & CD_KF_SELECTOR))
            sel = &cd_config_keys[i];
    if (map && is_null(map))
        map = NULL;
    if (map && map->type != YAML_MAPPING_NODE) {
        char list[512];
        render(r->doc, map, val, sizeof val, 0);
        cd_key_known_list(sect, NULL, -1, list, sizeof list);
        return fail(r, line_of(map), "%s = %s: expected a mapping with keys %s", *epath ? epath : "(top level)", val, list);
    }
    /* the selector first: it decides which other keys apply */
    if (sel) {
        yaml_node_t *v = lookup(r->doc, map, cd_key_leaf(sel), NULL);
        join(path, epath, cd_key_leaf(sel));
        if (v) {
            if (convert(r, sel, v, r->base[sel->target], path, &choice) != 0)
                return -1;
        } else if (sel->def) {
            choice = cd_key_choice_index(sel->choices, sel->def);
        } else if (sel->required) {
            char exp[256];
            cd_key_expect_text(sel, exp, sizeof exp);
            return fail(r, line > 0 ? line : 1, "%s: missing; expected %s (%s)", path, exp, sel->label);
        }
    }
    if (map) {
        for (yaml_node_pair_t *p = map->data.mapping.pairs.start; p < map->data.mapping.pairs.top; p++) {
            yaml_node_t *kn = yaml_document_get_node(r->doc, p->key);
            yaml_node_t *v = yaml_document_get_node(r->doc, p->value);
            if (kn->type != YAML_SCALAR_NODE) {
                render(r->doc, kn, val, sizeof val, 0);
                return fail(r, line_of(kn), "%s key %s: expected a key name (a word)", *epath ? epath : "top-level", val);
            }
            const char *key = sval(kn);
            join(path, epath, key);
            for (yaml_node_pair_t *q = map->data.mapping.pairs.start; q < p; q++) {
                yaml_node_t *kq = yaml_document_get_node(r->doc, q->key);
                if (kq->type == YAML_SCALAR_NODE && strcmp(sval(kq), key) == 0) {
                    render(r->doc, v, val, sizeof val, 0);
                    return fail(r, line_of(kn), "%s = %s: given twice (first at line %d); expected each key once",
                                path, val, line_of(kq));
                }
            }
            join(full, sect, key);
            const cd_key *k = NULL;
            int exists = 0;
            for (size_t i = 0; i < cd_config_nkeys; i++) {
                const cd_key *c = &cd_config_keys[i];
                if (strcmp(c->path, full) != 0)
                    continue;
                exists = 1;
                if (!k && (choice < 0 || (cd_key_applies(c) >> choice & 1u)))
                    k = c;
            }
            if (!exists) {
                size_t fl = strlen(full);
                int is_sub = fl && full[fl - 1] != ']';
                for (size_t i = 0; is_sub && i < cd_config_nkeys; i++)
                    if (strncmp(cd_config_keys[i].path, full, fl) == 0 && cd_config_keys[i].path[fl] == '.')
                        is_sub = 2;
                if (is_sub == 2) {
                    if (read_map(r, full, path, v, line_of(kn)) != 0)
                        return -1;
                    continue;
                }
                return unknown_key(r, sect, epath, key, v, sel, choice);
            }
            if (!k) {
                char sp[PATHLEN], list[512], cname[32];
                cd_key_choice_name(sel->choices, choice, cname, sizeof cname);
                join(sp, epath, cd_key_leaf(sel));
                render(r->doc, v, val, sizeof val, 0);
                cd_key_known_list(sect, sel, choice, list, sizeof list);
                return fail(r, line_of(kn), "%s = %s: does not apply to %s = %s; expected one of the keys for %s: %s",
                            path, val, sp, cname, cname, list);
            }
            size_t idx = (size_t)(k - cd_config_keys);
            seen[idx] = v;
            if (k->target == CD_TGT_CONFIG || k->target == CD_TGT_SCRATCH)
                r->seen[idx] = v;
            if (k == sel)
                continue;
            if (k->type == CD_KT_LIST) {
                if (read_list(r, k, path, v) != 0)
                    return -1;
            } else {
                int dummy;
                if (convert(r, k, v, r->base[k->target], path, &dummy) != 0)
                    return -1;
            }
        }
    }
    /* absent sub-sections may still have required keys */
    for (int i = 0; cd_key_child(sect, i, name, sizeof name); i++) {
        join(full, sect, name);
        join(path, epath, name);
        int is_key = 0;
        for (size_t k = 0; k < cd_config_nkeys; k++)
            is_key |= strcmp(cd_config_keys[k].path, full) == 0;
        if (!is_key && !lookup(r->doc, map, name, NULL) && read_map(r, full, path, NULL, line) != 0)
            return -1;
    }
    /* required keys, keys that exclude each other */
    for (size_t i = 0; i < cd_config_nkeys; i++) {
        const cd_key *k = &cd_config_keys[i];
        if (!cd_key_in_section(k, sect))
            continue;
        unsigned req = k->required & cd_key_applies(k);
        int needed = sel ? (choice >= 0 && (req >> choice & 1u)) : req != 0;
        if (needed && !seen[i]) {
            char exp[256], cond[PATHLEN + 64] = "";
            int unit = strcmp(k->unit, "-") != 0 && strcmp(k->unit, "1") != 0;
            if (sel && k->required != CD_ALL_CHOICES) {
                char cname[32];
                cd_key_choice_name(sel->choices, choice, cname, sizeof cname);
                join(path, epath, cd_key_leaf(sel));
                snprintf(cond, sizeof cond, ", needed for %s = %s", path, cname);
            }
            cd_key_expect_text(k, exp, sizeof exp);
            join(path, epath, cd_key_leaf(k));
            return fail(r, line > 0 ? line : 1, "%s: missing; expected %s (%s%s%s)%s", path, exp, k->label,
                        unit ? ", " : "", unit ? k->unit : "", cond);
        }
        if (k->conflicts && seen[i]) {
            join(full, sect, k->conflicts);
            for (size_t q = 0; q < i; q++)
                if (seen[q] && strcmp(cd_config_keys[q].path, full) == 0) {
                    char other[PATHLEN];
                    yaml_node_t *later = line_of(seen[i]) >= line_of(seen[q]) ? seen[i] : seen[q];
                    const cd_key *lk = later == seen[i] ? k : &cd_config_keys[q];
                    const cd_key *ek = later == seen[i] ? &cd_config_keys[q] : k;
                    join(path, epath, cd_key_leaf(lk));
                    join(other, epath, cd_key_leaf(ek));
                    render(r->doc, later, val, sizeof val, 0);
                    return fail(r, line_of(later), "%s = %s: cannot be given together with %s (line %d); expected only one of %s and %s",
                                path, val, other, line_of(later == seen[i] ? seen[q] : seen[i]), other, path);
                }
        }
    }
    return 0;
}

/* ---- defaults and the whole file --------------------------------------- */

static void apply_default(const cd_key *k, void *base)
{
    yaml_parser_t p;
    yaml_document_t d;
    reader r = {.file = "(built-in default)"};
    char err[256];
    int choice;
    if (!k->def || (k->flags & CD_KF_DERIVED) || k->type == CD_KT_LIST)
        return;
    r.err = err;
    r.errlen = sizeof err;
    yaml_parser_initialize(&p);
    yaml_parser_set_input_string(&p, (const unsigned char *)k->def, strlen(k->def));
    if (!yaml_parser_load(&p, &d) || !yaml_document_get_root_node(&d)) {
        fprintf(stderr, "capdem: bad built-in default for %s: %s\n", k->path, k->def);
        abort();
    }
    r.doc = &d;
    if (convert(&r, k, yaml_document_get_root_node(&d), base, k->path, &choice) != 0) {
        fprintf(stderr, "%s\n", err);
        abort();
    }
    yaml_document_delete(&d);
    yaml_parser_delete(&p);
}

static size_t key_index(const char *path)
{
    for (size_t i = 0; i < cd_config_nkeys; i++)
        if (strcmp(cd_config_keys[i].path, path) == 0)
            return i;
    abort();
}

/* Values that follow from others: kt, eta_t, eta_n from restitution. */
static void derive(cd_config *c, yaml_node_t *const *seen, const cd_config_scratch *s)
{
    if (seen && seen[key_index("material.restitution")]) {
        double le = log(s->restitution);
        c->eta_n = -le / sqrt(CD_PI * CD_PI + le * le);
    }
    if (!seen || !seen[key_index("material.kt")])
        c->kt = 0.5 * c->kn;
    if (!seen || !seen[key_index("material.damping_tangential")])
        c->eta_t = c->eta_n;
    for (int i = 0; i < c->n_extra_walls; i++) {
        c->extra_walls[i].type = CD_WALL_PLANE;
        c->extra_walls[i].friction = c->wall_friction;
    }
}

void cd_config_defaults(cd_config *c)
{
    if (cd_config_nkeys > MAX_KEYS) {
        fprintf(stderr, "capdem: config.c: raise MAX_KEYS to %zu\n", cd_config_nkeys);
        abort();
    }
    memset(c, 0, sizeof *c);
    for (size_t i = 0; i < cd_config_nkeys; i++)
        if (cd_config_keys[i].target == CD_TGT_CONFIG)
            apply_default(&cd_config_keys[i], c);
    derive(c, NULL, NULL);
}

/* Checks that need more than one key. */
static int check_whole(reader *r, cd_config *c, yaml_node_t *root)
{
    yaml_node_t *plist = lookup(r->doc, root, "particles", NULL);
    long long total = 0;
    for (int i = 0; i < c->n_species; i++) {
        cd_species_config *sp = &c->species[i];
        yaml_node_t *item = yaml_document_get_node(r->doc, plist->data.sequence.items.start[i]);
        yaml_node_t *a = lookup(r->doc, item, "aspect", NULL);
        if (strcmp(sp->shape, "sphere") == 0 && sp->aspect != 1.0) {
            char val[VALLEN];
            render(r->doc, a, val, sizeof val, 0);
            return fail(r, line_of(a), "particles[%d].aspect = %s: expected 1 for shape sphere (aspect ratio)", i, val);
        }
        total += sp->count;
    }
    if (total > 2147483647LL)
        return fail(r, line_of(plist), "particles = (%lld particles in all): expected at most 2147483647 in all (particle count)",
                    total);
    return 0;
}

static int parse_document(reader *r, cd_config *c, const char *text)
{
    yaml_parser_t p;
    yaml_document_t d, d2;
    int rc = -1;
    yaml_parser_initialize(&p);
    yaml_parser_set_input_string(&p, (const unsigned char *)text, strlen(text));
    if (!yaml_parser_load(&p, &d)) {
        if (p.error == YAML_READER_ERROR)
            fail(r, 0, "not readable as UTF-8 text at byte %zu: %s", p.problem_offset, p.problem);
        else if (p.context)
            fail(r, (int)p.problem_mark.line + 1, "YAML syntax error: %s (%s that starts at line %d); expected valid YAML 1.1",
                 p.problem ? p.problem : "?", p.context, (int)p.context_mark.line + 1);
        else
            fail(r, (int)p.problem_mark.line + 1, "YAML syntax error: %s; expected valid YAML 1.1",
                 p.problem ? p.problem : "out of memory");
        yaml_parser_delete(&p);
        return -1;
    }
    r->doc = &d;
    yaml_node_t *root = yaml_document_get_root_node(&d);
    if (root && yaml_parser_load(&p, &d2)) {
        yaml_node_t *more = yaml_document_get_root_node(&d2);
        if (more)
            fail(r, line_of(more), "a second YAML document starts here; expected one document");
        yaml_document_delete(&d2);
        if (more)
            goto done;
    } else if (root) {
        fail(r, (int)p.problem_mark.line + 1, "YAML syntax error: %s; expected valid YAML 1.1",
             p.problem ? p.problem : "out of memory");
        goto done;
    }
    if (read_map(r, "", "", root, 1) != 0 || check_whole(r, c, root) != 0)
        goto done;
    derive(c, r->seen, &r->scratch);
    rc = 0;
done:
    yaml_document_delete(&d);
    yaml_parser_delete(&p);
    return rc;
}

int cd_config_parse(const char *text, const char *name_for_errors, cd_config *c, char *err, size_t errlen)
{
    reader r;
    memset(&r, 0, sizeof r);
    r.file = name_for_errors ? name_for_errors : "(text)";
    r.err = err;
    r.errlen = errlen;
    cd_config_defaults(c);
    snprintf(c->source_path, sizeof c->source_path, "%s", r.file);
    if (!text)
        return fail(&r, 0, "no text to read");
    c->source_text = malloc(strlen(text) + 1);
    if (!c->source_text)
        return fail(&r, 0, "out of memory");
    strcpy(c->source_text, text);
    r.base[CD_TGT_CONFIG] = c;
    r.base[CD_TGT_SCRATCH] = &r.scratch;
    if (parse_document(&r, c, text) != 0) {
        free(c->source_text);
        c->source_text = NULL;
        return -1;
    }
    return 0;
}

int cd_config_load(const char *path, cd_config *c, char *err, size_t errlen)
{
    reader r = {.file = path ? path : "(null)", .err = err, .errlen = errlen};
    FILE *f;
    char *text = NULL;
    size_t len = 0, cap = 0, got;
    int rc;
    cd_config_defaults(c);
    if (!path || !(f = fopen(path, "rb")))
        return fail(&r, 0, "cannot open the run file: %s", strerror(path ? errno : EINVAL));
    do {
        if (len + 4096 + 1 > cap) {
            char *t = realloc(text, cap = 2 * cap + 8192);
            if (!t) {
                free(text);
                fclose(f);
                return fail(&r, 0, "out of memory");
            }
            text = t;
        }
        got = fread(text + len, 1, cap - len - 1, f);
        len += got;
    } while (got > 0);
    rc = ferror(f);
    fclose(f);
    text[len] = 0;
    if (rc) {
        free(text);
        return fail(&r, 0, "cannot read the run file");
    }
    if (strlen(text) != len) {
        size_t at = strlen(text);
        free(text);
        return fail(&r, 0, "contains a NUL byte at offset %zu; expected a YAML text file", at);
    }
    rc = cd_config_parse(text, path, c, err, errlen);
    free(text);
    return rc;
}

void cd_config_free(cd_config *c)
{
    if (!c)
        return;
    free(c->source_text);
    c->source_text = NULL;
}
