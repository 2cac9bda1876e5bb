/* Key-by-key comparison of two configs (capdem run --resume: the config
 * stored in the run file against the one given), walking the key table:
 * what may change on a resume is marked CD_KF_RESUMABLE there. */
#include <stdio.h>
#include <string.h>
#include "config/config.h"
#include "config/config_schema.h"

/* Start of the storage of key k's target in config c, item i of its list. */
static const char *base_of(const cd_key *k, const cd_config *c, int i)
{
    switch (k->target) {
    case CD_TGT_CONFIG:
        return (const char *)c;
    case CD_TGT_SPECIES:
        return (const char *)&c->species[i];
    case CD_TGT_WALL:
        return (const char *)&c->extra_walls[i];
    default:
        return NULL;
    }
}

static void real_text(double v, char *buf, size_t n) { snprintf(buf, n, "%.15g", v); }

/* The stored value of k (in the target storage at base) as text. */
static void value_text(const cd_key *k, const char *base, char *buf, size_t n)
{
    const char *p = base + k->offset;
    char a[40], b[40], c[40];
    switch (k->type) {
    case CD_KT_STRING:
        snprintf(buf, n, "\"%s\"", p);
        break;
    case CD_KT_ENUM:
        if (k->size) snprintf(buf, n, "%s", p);
        else cd_key_choice_name(k->choices, *(const int *)p, buf, n);
        break;
    case CD_KT_BOOL:
        snprintf(buf, n, "%s", *(const int *)p ? "true" : "false");
        break;
    case CD_KT_INT:
        if (k->size == sizeof(int)) snprintf(buf, n, "%d", *(const int *)p);
        else if (k->size == sizeof(long)) snprintf(buf, n, "%ld", *(const long *)p);
        else snprintf(buf, n, "%lld", *(const long long *)p);
        break;
    case CD_KT_UINT:
        snprintf(buf, n, "%llu", *(const unsigned long long *)p);
        break;
    case CD_KT_REAL:
        real_text(*(const double *)p, buf, n);
        break;
    case CD_KT_VEC3: {
        const double *v = (const double *)p;
        real_text(v[0], a, sizeof a);
        real_text(v[1], b, sizeof b);
        real_text(v[2], c, sizeof c);
        snprintf(buf, n, "[%s, %s, %s]", a, b, c);
        break;
    }
    case CD_KT_SEGMENTS: {
        const cd_species_config *s = (const cd_species_config *)base;
        size_t j = (size_t)snprintf(buf, n, "[");
        for (int q = 0; q < s->n_segments && j < n; q++) {
            char r[40];
            j += (size_t)snprintf(buf + j, n - j, "%s[", q ? ", " : "");
            for (int e = 0; e < 7 && j < n; e++) {
                double x = e < 3 ? s->seg_a[q][e] : e < 6 ? s->seg_b[q][e - 3] : s->seg_radius[q];
                real_text(x, r, sizeof r);
                j += (size_t)snprintf(buf + j, n - j, "%s%s", e ? ", " : "", r);
            }
            if (j < n) j += (size_t)snprintf(buf + j, n - j, "]");
        }
        if (j < n) snprintf(buf + j, n - j, "]");
        break;
    }
    default:
        buf[0] = 0;
        break;
    }
}

/* Whether k's values differ (numbers compared by value). */
static int differs(const cd_key *k, const char *pa, const char *pb)
{
    const char *a = pa + k->offset, *b = pb + k->offset;
    switch (k->type) {
    case CD_KT_STRING:
        return strcmp(a, b) != 0;
    case CD_KT_ENUM:
        return k->size ? strcmp(a, b) != 0 : *(const int *)a != *(const int *)b;
    case CD_KT_BOOL:
        return *(const int *)a != *(const int *)b;
    case CD_KT_INT:
        if (k->size == sizeof(int)) return *(const int *)a != *(const int *)b;
        if (k->size == sizeof(long)) return *(const long *)a != *(const long *)b;
        return *(const long long *)a != *(const long long *)b;
    case CD_KT_UINT:
        return *(const unsigned long long *)a != *(const unsigned long long *)b;
    case CD_KT_REAL:
        return *(const double *)a != *(const double *)b;
    case CD_KT_VEC3:
        for (int c = 0; c < 3; c++)
            if (((const double *)a)[c] != ((const double *)b)[c]) return 1;
        return 0;
    case CD_KT_SEGMENTS: {
        const cd_species_config *sa = (const cd_species_config *)pa, *sb = (const cd_species_config *)pb;
        if (sa->n_segments != sb->n_segments) return 1;
        for (int q = 0; q < sa->n_segments; q++)
            for (int e = 0; e < 3; e++)
                if (sa->seg_a[q][e] != sb->seg_a[q][e] || sa->seg_b[q][e] != sb->seg_b[q][e]) return 1;
        for (int q = 0; q < sa->n_segments; q++)
            if (sa->seg_radius[q] != sb->seg_radius[q]) return 1;
        return 0;
    }
    default:
        return 0;
    }
}

/* "particles[2].count" -> "particles[].count" into buf. */
static void generic_path(const char *name, char *buf, size_t n)
{
    size_t j = 0;
    for (const char *p = name; *p && j + 1 < n; p++) {
        buf[j++] = *p;
        if (*p == '[') {
            while (p[1] >= '0' && p[1] <= '9') p++;
        }
    }
    buf[j] = 0;
}

int cd_config_key_known(const char *name, char *suggest, size_t n)
{
    char g[256];
    generic_path(name, g, sizeof g);
    int best = 4;
    if (suggest && n) suggest[0] = 0;
    for (size_t i = 0; i < cd_config_nkeys; i++) {
        if (!strcmp(cd_config_keys[i].path, g)) return 1;
        int d = cd_edit_distance(g, cd_config_keys[i].path);
        if (suggest && d < best) {
            best = d;
            snprintf(suggest, n, "%s", cd_config_keys[i].path);
        }
    }
    return 0;
}

static int allowed(const char *name, const char *const *allow, int n_allow)
{
    char g[256], ga[256];
    generic_path(name, g, sizeof g);
    for (int i = 0; i < n_allow; i++) {
        if (!strcmp(allow[i], name)) return 1; /* this item only */
        generic_path(allow[i], ga, sizeof ga);
        if (!strcmp(allow[i], ga) && !strcmp(ga, g)) return 1; /* every item */
    }
    return 0;
}

static void add_line(char *buf, size_t n, const char *fmt, const char *key, const char *va, const char *vb,
                     const char *note)
{
    if (!buf || !n) return;
    size_t j = strlen(buf);
    if (j + 1 >= n) return;
    int w = snprintf(buf + j, n - j, fmt, key, va, vb);
    if (w >= 0 && (size_t)w < n - j && note && *note) snprintf(buf + j + (size_t)w, n - j - (size_t)w, "%s", note);
    j = strlen(buf);
    if (j + 1 < n) strcat(buf, "\n");
}

int cd_config_resume_diff(const cd_config *stored, const cd_config *given, const char *const *allow, int n_allow,
                          char *refused, size_t rlen, char *accepted, size_t alen)
{
    int n_refused = 0;
    if (refused && rlen) refused[0] = 0;
    if (accepted && alen) accepted[0] = 0;
    const char *fmt = "  %s: %s in the run file, %s given";
    for (size_t i = 0; i < cd_config_nkeys; i++) {
        const cd_key *k = &cd_config_keys[i];
        if (k->target == CD_TGT_SCRATCH) continue; /* compared through what it sets (restitution: eta_n) */
        int items = 1, items_b = 1;
        char name[256], va[1024], vb[1024];
        const char *note = "";
        if (k->target == CD_TGT_SPECIES) items = stored->n_species, items_b = given->n_species;
        if (k->target == CD_TGT_WALL) items = stored->n_extra_walls, items_b = given->n_extra_walls;
        if (k->type == CD_KT_LIST) {
            /* the number of items; the items' keys are rows of their own */
            int na = *(const int *)((const char *)stored + k->count_offset);
            int nb = *(const int *)((const char *)given + k->count_offset);
            if (na == nb) continue;
            snprintf(va, sizeof va, "%d item%s", na, na == 1 ? "" : "s");
            snprintf(vb, sizeof vb, "%d item%s", nb, nb == 1 ? "" : "s");
            int ok = (k->flags & CD_KF_RESUMABLE) || allowed(k->path, allow, n_allow);
            add_line(ok ? accepted : refused, ok ? alen : rlen, fmt, k->path, va, vb, "");
            n_refused += !ok;
            continue;
        }
        if (items_b < items) items = items_b;
        for (int it = 0; it < items; it++) {
            const char *pa = base_of(k, stored, it), *pb = base_of(k, given, it);
            if (!pa || !pb || !differs(k, pa, pb)) continue;
            if (k->target == CD_TGT_CONFIG) {
                snprintf(name, sizeof name, "%s", k->path);
            } else {
                const char *br = strstr(k->path, "[]");
                snprintf(name, sizeof name, "%.*s[%d]%s", br ? (int)(br - k->path) : 0, k->path, it,
                         br ? br + 2 : k->path);
            }
            value_text(k, pa, va, sizeof va);
            value_text(k, pb, vb, sizeof vb);
            if (k->flags & CD_KF_DERIVED)
                note = " (derived from another key when not given: allow it too if that change is meant)";
            else if (!strcmp(k->path, "material.damping_normal")) note = " (or set by material.restitution)";
            else note = "";
            int ok = (k->flags & CD_KF_RESUMABLE) || allowed(name, allow, n_allow);
            add_line(ok ? accepted : refused, ok ? alen : rlen, fmt, name, va, vb, note);
            n_refused += !ok;
        }
    }
    return n_refused;
}
