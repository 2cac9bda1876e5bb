/* The result container of `capdem analyze`: named groups of scalars (with
 * units), texts and tables, filled by the measures and written out by
 * analyze_write.c; and the histogram every distribution uses. */
#include "analysis/analyze.h"
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Makes room in *arr (elements of size sz, n in use) for one more.  The
 * capacity is implied by n: 4, then doubled each time n reaches a power of
 * two, so appends stay O(1) amortised without storing it. */
static int grow(void **arr, int n, size_t sz)
{
    int full = n == 0 || (n >= 4 && (n & (n - 1)) == 0);
    if (!full) return 0;
    int cap = n == 0 ? 4 : 2 * n;
    void *p = realloc(*arr, (size_t)cap * sz);
    if (!p) return -1;
    *arr = p;
    return 0;
}

cd_an_group *cd_an_group_get(cd_an_report *r, const char *name)
{
    for (int k = 0; k < r->n_groups; k++)
        if (!strcmp(r->groups[k].name, name)) return &r->groups[k];
    if (grow((void **)&r->groups, r->n_groups, sizeof(cd_an_group))) return NULL;
    cd_an_group *g = &r->groups[r->n_groups++];
    memset(g, 0, sizeof(*g));
    snprintf(g->name, sizeof g->name, "%s", name);
    return g;
}

const cd_an_group *cd_an_group_find(const cd_an_report *r, const char *name)
{
    for (int k = 0; k < r->n_groups; k++)
        if (!strcmp(r->groups[k].name, name)) return &r->groups[k];
    return NULL;
}

void cd_an_put(cd_an_group *g, const char *name, double value, const char *unit)
{
    if (!g) return;
    for (int k = 0; k < g->n_scalars; k++)
        if (!strcmp(g->scalars[k].name, name)) {
            g->scalars[k].value = value;
            snprintf(g->scalars[k].unit, sizeof g->scalars[k].unit, "%s", unit);
            return;
        }
    if (grow((void **)&g->scalars, g->n_scalars, sizeof(cd_an_scalar))) return;
    cd_an_scalar *s = &g->scalars[g->n_scalars++];
    snprintf(s->name, sizeof s->name, "%s", name);
    s->value = value;
    snprintf(s->unit, sizeof s->unit, "%s", unit);
}

void cd_an_put_text(cd_an_group *g, const char *name, const char *fmt, ...)
{
    if (!g) return;
    cd_an_text *t = NULL;
    for (int k = 0; k < g->n_texts; k++)
        if (!strcmp(g->texts[k].name, name)) t = &g->texts[k];
    if (!t) {
        if (grow((void **)&g->texts, g->n_texts, sizeof(cd_an_text))) return;
        t = &g->texts[g->n_texts++];
        snprintf(t->name, sizeof t->name, "%s", name);
    }
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(t->text, sizeof t->text, fmt, ap);
    va_end(ap);
}

double *cd_an_put_curve(cd_an_group *g, const char *name, size_t rows, const char *columns, const char *units)
{
    if (!g) return NULL;
    int cols = 1;
    for (const char *c = columns; *c; c++) cols += *c == ',';
    double *data = calloc(rows ? rows * (size_t)cols : 1, sizeof(double));
    if (!data) return NULL;
    if (grow((void **)&g->curves, g->n_curves, sizeof(cd_an_curve))) {
        free(data);
        return NULL;
    }
    cd_an_curve *c = &g->curves[g->n_curves++];
    memset(c, 0, sizeof(*c));
    snprintf(c->name, sizeof c->name, "%s", name);
    snprintf(c->columns, sizeof c->columns, "%s", columns);
    snprintf(c->units, sizeof c->units, "%s", units);
    c->rows = rows;
    c->cols = cols;
    c->data = data;
    return data;
}

double cd_an_value(const cd_an_report *r, const char *group, const char *name)
{
    const cd_an_group *g = cd_an_group_find(r, group);
    if (!g) return NAN;
    for (int k = 0; k < g->n_scalars; k++)
        if (!strcmp(g->scalars[k].name, name)) return g->scalars[k].value;
    return NAN;
}

const cd_an_curve *cd_an_curve_find(const cd_an_report *r, const char *group, const char *name)
{
    const cd_an_group *g = cd_an_group_find(r, group);
    if (!g) return NULL;
    for (int k = 0; k < g->n_curves; k++)
        if (!strcmp(g->curves[k].name, name)) return &g->curves[k];
    return NULL;
}

void cd_an_report_free(cd_an_report *r)
{
    for (int k = 0; k < r->n_groups; k++) {
        cd_an_group *g = &r->groups[k];
        for (int c = 0; c < g->n_curves; c++) free(g->curves[c].data);
        free(g->curves);
        free(g->scalars);
        free(g->texts);
    }
    free(r->groups);
    memset(r, 0, sizeof(*r));
}

void cd_an_histogram(const double *x, size_t n, double lo, double w, int nb, double *counts, size_t *under,
                     size_t *over)
{
    size_t u = 0, o = 0;
    for (int b = 0; b < nb; b++) counts[b] = 0;
    for (size_t i = 0; i < n; i++) {
        double t = (x[i] - lo) / w;
        if (!(t >= 0)) {
            u++;
            continue;
        } /* NaN counts as outside too */
        if (t >= nb) {
            o++;
            continue;
        }
        counts[(int)t] += 1;
    }
    if (under) *under = u;
    if (over) *over = o;
}

void cd_an_put_fit(cd_an_group *g, const char *const *names, const cd_an_nlfit *f)
{
    for (int k = 0; k < f->np; k++) {
        char key[64];
        cd_an_put(g, names[k], f->p[k], "1");
        snprintf(key, sizeof key, "%s_lo", names[k]);
        cd_an_put(g, key, f->lo[k], "1");
        snprintf(key, sizeof key, "%s_hi", names[k]);
        cd_an_put(g, key, f->hi[k], "1");
    }
}
