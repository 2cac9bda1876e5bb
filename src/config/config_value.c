/* Run-file reader, values: one YAML node read into its place, checked for
 * type and range (config_internal.h). */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "config/config_internal.h"

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
        if (*s == '_') continue;
        if (!strchr("0123456789+-.eE", *s) || j + 1 >= n) return 0;
        buf[j++] = *s;
    }
    buf[j] = 0;
    return j > 0;
}

static int parse_real(const char *s, double *out)
{
    char b[128], *end;
    if (!number_text(s, b, sizeof b)) return 0;
    errno = 0;
    *out = strtod(b, &end);
    return *end == 0 && errno != ERANGE && isfinite(*out);
}

static int parse_int(const char *s, long long *out)
{
    char b[128], *end;
    double x;
    if (!number_text(s, b, sizeof b)) return 0;
    errno = 0;
    *out = strtoll(b, &end, 10);
    if (*end == 0 && errno == 0) return 1;
    /* 1e6 steps: a real with an integer value */
    if (!parse_real(s, &x) || x != floor(x) || fabs(x) >= 9.2e18) return 0;
    *out = (long long)x;
    return 1;
}

static int parse_uint(const char *s, unsigned long long *out)
{
    char b[128], *end;
    double x;
    if (!number_text(s, b, sizeof b) || strchr(b, '-')) return 0;
    errno = 0;
    *out = strtoull(b, &end, 10);
    if (*end == 0 && errno == 0) return 1;
    if (!parse_real(s, &x) || x != floor(x) || x >= 18446744073709551616.0) return 0;
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

static int number_item(yaml_document_t *d, yaml_node_item_t id, double *out)
{
    yaml_node_t *e = yaml_document_get_node(d, id);
    return e && is_plain(e) && parse_real(sval(e), out);
}

static int read_segments(reader *r, const cd_key *k, yaml_node_t *v, cd_species_config *sp, const char *path)
{
    if (v->type != YAML_SEQUENCE_NODE) return cd_cfg_bad(r, k, v, path, NULL);
    long n = v->data.sequence.items.top - v->data.sequence.items.start;
    if (n < k->min_items || n > k->max_items) return cd_cfg_bad(r, k, v, path, NULL);
    for (long i = 0; i < n; i++) {
        yaml_node_t *s = yaml_document_get_node(r->doc, v->data.sequence.items.start[i]);
        double x[7];
        int ok = s->type == YAML_SEQUENCE_NODE && s->data.sequence.items.top - s->data.sequence.items.start == 7;
        for (int c = 0; ok && c < 7; c++) ok = number_item(r->doc, s->data.sequence.items.start[c], &x[c]);
        if (!ok || !(x[6] > 0)) {
            char val[VALLEN];
            cd_cfg_render(r->doc, s, val, sizeof val, 0);
            return cd_cfg_fail(r, line_of(s),
                               "%s[%ld] = %s: expected [ax, ay, az, bx, by, bz, radius], 7 numbers with radius > 0 "
                               "(segment axis ends and radius, m)",
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
int cd_cfg_convert(reader *r, const cd_key *k, yaml_node_t *v, void *base, const char *path, int *choice)
{
    char *dst = (char *)base + k->offset;
    long long i;
    double x;
    int b;
    if (k->type == CD_KT_SEGMENTS) return read_segments(r, k, v, (cd_species_config *)base, path);
    if (k->type == CD_KT_VEC3) {
        double u[3], norm;
        if (v->type != YAML_SEQUENCE_NODE || v->data.sequence.items.top - v->data.sequence.items.start != 3)
            return cd_cfg_bad(r, k, v, path, NULL);
        for (int c = 0; c < 3; c++)
            if (!number_item(r->doc, v->data.sequence.items.start[c], &u[c])) return cd_cfg_bad(r, k, v, path, NULL);
        norm = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
        if (k->flags & CD_KF_UNIT) {
            if (!(norm > 0)) return cd_cfg_bad(r, k, v, path, NULL);
            for (int c = 0; c < 3; c++) u[c] /= norm;
        }
        memcpy(dst, u, sizeof u);
        return 0;
    }
    if (v->type != YAML_SCALAR_NODE) return cd_cfg_bad(r, k, v, path, NULL);
    const char *s = is_null(v) ? "" : sval(v);
    switch (k->type) {
    case CD_KT_STRING:
        if ((k->flags & CD_KF_NONEMPTY) && !*s) return cd_cfg_bad(r, k, v, path, NULL);
        if (strlen(s) >= k->size) {
            char note[64];
            snprintf(note, sizeof note, "at most %zu characters", k->size - 1);
            return cd_cfg_bad(r, k, v, path, note);
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
            return cd_cfg_bad(r, k, v, path, tried);
        }
        if (k->size) strcpy(dst, s);
        else *(int *)dst = c;
        *choice = c;
        return 0;
    }
    case CD_KT_BOOL:
        if (!is_plain(v) || !parse_bool(s, &b)) return cd_cfg_bad(r, k, v, path, NULL);
        *(int *)dst = b;
        return 0;
    case CD_KT_INT:
        if (!is_plain(v) || !parse_int(s, &i) || !in_range(k, (double)i)) return cd_cfg_bad(r, k, v, path, NULL);
        if (k->size == sizeof(int)) {
            if (i < -2147483647LL - 1 || i > 2147483647LL) return cd_cfg_bad(r, k, v, path, NULL);
            *(int *)dst = (int)i;
        } else if (k->size == sizeof(long)) {
            *(long *)dst = (long)i;
        } else {
            *(long long *)dst = i;
        }
        return 0;
    case CD_KT_UINT:
        if (!is_plain(v) || !parse_uint(s, (unsigned long long *)dst)) return cd_cfg_bad(r, k, v, path, NULL);
        return 0;
    case CD_KT_REAL:
        if (!is_plain(v) || !parse_real(s, &x) || !in_range(k, x)) return cd_cfg_bad(r, k, v, path, NULL);
        *(double *)dst = x;
        return 0;
    default:
        return cd_cfg_bad(r, k, v, path, NULL);
    }
}
