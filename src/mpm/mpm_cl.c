/* The material point method on the OpenCL backend (docs/mpm.md, "The
 * OpenCL backend"): the step of src/mpm/mpm.c, loop for loop, as launches
 * of the kernels of kernels/cl/mpm.cl, which wrap the same items
 * (kernels/mpm_step_items.h, kernels/mpm_contact.h).  The device, context
 * and program are the DEM backend's (src/backend/opencl: cd_cl_open builds
 * every .cl file of kernels/cl, this one's kernels included).
 *
 * The state lives in device buffers from the first step on: the columns of
 * kernels/cl/mpm_col_list.h, the body-node ones sized at the first step
 * with a margin.  A step only enqueues: nothing is read back between steps.
 * The kernels run over sizes the host knows (points, bodies, the body-node
 * buffers' rows, a bound on the listed common nodes) and read the counts
 * the step makes from the device; failures (a point left the mesh, the
 * body-nodes outgrew their buffers, a crowded common node, a point blew
 * up) are integer atomics with the step they were seen at, and stop every
 * later kernel.  The host looks only where the run reads the state (a
 * series row, a snapshot, the progress line: cd_mpm_cl_settle): it then
 * reads the checks, the counts and the observed step's sums (walls'
 * forces, the deepest overlap, the mesh's kinetic energy, computed only at
 * the steps the run marks in m->observe) and downloads the columns; after
 * a failure it goes back to the failing step's start (time, step and walls
 * from a record of the steps since it last looked) and reports it as the
 * omp loops do; after an overflow it grows the buffers and the run steps
 * on from there.  Every floating-point sum is an item's gather or a
 * one-item loop in a fixed order, so the bits are those of the omp backend
 * where the device rounds as the host does. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "mpm/mpm.h"

#ifdef CAPDEM_HAVE_OPENCL
#include "backend/opencl/backend_cl.h"
#include "cl/mpm_col_list.h"
#include "mpm_checks.h"

/* Kernels of kernels/cl/mpm.cl; every one takes the columns, the mesh and the checks first. */
enum {
    K_PREPARE,
    K_WALL_FORCE,
    K_WINDOW,
    K_WINDOW_OFFSETS,
    K_BNODE_BODY,
    K_SORT_BODY,
    K_TO_GRID,
    K_NODE_UPDATE,
    K_CN_ROWS,
    K_CN_COUNT,
    K_CN_BLOCK_SUMS,
    K_CN_BLOCK_SCAN,
    K_CN_BLOCK_STARTS,
    K_CN_ENTRIES,
    K_CONTACT_CROWDED,
    K_CONTACT,
    K_MAX_OVER,
    K_POINT_UPDATE,
    K_REMAP,
    K_MESH_KINETIC,
    K_STRESS,
    K_PAIR_KEYS,
    K_COUNT
};
static const struct {
    const char *name;
    int one_item; /* the serial parts: one work-item */
} kernel_table[K_COUNT] = {
    {"cd_mpm_cl_prepare", 0},         {"cd_mpm_cl_wall_force", 0},    {"cd_mpm_cl_window", 0},
    {"cd_mpm_cl_window_offsets", 1},  {"cd_mpm_cl_bnode_body", 0},    {"cd_mpm_cl_sort_body", 0},
    {"cd_mpm_cl_to_grid", 0},         {"cd_mpm_cl_node_update", 0},   {"cd_mpm_cl_cn_rows", 0},
    {"cd_mpm_cl_cn_count", 0},        {"cd_mpm_cl_cn_block_sums", 0}, {"cd_mpm_cl_cn_block_scan", 1},
    {"cd_mpm_cl_cn_block_starts", 0}, {"cd_mpm_cl_cn_entries", 0},    {"cd_mpm_cl_contact_crowded", 0},
    {"cd_mpm_cl_contact", 0},         {"cd_mpm_cl_max_over", 1},      {"cd_mpm_cl_point_update", 0},
    {"cd_mpm_cl_remap", 0},           {"cd_mpm_cl_mesh_kinetic", 1},  {"cd_mpm_cl_stress", 0},
    {"cd_mpm_cl_pair_keys", 1},
};

/* Columns, in the kernels' parameter order; and what their rows are. */
enum {
#define COL_ENUM(type, name, host, rows) COL_##name,
    CD_MPM_CL_COLS(COL_ENUM)
#undef COL_ENUM
        N_COLS
};
enum rows_kind { POINT, STENCIL, BODY, BODY1, BNODE, BNODE1, NODE, NODE1 };
static const struct {
    size_t size;
    enum rows_kind rows;
} col_table[N_COLS] = {
#define COL_INFO(type, name, host, rows) {sizeof(type), rows},
    CD_MPM_CL_COLS(COL_INFO)
#undef COL_INFO
};
/* The arguments after the columns: the mesh (nx, ny, n_bodies, h, ox, oy),
 * the checks (flags, counts, j); then each kernel's own. */
#define ARG_FLAGS (N_COLS + 6)
#define ARG_J     (N_COLS + 8)
#define FIRST_ARG (N_COLS + 9)

/* The checks (kernels/mpm_checks.h): flags, counts, an observed step's sums. */
#define N_FLAGS (2 * CD_MPM_N_FAILS)

struct cd_mpm_cl {
    cd_cl cl;
    cl_kernel k[K_COUNT];
    cl_mem col[N_COLS];
    size_t cap_bnodes;   /* body-node rows of the BNODE columns */
    cl_mem flags, reals; /* N_FLAGS cd_int, CD_MPM_N_REALS cd_real */
    cl_mem count;        /* CD_MPM_N_COUNTS cd_ulong */
    cl_mem over;         /* cd_real per common node: the contact's overlaps */
    cl_mem keys;         /* cd_long: the contact pairs' keys */
    size_t cap_keys;
    cl_mem row_n, rows; /* the common nodes' lists: bodies per mesh row (cd_int ny, ny x n_bodies) */
    cl_mem blocks;      /* cd_ulong 2 per CD_MPM_CN_BLOCK common nodes */
};

static size_t rows_of(const cd_mpm *m, enum rows_kind r)
{
    size_t n = m->n, nb = (size_t)m->n_bodies, nn = (size_t)m->nx * (size_t)m->ny, t = m->cl->cap_bnodes;
    switch (r) {
    case POINT:
        return n;
    case STENCIL:
        return CD_MPM_STENCIL * n;
    case BODY:
        return nb;
    case BODY1:
        return nb + 1;
    case BNODE:
        return t;
    case BNODE1:
        return t + 1;
    case NODE:
        return nn;
    default:
        return nn + 1;
    }
}

static void *host_col(const cd_mpm *m, int f)
{
    void *cols[N_COLS] = {
#define COL_HOST(type, name, host, rows) (void *)m->host,
        CD_MPM_CL_COLS(COL_HOST)
#undef COL_HOST
    };
    return cols[f];
}

static int arg(struct cd_mpm_cl *d, int k, cl_uint i, size_t size, const void *value)
{
    cl_int rc = clSetKernelArg(d->k[k], i, size, value);
    if (rc == CL_SUCCESS || d->cl.status) return d->cl.status ? -1 : 0;
    char what[96];
    snprintf(what, sizeof what, "setting argument %u of %s", i, kernel_table[k].name);
    cd_cl_check(&d->cl, rc, what);
    return -1;
}

static int arg_mem(struct cd_mpm_cl *d, int k, cl_uint i, cl_mem b) { return arg(d, k, i, sizeof b, &b); }
static int arg_ulong(struct cd_mpm_cl *d, int k, cl_uint i, size_t v)
{
    cl_ulong u = v;
    return arg(d, k, i, sizeof u, &u);
}
static int arg_real(struct cd_mpm_cl *d, int k, cl_uint i, double v) { return arg(d, k, i, sizeof v, &v); }

/* Kernel k over n items (the one-item kernels: one work-item; none when n is 0). */
static int launch(struct cd_mpm_cl *d, int k, size_t n)
{
    if (d->cl.status) return -1;
    if (n == 0) return 0;
    size_t local = kernel_table[k].one_item ? 1 : d->cl.local;
    size_t global = kernel_table[k].one_item ? 1 : (n + local - 1) / local * local; /* the kernels skip items >= n */
    cl_int rc = clEnqueueNDRangeKernel(d->cl.queue, d->k[k], 1, NULL, &global, &local, 0, NULL, NULL);
    return cd_cl_check(&d->cl, rc, kernel_table[k].name) ? -1 : 0;
}

static int read_buf(struct cd_mpm_cl *d, cl_mem b, size_t offset, size_t bytes, void *host, const char *what)
{
    if (d->cl.status || bytes == 0) return d->cl.status ? -1 : 0;
    return cd_cl_check(&d->cl, clEnqueueReadBuffer(d->cl.queue, b, CL_TRUE, offset, bytes, host, 0, NULL, NULL), what)
               ? -1
               : 0;
}

/* Column f's buffer and its arguments of every kernel that takes the columns. */
static int bind_col(cd_mpm *m, int f, cl_mem b)
{
    struct cd_mpm_cl *d = m->cl;
    if (d->col[f]) clReleaseMemObject(d->col[f]);
    d->col[f] = b;
    for (int k = 0; k < K_COUNT && b; k++)
        if (arg_mem(d, k, (cl_uint)f, b)) return -1;
    return b ? 0 : -1;
}

/* Room for nbn body-nodes in the BNODE columns (their contents dropped, as
 * the omp backend's): rebinds them. */
static int reserve_bnodes(cd_mpm *m, size_t nbn)
{
    struct cd_mpm_cl *d = m->cl;
    if (nbn <= d->cap_bnodes) return 0;
    d->cap_bnodes = nbn + nbn / 4 + 64;
    for (int f = 0; f < N_COLS; f++)
        if ((col_table[f].rows == BNODE || col_table[f].rows == BNODE1) &&
            bind_col(m, f,
                     cd_cl_buffer(&d->cl, rows_of(m, col_table[f].rows) * col_table[f].size,
                                  "allocating the body-node columns")))
            return -1;
    return 0;
}

/* The contact's row lists hold a row per mesh row, each room for every body. */
static size_t nb_rows(const cd_mpm *m) { return m->n_bodies > 0 ? (size_t)m->n_bodies : 1; }
/* Blocks of CD_MPM_CN_BLOCK common nodes. */
static size_t n_blocks(const cd_mpm *m)
{
    return ((size_t)m->nx * (size_t)m->ny + CD_MPM_CN_BLOCK - 1) / CD_MPM_CN_BLOCK;
}

/* The checks as they are before any step: no failure, never seen. */
static int reset_flags(cd_mpm *m)
{
    struct cd_mpm_cl *d = m->cl;
    static const cd_int none[N_FLAGS] = {-1, -1, -1, -1, CD_MPM_NEVER, CD_MPM_NEVER, CD_MPM_NEVER, CD_MPM_NEVER};
    m->pending = 0;
    return cd_cl_check(&d->cl,
                       clEnqueueWriteBuffer(d->cl.queue, d->flags, CL_TRUE, 0, sizeof none, none, 0, NULL, NULL),
                       "resetting the step's checks")
               ? -1
               : 0;
}

/* The first step (or the first after cd_mpm_device_stop): the buffers and
 * the host's columns on the device, the mesh's and the checks' arguments. */
static int start(cd_mpm *m)
{
    struct cd_mpm_cl *d = m->cl;
    cd_cl *cl = &d->cl;
    if (!d->flags) {
        for (int f = 0; f < N_COLS; f++)
            if (col_table[f].rows != BNODE && col_table[f].rows != BNODE1 &&
                bind_col(m, f,
                         cd_cl_buffer(cl, rows_of(m, col_table[f].rows) * col_table[f].size,
                                      "allocating the material points' columns")))
                return -1;
        if (reserve_bnodes(m, 1)) return -1; /* bound before the first step's count sizes them */
        size_t nn = (size_t)m->nx * (size_t)m->ny;
        d->flags = cd_cl_buffer(cl, N_FLAGS * sizeof(cd_int), "allocating the step's checks");
        d->reals = cd_cl_buffer(cl, CD_MPM_N_REALS * sizeof(cd_real), "allocating the step's sums");
        d->count = cd_cl_buffer(cl, CD_MPM_N_COUNTS * sizeof(cd_ulong), "allocating the step's counts");
        d->over = cd_cl_buffer(cl, nn * sizeof(cd_real), "allocating the contact's overlaps");
        d->row_n = cd_cl_buffer(cl, (size_t)m->ny * sizeof(cd_int), "allocating the contact's row lists");
        d->rows = cd_cl_buffer(cl, (size_t)m->ny * nb_rows(m) * sizeof(cd_int), "allocating the contact's row lists");
        d->blocks = cd_cl_buffer(cl, 2 * n_blocks(m) * sizeof(cd_ulong), "allocating the contact's block sums");
        if (!d->flags || !d->reals || !d->count || !d->over || !d->row_n || !d->rows || !d->blocks) return -1;
        cl_int nx = m->nx, ny = m->ny, nb = m->n_bodies;
        double mesh[3] = {m->h, m->ox, m->oy}; /* [m] */
        for (int k = 0; k < K_COUNT; k++)
            if (arg(d, k, N_COLS, sizeof nx, &nx) || arg(d, k, N_COLS + 1, sizeof ny, &ny) ||
                arg(d, k, N_COLS + 2, sizeof nb, &nb) || arg_real(d, k, N_COLS + 3, mesh[0]) ||
                arg_real(d, k, N_COLS + 4, mesh[1]) || arg_real(d, k, N_COLS + 5, mesh[2]) ||
                arg_mem(d, k, ARG_FLAGS, d->flags) || arg_mem(d, k, ARG_FLAGS + 1, d->count))
                return -1;
    }
    for (int f = 0; f < N_COLS && !cl->status; f++) {
        size_t bytes = rows_of(m, col_table[f].rows) * col_table[f].size;
        if (col_table[f].rows == BNODE || col_table[f].rows == BNODE1 || bytes == 0) continue;
        cd_cl_check(cl, clEnqueueWriteBuffer(cl->queue, d->col[f], CL_TRUE, 0, bytes, host_col(m, f), 0, NULL, NULL),
                    "uploading the material points");
    }
    if (cl->status || reset_flags(m)) return -1;
    m->sized = 0;
    m->loop_on = 1;
    return 0;
}

/* Arguments after the columns, the mesh and the checks, then the launch. */
#define LAUNCH_WITH(k, n, ...)                                                                                         \
    do {                                                                                                               \
        cl_uint a_ = FIRST_ARG;                                                                                        \
        (void)a_;                                                                                                      \
        arg(d, k, ARG_J, sizeof m->pending, &m->pending);                                                              \
        __VA_ARGS__;                                                                                                   \
        launch(d, k, n);                                                                                               \
    } while (0)
#define A_MEM(k, b)   arg_mem(d, k, a_++, b)
#define A_ULONG(k, v) arg_ulong(d, k, a_++, v)
#define A_REAL(k, v)  arg_real(d, k, a_++, v)
#define A_ANY(k, v)   arg(d, k, a_++, sizeof(v), &(v))

/* As cd_mpm_step, loop for loop (src/mpm/mpm.c, src/mpm/mpm_contact.c),
 * enqueued only: the host reads nothing until cd_mpm_cl_settle, except the
 * body-node count once at the first step (to size their buffers). */
int cd_mpm_cl_step(cd_mpm *m, char *err, size_t errlen)
{
    struct cd_mpm_cl *d = m->cl;
    cd_cl *cl = &d->cl;
    if (!m->loop_on && start(m)) goto failed;
    if (cd_mpm_record_start(m, err, errlen)) return -1;
    size_t n = m->n, nb = (size_t)m->n_bodies;
    double dt = m->dt; /* [s] */
    /* stencils, wall forces, windows, the points sorted by (body, cell) */
    cd_mpm_item_walls walls = cd_mpm_walls_items(m);
    LAUNCH_WITH(K_PREPARE, n, A_ULONG(K_PREPARE, n); A_ANY(K_PREPARE, walls));
    if (m->observe)
        LAUNCH_WITH(K_WALL_FORCE, (size_t)m->n_walls, A_ULONG(K_WALL_FORCE, n); A_ANY(K_WALL_FORCE, walls);
                    A_MEM(K_WALL_FORCE, d->reals)); /* at CD_MPM_REAL_WALLS = 0 */
    LAUNCH_WITH(K_WINDOW, nb, );
    /* the first step sizes the body-node buffers from its count; later
     * steps check it against them on the device (failure OVERFLOW) */
    LAUNCH_WITH(K_WINDOW_OFFSETS, 1, A_ULONG(K_WINDOW_OFFSETS, m->sized ? d->cap_bnodes : (size_t)-1));
    if (!m->sized) { /* (unless the step already failed: then it stops here and settle reports it) */
        cl_ulong nbn;
        cd_int left;
        if (read_buf(d, d->count, 0, sizeof nbn, &nbn, "reading the body-node count") ||
            read_buf(d, d->flags, CD_MPM_FAIL_LEFT * sizeof(cd_int), sizeof left, &left, "reading the step's checks") ||
            (left < 0 && reserve_bnodes(m, nbn)))
            goto failed;
        m->sized = 1;
    }
    size_t rows = d->cap_bnodes;                                                               /* body-node kernels */
    size_t nn = (size_t)m->nx * (size_t)m->ny, listed = rows / 2 + 1 < nn ? rows / 2 + 1 : nn; /* >= listed nodes */
    LAUNCH_WITH(K_BNODE_BODY, nb, );
    LAUNCH_WITH(K_SORT_BODY, nb, );
    /* to the grid, node update, contact */
    cd_int normals = m->n_bodies > 1;
    LAUNCH_WITH(K_TO_GRID, rows, A_ANY(K_TO_GRID, normals));
    LAUNCH_WITH(K_NODE_UPDATE, rows, A_REAL(K_NODE_UPDATE, dt));
    if (m->n_bodies > 1) {
        size_t nblk = n_blocks(m);
        LAUNCH_WITH(K_CN_ROWS, (size_t)m->ny, A_MEM(K_CN_ROWS, d->row_n); A_MEM(K_CN_ROWS, d->rows));
        LAUNCH_WITH(K_CN_COUNT, nn, A_MEM(K_CN_COUNT, d->row_n); A_MEM(K_CN_COUNT, d->rows));
        LAUNCH_WITH(K_CN_BLOCK_SUMS, nblk, A_MEM(K_CN_BLOCK_SUMS, d->blocks); A_ULONG(K_CN_BLOCK_SUMS, nblk));
        LAUNCH_WITH(K_CN_BLOCK_SCAN, 1, A_MEM(K_CN_BLOCK_SCAN, d->blocks); A_ULONG(K_CN_BLOCK_SCAN, nblk));
        LAUNCH_WITH(K_CN_BLOCK_STARTS, nblk, A_MEM(K_CN_BLOCK_STARTS, d->blocks); A_ULONG(K_CN_BLOCK_STARTS, nblk));
        LAUNCH_WITH(K_CN_ENTRIES, nn, A_MEM(K_CN_ENTRIES, d->row_n); A_MEM(K_CN_ENTRIES, d->rows));
        LAUNCH_WITH(K_CONTACT_CROWDED, listed, );
        LAUNCH_WITH(K_CONTACT, listed, A_REAL(K_CONTACT, m->contact_gap); A_REAL(K_CONTACT, dt);
                    A_MEM(K_CONTACT, d->over));
        if (m->observe) LAUNCH_WITH(K_MAX_OVER, 1, A_MEM(K_MAX_OVER, d->over); A_MEM(K_MAX_OVER, d->reals));
    }
    /* the points' update, MUSL's remap, the stress */
    LAUNCH_WITH(K_POINT_UPDATE, n, A_ULONG(K_POINT_UPDATE, n); A_REAL(K_POINT_UPDATE, dt);
                A_REAL(K_POINT_UPDATE, m->pic_fraction));
    LAUNCH_WITH(K_REMAP, rows, );
    if (m->observe)
        LAUNCH_WITH(K_MESH_KINETIC, 1, A_MEM(K_MESH_KINETIC, d->reals); A_ULONG(K_MESH_KINETIC, CD_MPM_REAL_KINETIC));
    cd_mpm_material mat = m->mat;
    LAUNCH_WITH(K_STRESS, n, A_ULONG(K_STRESS, n); A_REAL(K_STRESS, dt); A_ANY(K_STRESS, mat));
    if (cl->status) goto failed;
    m->pending++;
    cd_mpm_step_done(m);
    return 0;
failed:
    cd_cl_report(cl, err, errlen);
    return -1;
}

/* The columns the host reads (every one but the stencils and the
 * body-nodes, which each step makes anew), from the device. */
void cd_mpm_cl_sync(cd_mpm *m)
{
    struct cd_mpm_cl *d = m->cl;
    if (!m->loop_on) return;
    for (int f = 0; f < N_COLS && !d->cl.status; f++) {
        enum rows_kind r = col_table[f].rows;
        size_t bytes = rows_of(m, r) * col_table[f].size;
        if (r == STENCIL || r == BNODE || r == BNODE1 || bytes == 0) continue;
        cd_cl_check(&d->cl,
                    clEnqueueReadBuffer(d->cl.queue, d->col[f], CL_FALSE, 0, bytes, host_col(m, f), 0, NULL, NULL),
                    "downloading the material points");
    }
    if (!d->cl.status) cd_cl_check(&d->cl, clFinish(d->cl.queue), "downloading the material points");
    /* a failure stays recorded: the next step reports it */
}

int cd_mpm_cl_settle(cd_mpm *m, char *err, size_t errlen)
{
    struct cd_mpm_cl *d = m->cl;
    if (!m->loop_on || m->pending == 0) return 0;
    cd_int flags[N_FLAGS];
    cl_ulong counts[CD_MPM_N_COUNTS];
    double r[CD_MPM_N_REALS];
    if (read_buf(d, d->flags, 0, sizeof flags, flags, "reading the step's checks") ||
        read_buf(d, d->count, 0, sizeof counts, counts, "reading the step's counts") ||
        read_buf(d, d->reals, 0, sizeof r, r, "reading the step's sums"))
        goto failed;
    cd_ulong c[CD_MPM_N_COUNTS];
    for (int i = 0; i < CD_MPM_N_COUNTS; i++) c[i] = counts[i];
    int rc = cd_mpm_checks_apply(m, flags, c, r, err, errlen);
    if (rc == 0) cd_mpm_cl_sync(m);
    if (rc == 1 && (reserve_bnodes(m, counts[CD_MPM_COUNT_BNODES]) || reset_flags(m))) goto failed;
    if (d->cl.status) goto failed;
    return rc;
failed:
    cd_cl_report(&d->cl, err, errlen);
    return -1;
}

int cd_mpm_cl_pair_keys(cd_mpm *m, size_t *n, char *err, size_t errlen)
{
    struct cd_mpm_cl *d = m->cl;
    cl_ulong count = 0;
    LAUNCH_WITH(K_PAIR_KEYS, 1, arg(d, K_PAIR_KEYS, a_++, sizeof(cl_mem), NULL));
    if (read_buf(d, d->count, CD_MPM_COUNT_KEYS * sizeof(cl_ulong), sizeof count, &count,
                 "reading the contact pairs' count"))
        goto failed;
    if (cd_mpm_pair_keys_room(m, count, err, errlen)) return -1;
    if (count > d->cap_keys) {
        if (d->keys) clReleaseMemObject(d->keys);
        d->cap_keys = count + 64;
        if (!(d->keys = cd_cl_buffer(&d->cl, d->cap_keys * sizeof(cd_long), "allocating the contact pairs' keys")))
            goto failed;
    }
    LAUNCH_WITH(K_PAIR_KEYS, 1, A_MEM(K_PAIR_KEYS, d->keys));
    if (read_buf(d, d->keys, 0, count * sizeof(cd_long), m->pair_keys, "reading the contact pairs' keys")) goto failed;
    *n = count;
    return 0;
failed:
    cd_cl_report(&d->cl, err, errlen);
    return -1;
}

int cd_mpm_cl_open(cd_mpm *m, const char *device, char *err, size_t errlen)
{
    struct cd_mpm_cl *d = calloc(1, sizeof *d);
    if (!d) {
        snprintf(err, errlen, "out of memory for the OpenCL backend");
        return -1;
    }
    m->cl = d;
    if (cd_cl_open(&d->cl, device, err, errlen)) {
        cd_mpm_cl_close(m);
        return -1;
    }
    for (int k = 0; k < K_COUNT; k++) {
        cl_int rc;
        d->k[k] = clCreateKernel(d->cl.program, kernel_table[k].name, &rc);
        if (rc != CL_SUCCESS) {
            snprintf(err, errlen, "OpenCL: kernel %s missing from the program (%s)", kernel_table[k].name,
                     cd_cl_error_name(rc));
            cd_mpm_cl_close(m);
            return -1;
        }
        size_t wg = 0;
        if (clGetKernelWorkGroupInfo(d->k[k], d->cl.device, CL_KERNEL_WORK_GROUP_SIZE, sizeof wg, &wg, NULL) ==
                CL_SUCCESS &&
            wg > 0 && wg < d->cl.local)
            d->cl.local = wg; /* a work-group size every kernel accepts */
    }
    return 0;
}

void cd_mpm_cl_close(cd_mpm *m)
{
    struct cd_mpm_cl *d = m->cl;
    if (!d) return;
    for (int f = 0; f < N_COLS; f++)
        if (d->col[f]) clReleaseMemObject(d->col[f]);
    cl_mem scratch[] = {d->flags, d->reals, d->count, d->over, d->keys, d->row_n, d->rows, d->blocks};
    for (size_t i = 0; i < sizeof scratch / sizeof scratch[0]; i++)
        if (scratch[i]) clReleaseMemObject(scratch[i]);
    for (int k = 0; k < K_COUNT; k++)
        if (d->k[k]) clReleaseKernel(d->k[k]);
    cd_cl_close(&d->cl);
    free(d);
    m->cl = NULL;
    m->loop_on = 0;
}

const char *cd_mpm_cl_device(const cd_mpm *m) { return m->cl ? m->cl->cl.desc : "host"; }

#else /* a build without OpenCL: m->cl stays NULL, so only the refusal is reachable */

int cd_mpm_cl_open(cd_mpm *m, const char *device, char *err, size_t errlen)
{
    (void)m;
    (void)device;
    snprintf(err, errlen, "--backend opencl: expected omp (this build has: omp; configure with -DCAPDEM_OPENCL=ON)");
    return -1;
}
int cd_mpm_cl_step(cd_mpm *m, char *err, size_t errlen)
{
    (void)m;
    snprintf(err, errlen, "no OpenCL backend in this build");
    return -1;
}
void cd_mpm_cl_sync(cd_mpm *m) { (void)m; }
int cd_mpm_cl_settle(cd_mpm *m, char *err, size_t errlen)
{
    (void)m;
    (void)err;
    (void)errlen;
    return 0;
}
void cd_mpm_cl_close(cd_mpm *m) { (void)m; }
const char *cd_mpm_cl_device(const cd_mpm *m)
{
    (void)m;
    return "host";
}
int cd_mpm_cl_pair_keys(cd_mpm *m, size_t *n, char *err, size_t errlen)
{
    (void)m;
    *n = 0;
    snprintf(err, errlen, "no OpenCL backend in this build");
    return -1;
}
#endif
