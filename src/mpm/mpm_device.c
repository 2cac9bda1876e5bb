/* Where the material point method's step runs (docs/mpm.md, "Work items";
 * docs/offload.md): the columns its loops work on.
 *
 * Default build: the loops are host-thread loops over m's own columns; the
 * functions below cost nothing.  Offload builds (CAPDEM_OFFLOAD=nvptx|host):
 * the state lives on the offload device from the first step on.  The point,
 * body and common-node columns are mapped once (target enter data; their
 * host copies are brought up to date by cd_mpm_device_sync); the body-node
 * columns, whose count changes every step, and the contact pairs' keys are
 * device allocations of their own, grown with a margin; the step's serial
 * parts (sorts, offsets, sums in a fixed order) run there as one-item
 * loops.  A host change to the columns after the first step must be
 * followed by cd_mpm_device_stop (the next step maps the state anew).
 *
 * Every build: the step's checks, counts and observed sums
 * (kernels/mpm_checks.h) live where the loops run, one block the host
 * reads in one copy at cd_mpm_settle, and nothing else comes back between
 * steps (docs/mpm.md, "Reading nothing between steps"); the OpenCL
 * backend (src/mpm/mpm_cl.c) keeps its own and shares cd_mpm_checks_apply. */
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "mpm/mpm.h"
#include "backend/omp/omp_loops.h"
#include "mpm_checks.h"

/* The checks block, where the loops run. */
typedef struct {
    cd_int flags[2 * CD_MPM_N_FAILS];
    cd_ulong counts[CD_MPM_N_COUNTS];
    double reals[CD_MPM_N_REALS];
} cd_mpm_checks;

#if CD_OFFLOAD
/* The host columns mapped to the device: address and bytes. */
static int mapped_cols(cd_mpm *m, void **host, size_t *bytes)
{
    size_t n = m->n, nb = (size_t)m->n_bodies, nn = (size_t)m->nx * (size_t)m->ny, d = sizeof(double),
           u = sizeof(cd_ulong), i4 = sizeof(int);
    /* per point: 18 doubles, then the 4 stencil columns */
    double *pd[] = {m->x,   m->y,   m->vx,    m->vy,   m->mass, m->vol,  m->half, m->sxx, m->syy,
                    m->sxy, m->szz, m->eps_p, m->f_xx, m->f_xy, m->f_yx, m->f_yy, m->ex,  m->ey};
    double *ps[] = {m->wx, m->wy, m->dwx, m->dwy};
    int k = 0;
    for (size_t i = 0; i < sizeof pd / sizeof pd[0]; i++, k++) host[k] = pd[i], bytes[k] = n * d;
    for (size_t i = 0; i < sizeof ps / sizeof ps[0]; i++, k++) host[k] = ps[i], bytes[k] = CD_MPM_STENCIL * n * d;
    /* per point ints and order; per body; per common node */
    void *rest[] = {m->particle, m->bx,     m->by,     m->order,    m->pfirst,  m->win_off,  m->win_i0,
                    m->win_j0,   m->win_nx, m->win_ny, m->cn_start, m->cn_list, m->cn_active};
    size_t rest_b[] = {n * i4,  n * i4,  n * i4,  n * u,        (nb + 1) * u, (nb + 1) * u,        nb * i4,
                       nb * i4, nb * i4, nb * i4, (nn + 1) * u, nn * u,       nn * sizeof(cd_uint)};
    for (size_t i = 0; i < sizeof rest / sizeof rest[0]; i++, k++) host[k] = rest[i], bytes[k] = rest_b[i];
    return k;
}

static void *devptr(void *p)
{
    void *r = p;
#pragma omp target data use_device_ptr(r)
    {
        p = r;
    }
    return p;
}

#define MPM_MAPPED 40

enum { MAP_ENTER, MAP_UPDATE_FROM, MAP_DELETE };

/* Every mapped column: mapped to the device, brought back, or unmapped. */
static void map_all(cd_mpm *m, int op)
{
    void *host[MPM_MAPPED];
    size_t bytes[MPM_MAPPED];
    int k = mapped_cols(m, host, bytes);
    for (int i = 0; i < k; i++) {
        char *c = host[i];
        size_t nb = bytes[i];
        if (!c || !nb) continue;
        if (op == MAP_ENTER) {
#pragma omp target enter data map(to : c [0:nb])
        } else if (op == MAP_UPDATE_FROM) {
#pragma omp target update from(c [0:nb])
        } else {
#pragma omp target exit data map(delete : c [0:nb])
        }
    }
}

static void free_bnodes(cd_mpm *m)
{
    cd_mpm_cols *c = &m->loop_cols;
    void *cols[] = {c->gm,  c->gpx, c->gpy, c->gfx,        c->gfy,        c->gvx,
                    c->gvy, c->gnx, c->gny, c->bnode_body, c->cell_start, c->cn_entry};
    for (size_t i = 0; i < sizeof cols / sizeof cols[0]; i++) cd_dev_free(cols[i]);
    c->gm = c->gpx = c->gpy = c->gfx = c->gfy = c->gvx = c->gvy = c->gnx = c->gny = NULL;
    c->bnode_body = NULL;
    c->cell_start = c->cn_entry = NULL;
    m->loop_cap = 0;
}
#endif

/* The loops' scratch: the checks block and the contact's lists. */
static int scratch_alloc(cd_mpm *m)
{
    if (m->loop_checks) return 0;
    size_t ny = (size_t)m->ny, nn = (size_t)m->nx * ny, nb = m->n_bodies > 0 ? (size_t)m->n_bodies : 1;
    m->loop_checks = cd_dev_alloc(sizeof(cd_mpm_checks));
    m->loop_row_n = cd_dev_alloc(ny * sizeof(cd_int));
    m->loop_rows = cd_dev_alloc(ny * nb * sizeof(cd_int));
    m->loop_blocks = cd_dev_alloc(2 * ((nn + CD_MPM_CN_BLOCK - 1) / CD_MPM_CN_BLOCK) * sizeof(cd_ulong));
    m->loop_over = cd_dev_alloc(nn * sizeof(double));
    m->loop_args = cd_dev_alloc(sizeof(cd_mpm_cols));
    if (!m->loop_checks || !m->loop_row_n || !m->loop_rows || !m->loop_blocks || !m->loop_over || !m->loop_args)
        return -1;
    /* (device addresses: offsets into the block, not dereferenced here) */
    char *b = m->loop_checks;
    m->loop_flags = (cd_int *)(void *)(b + offsetof(cd_mpm_checks, flags));
    m->loop_counts = (cd_ulong *)(void *)(b + offsetof(cd_mpm_checks, counts));
    m->loop_reals = (double *)(void *)(b + offsetof(cd_mpm_checks, reals));
    return 0;
}

void cd_mpm_loop_args_refresh(cd_mpm *m)
{
    cd_mpm_cols c = cd_mpm_loop_cols(m), *args = m->loop_args;
    CD_WIDE_MIN
    CD_STEP_FOR(1, firstprivate(c) CD_DEV(is_device_ptr(args)))
    for (int one = 0; one < 1; one++) *args = c;
}

/* The checks as before any step, where the loops run (a one-item loop: no copy). */
static void checks_clear(cd_mpm *m)
{
    cd_int *flags = m->loop_flags;
    cd_ulong *counts = m->loop_counts;
    double *reals = m->loop_reals;
    CD_WIDE_MIN
    CD_STEP_FOR(1, CD_DEV(is_device_ptr(flags, counts, reals)))
    for (int one = 0; one < 1; one++) cd_mpm_checks_clear(flags, counts, reals);
    m->pending = 0;
}

int cd_mpm_device_start(cd_mpm *m, char *err, size_t errlen)
{
    if (m->loop_on) return 0;
    if (scratch_alloc(m)) {
        snprintf(err, errlen, "out of device memory for the step's scratch");
        return -1;
    }
    checks_clear(m);
    m->sized = 0;
#if CD_OFFLOAD
    map_all(m, MAP_ENTER);
    cd_mpm_cols c = cd_mpm_step_cols(m);
    CD_GLOBAL cd_real **dcols[] = {&c.x,   &c.y,   &c.vx,  &c.vy,    &c.mass, &c.vol,  &c.half_side, &c.sxx,
                                   &c.syy, &c.sxy, &c.szz, &c.eps_p, &c.f_xx, &c.f_xy, &c.f_yx,      &c.f_yy,
                                   &c.ex,  &c.ey,  &c.wx,  &c.wy,    &c.dwx,  &c.dwy};
    for (size_t i = 0; i < sizeof dcols / sizeof dcols[0]; i++) *dcols[i] = devptr(*dcols[i]);
    CD_GLOBAL cd_int **icols[] = {&c.particle, &c.bx, &c.by, &c.win_i0, &c.win_j0, &c.win_nx, &c.win_ny};
    for (size_t i = 0; i < sizeof icols / sizeof icols[0]; i++) *icols[i] = devptr(*icols[i]);
    CD_GLOBAL cd_ulong **ucols[] = {&c.order, &c.pfirst, &c.win_off, &c.cn_start, &c.cn_list};
    for (size_t i = 0; i < sizeof ucols / sizeof ucols[0]; i++) *ucols[i] = devptr(*ucols[i]);
    c.cn_active = devptr(c.cn_active);
    m->loop_cols = c; /* the body-node columns: cd_mpm_device_reserve */
    m->loop_cap = 0;
#endif
    m->loop_on = 1;
    cd_mpm_loop_args_refresh(m);
    return 0;
}

int cd_mpm_device_reserve(cd_mpm *m, size_t n)
{
#if CD_OFFLOAD
    if (n <= m->loop_cap) return 0;
    free_bnodes(m);
    size_t cap = n + n / 4 + 64;
    cd_mpm_cols *c = &m->loop_cols;
    CD_GLOBAL cd_real **cols[] = {&c->gm, &c->gpx, &c->gpy, &c->gfx, &c->gfy, &c->gvx, &c->gvy, &c->gnx, &c->gny};
    int ok = 1;
    for (size_t i = 0; i < sizeof cols / sizeof cols[0]; i++)
        ok &= (*cols[i] = cd_dev_alloc(cap * sizeof(double))) != NULL;
    ok &= (c->bnode_body = cd_dev_alloc(cap * sizeof(cd_int))) != NULL;
    ok &= (c->cell_start = cd_dev_alloc((cap + 1) * sizeof(cd_ulong))) != NULL;
    ok &= (c->cn_entry = cd_dev_alloc(cap * sizeof(cd_ulong))) != NULL;
    if (!ok) {
        free_bnodes(m);
        return -1;
    }
    m->loop_cap = cap;
#else
    (void)m;
    (void)n;
#endif
    return 0;
}

int cd_mpm_device_keys(cd_mpm *m, size_t n)
{
    if (n <= m->loop_cap_keys) return 0;
    cd_dev_free(m->loop_keys);
    m->loop_cap_keys = 0;
    m->loop_keys = cd_dev_alloc((n + 64) * sizeof(cd_long));
    if (!m->loop_keys) return -1;
    m->loop_cap_keys = n + 64;
    return 0;
}

size_t cd_mpm_loop_rows(const cd_mpm *m)
{
#if CD_OFFLOAD
    if (m->loop_on) return m->loop_cap;
#endif
    return m->cap_bnodes;
}

cd_mpm_cols cd_mpm_loop_cols(const cd_mpm *m)
{
#if CD_OFFLOAD
    if (m->loop_on) {
        cd_mpm_cols c = m->loop_cols;
        c.n_bodies = m->n_bodies;
        return c;
    }
#endif
    return cd_mpm_step_cols(m);
}

void cd_mpm_device_sync(cd_mpm *m)
{
    if (m->cl) {
        cd_mpm_cl_sync(m);
        return;
    }
#if CD_OFFLOAD
    if (m->loop_on) map_all(m, MAP_UPDATE_FROM);
#else
    (void)m;
#endif
}

int cd_mpm_settle(cd_mpm *m, char *err, size_t errlen)
{
    if (m->cl) return cd_mpm_cl_settle(m, err, errlen);
    if (!m->loop_on || m->pending == 0) return 0;
    cd_mpm_checks k;
    if (cd_dev_get(&k, m->loop_checks, sizeof k)) {
        snprintf(err, errlen, "cannot read the step's checks from the offload device");
        return -1;
    }
    int rc = cd_mpm_checks_apply(m, k.flags, k.counts, k.reals, err, errlen);
    if (rc == 0) cd_mpm_device_sync(m);
    if (rc == 1) {
        if (cd_mpm_bnodes_room(m, k.counts[CD_MPM_COUNT_BNODES], err, errlen)) return -1;
        checks_clear(m);
    }
    return rc;
}

int cd_mpm_record_start(cd_mpm *m, char *err, size_t errlen)
{
    if ((size_t)m->pending >= m->cap_since) {
        size_t cap = 2 * m->cap_since + 16;
        cd_mpm_step_start *q = realloc(m->since, cap * sizeof *q);
        if (!q) {
            snprintf(err, errlen, "out of memory for the record of %d steps", m->pending + 1);
            return -1;
        }
        m->since = q;
        m->cap_since = cap;
    }
    cd_mpm_step_start *s = &m->since[m->pending];
    s->time = m->time;
    for (int w = 0; w < m->n_walls; w++) {
        s->px[w] = m->walls[w].px;
        s->py[w] = m->walls[w].py;
    }
    return 0;
}

int cd_mpm_checks_apply(cd_mpm *m, const cd_int *flags, const cd_ulong *counts, const double *reals, char *err,
                        size_t errlen)
{
    int fail = -1; /* the first failure: the earliest step, and in a step the earliest check */
    cd_int at = CD_MPM_NEVER;
    for (int f = 0; f < CD_MPM_N_FAILS; f++)
        if (flags[CD_MPM_N_FAILS + f] < at) at = flags[CD_MPM_N_FAILS + f], fail = f;
    if (fail < 0) {
        m->n_bnodes = counts[CD_MPM_COUNT_BNODES];
        m->n_cn = m->n_bodies > 1 ? counts[CD_MPM_COUNT_LISTED] : 0;
        if (m->observe) { /* the last step computed them */
            for (int w = 0; w < m->n_walls; w++) {
                m->walls[w].fx = reals[CD_MPM_REAL_WALLS + 2 * w];
                m->walls[w].fy = reals[CD_MPM_REAL_WALLS + 2 * w + 1];
            }
            if (m->n_bodies > 1) m->penetration = reals[CD_MPM_REAL_PEN];
            m->mesh_kinetic = reals[CD_MPM_REAL_KINETIC];
        }
        m->pending = 0;
        return 0;
    }
    /* back to where the failing step began: as the step stood when it returned at once */
    const cd_mpm_step_start *s = &m->since[at];
    m->step -= m->pending - at;
    m->time = s->time;
    for (int w = 0; w < m->n_walls; w++) {
        m->walls[w].px = s->px[w];
        m->walls[w].py = s->py[w];
    }
    m->pending = 0;
    if (fail == CD_MPM_FAIL_OVERFLOW) return 1; /* the caller grows the columns; the run steps on from here */
    if (fail == CD_MPM_FAIL_LEFT) return cd_mpm_fail_left_mesh(m, (size_t)flags[fail], err, errlen);
    if (fail == CD_MPM_FAIL_CROWDED) return cd_mpm_fail_crowded(m, (size_t)flags[fail], err, errlen);
    return cd_mpm_fail_blew_up(m, flags[fail], err, errlen);
}

void cd_mpm_device_stop(cd_mpm *m)
{
    if (m->cl) { /* the OpenCL buffers stay; the next step uploads the host columns again */
        m->loop_on = 0;
        return;
    }
#if CD_OFFLOAD
    if (m->loop_on) {
        map_all(m, MAP_DELETE);
        free_bnodes(m);
    }
#endif
    void *scratch[] = {m->loop_checks, m->loop_row_n, m->loop_rows, m->loop_blocks,
                       m->loop_over,   m->loop_keys,  m->loop_args};
    for (size_t i = 0; i < sizeof scratch / sizeof scratch[0]; i++) cd_dev_free(scratch[i]);
    m->loop_checks = NULL;
    m->loop_flags = NULL;
    m->loop_counts = NULL;
    m->loop_reals = NULL;
    m->loop_row_n = m->loop_rows = NULL;
    m->loop_blocks = NULL;
    m->loop_over = NULL;
    m->loop_keys = NULL;
    m->loop_args = NULL;
    m->loop_cap_keys = 0;
    m->loop_on = 0;
}
