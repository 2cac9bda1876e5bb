/* OpenCL backend: device buffers.  Every column of kernels/fields.def gets one
 * buffer, created once at start; only the pair columns grow (with
 * headroom) when the Verlet list outgrows them.  Uploads happen at start,
 * downloads at sync: between them the state lives on the device. */
#include <stddef.h>
#include <stdlib.h>
#include <string.h>
#include "backend/opencl/backend_cl.h"
#include "neighbor_items.h"
#include "observe_items.h"
#include "step_items.h"

/* Rows above need, so that a slowly growing list does not reallocate at
 * every rebuild (as the host list, neighbors.c: a 64th, cd_nb_room). */
static size_t with_headroom(size_t n) { return (size_t)cd_nb_room((cd_long)n); }

cl_mem cd_cl_buffer(cd_cl *cl, size_t bytes, const char *what)
{
    if (cl->status) return NULL;
    cl_int rc;
    cl_mem m = clCreateBuffer(cl->ctx, CL_MEM_READ_WRITE, bytes > 0 ? bytes : 16, NULL, &rc);
    if (cd_cl_check(cl, rc, what)) return NULL;
    return m;
}

static void release(cl_mem *m)
{
    if (*m) clReleaseMemObject(*m);
    *m = NULL;
}

cl_mem cd_cl_col(const cd_cl *cl, int f)
{
    if (f == CD_CL_F_pair_active) return cl->hist[cl->cur].active;
    if (f == CD_CL_F_pair_shear) return cl->hist[cl->cur].shear;
    return cl->col[f];
}

static int is_history(int f) { return f == CD_CL_F_pair_active || f == CD_CL_F_pair_shear; }

/* Rows of a column's group on the device. */
static size_t rows_of(const cd_cl *cl, const cd_state *s, const cd_field_info *f)
{
    return f->group == CD_GROUP_PAIR ? cl->cap_pairs : cd_state_rows(s, f->group);
}

int cd_cl_reserve_pairs(cd_cl *cl, size_t n, int which)
{
    size_t want = with_headroom(n);
    if (cl->cap_pairs < n) {
        for (int f = 0; f < CD_CL_N_FIELDS; f++) {
            if (cd_fields[f].group != CD_GROUP_PAIR || is_history(f)) continue;
            release(&cl->col[f]);
            cl->col[f] = cd_cl_buffer(cl, want * cd_fields[f].elem_size, "allocating the pair columns");
        }
        cl->cap_pairs = want;
        cl->cols_dirty = 1;
    }
    cd_cl_pairset *h = &cl->hist[which];
    if (h->cap < n) {
        release(&h->active);
        release(&h->shear);
        release(&h->keys);
        h->active = cd_cl_buffer(cl, want * sizeof(cd_flag), "allocating the contact history");
        h->shear = cd_cl_buffer(cl, want * sizeof(cd_vec3), "allocating the contact history");
        h->keys = cd_cl_buffer(cl, want * sizeof(cd_ulong), "allocating the pair keys");
        h->cap = want;
        if (which == cl->cur) cl->cols_dirty = 1;
    }
    if (cl->gather_cap < 2 * n) {
        release(&cl->gather_rows);
        cl->gather_rows = cd_cl_buffer(cl, 2 * want * sizeof(cd_pair_id), "allocating the gather lists");
        cl->gather_cap = 2 * want;
    }
    return cl->status ? -1 : 0;
}

int cd_cl_bind_force(cd_cl *cl, cl_mem force, cl_mem torque)
{
    for (int k = 0; k < CD_CLK_COUNT; k++) {
        if (!cd_cl_kernel_takes_cols((enum cd_cl_kernel)k)) continue;
        if (cd_cl_arg(cl, (enum cd_cl_kernel)k, CD_CL_N_FIELDS + 4, sizeof force, &force) ||
            cd_cl_arg(cl, (enum cd_cl_kernel)k, CD_CL_N_FIELDS + 5, sizeof torque, &torque))
            return -1;
    }
    return 0;
}

void cd_cl_force_release(cd_cl *cl)
{
    if (!cl->force && !cl->torque) return;
    release(&cl->force);
    release(&cl->torque);
    cd_cl_bind_force(cl, NULL, NULL);
}

int cd_cl_bind_cols(cd_cl *cl)
{
    for (int k = 0; k < CD_CLK_COUNT; k++) {
        if (!cd_cl_kernel_takes_cols((enum cd_cl_kernel)k)) continue;
        for (int f = 0; f < CD_CL_N_FIELDS; f++) {
            cl_mem m = cd_cl_col(cl, f);
            if (cd_cl_arg(cl, (enum cd_cl_kernel)k, (cl_uint)f, sizeof m, &m)) return -1;
        }
        /* a null prim_arm where every primitive has an arm (kernels/cols.h) */
        cl_mem arm_of = cl->arms_all ? NULL : cl->prim_arm;
        if (cd_cl_arg(cl, (enum cd_cl_kernel)k, CD_CL_N_FIELDS, sizeof arm_of, &arm_of) ||
            cd_cl_arg(cl, (enum cd_cl_kernel)k, CD_CL_N_FIELDS + 1, sizeof cl->arm, &cl->arm) ||
            cd_cl_arg(cl, (enum cd_cl_kernel)k, CD_CL_N_FIELDS + 2, sizeof cl->inertia, &cl->inertia) ||
            cd_cl_arg(cl, (enum cd_cl_kernel)k, CD_CL_N_FIELDS + 3, sizeof cl->inertia_iso, &cl->inertia_iso))
            return -1;
    }
    if (cd_cl_bind_force(cl, cl->force, cl->torque)) return -1;
    cl->cols_dirty = 0;
    return 0;
}

int cd_cl_fill_int(cd_cl *cl, cl_mem buf, cd_int value, size_t first, size_t count)
{
    if (cl->status) return -1;
    if (count == 0) return 0;
    cl_int rc = clEnqueueFillBuffer(cl->queue, buf, &value, sizeof value, first * sizeof value, count * sizeof value, 0,
                                    NULL, NULL);
    return cd_cl_check(cl, rc, "clearing a buffer") ? -1 : 0;
}

/* Arguments of a scan kernel: pairs of (buffer, index of its first entry),
 * the entries' count after the first pair. */
static void scan_args(cd_cl *cl, enum cd_cl_kernel k, cl_mem a, cd_int a_at, cd_int n, cl_mem b, cd_int b_at)
{
    cd_cl_arg(cl, k, 0, sizeof a, &a);
    cd_cl_arg(cl, k, 1, sizeof a_at, &a_at);
    cd_cl_arg(cl, k, 2, sizeof n, &n);
    cd_cl_arg(cl, k, 3, sizeof b, &b);
    cd_cl_arg(cl, k, 4, sizeof b_at, &b_at);
}

int cd_cl_scan(cd_cl *cl, cl_mem in, size_t n, cl_mem out)
{
    /* levels above the input in block_sum (cd_scan_scratch entries), as
     * src/backend/omp/neighbors.c's cd_nb_scan lays them out */
    cd_int at[8], len[8], L = 0, next = 0;
    len[0] = (cd_int)n;
    at[0] = 0;
    while (len[L] > CD_SCAN_CHUNK) {
        cd_int m = (len[L] + CD_SCAN_CHUNK - 1) / CD_SCAN_CHUNK;
        scan_args(cl, CD_CLK_SCAN_BLOCKS, L ? cl->block_sum : in, at[L], len[L], cl->block_sum, next);
        cd_cl_run(cl, CD_CLK_SCAN_BLOCKS, (size_t)m);
        L++;
        at[L] = next;
        len[L] = m;
        next += m + 1;
    }
    scan_args(cl, CD_CLK_SCAN_TOP, L ? cl->block_sum : in, at[L], len[L], L ? cl->block_sum : out, at[L]);
    cd_cl_run(cl, CD_CLK_SCAN_TOP, 1);
    for (int l = L - 1; l >= 0; l--) {
        cl_mem src = l ? cl->block_sum : in, dst = l ? cl->block_sum : out;
        scan_args(cl, CD_CLK_SCAN_FILL, src, at[l], len[l], cl->block_sum, at[l + 1]);
        cd_cl_arg(cl, CD_CLK_SCAN_FILL, 5, sizeof dst, &dst);
        cd_cl_arg(cl, CD_CLK_SCAN_FILL, 6, sizeof at[l], &at[l]);
        cd_cl_run(cl, CD_CLK_SCAN_FILL, (size_t)len[l + 1]);
    }
    return cl->status ? -1 : 0;
}

int cd_cl_reserve_wall_rows(cd_cl *cl, size_t n)
{
    if (n <= cl->cap_wall_rows && cl->wall_rows) return cl->status ? -1 : 0;
    size_t want = with_headroom(n);
    release(&cl->wall_rows);
    release(&cl->wall_out);
    cl->wall_rows = cd_cl_buffer(cl, want * sizeof(cd_int), "allocating the wall lists");
    cl->wall_out = cd_cl_buffer(cl, want * sizeof(cd_wall_entry), "allocating the wall lists");
    cl->cap_wall_rows = want;
    return cl->status ? -1 : 0;
}

void cd_cl_release_old_wall_rows(cd_cl *cl)
{
    release(&cl->old_wall_rows);
    release(&cl->old_wall_out);
    cl->cap_old_wall_rows = 0;
}

void cd_cl_keep_wall_rows(cd_cl *cl)
{
    cl_mem rows = cl->wall_rows, ent = cl->wall_out;
    size_t cap = cl->cap_wall_rows;
    cl->wall_rows = cl->old_wall_rows;
    cl->wall_out = cl->old_wall_out;
    cl->cap_wall_rows = cl->cap_old_wall_rows;
    cl->old_wall_rows = rows;
    cl->old_wall_out = ent;
    cl->cap_old_wall_rows = cap;
    cl->n_old_wall_rows = cl->n_wall_rows;
    cl->n_wall_rows = 0;
}

int cd_cl_buffers_create(cd_cl *cl, cd_sim *sim)
{
    const cd_state *s = &sim->s;
    size_t N = s->n_particles, P = s->n_prims, W = s->n_walls;
    cl->cap_pairs = 0;
    cl->cur = 0;
    if (cd_cl_reserve_pairs(cl, s->n_pairs > 0 ? s->n_pairs : 1, 0)) return -1;
    for (int f = 0; f < CD_CL_N_FIELDS; f++) {
        if (cd_fields[f].group == CD_GROUP_PAIR) continue;
        cl->col[f] = cd_cl_buffer(cl, rows_of(cl, s, &cd_fields[f]) * cd_fields[f].elem_size, "allocating the state");
    }
    cl->arms_all = cd_state_arms_all(s);
    cl->prim_arm = cd_cl_buffer(cl, (cl->arms_all ? 1 : P + 1) * sizeof(cd_int), "allocating the state");
    cl->arm = cd_cl_buffer(cl, (s->n_arms + 1) * sizeof(cd_arm), "allocating the state");
    cl->inertia = s->step_inertia ? cd_cl_buffer(cl, (N + 1) * sizeof(cd_vec3), "allocating the state") : NULL;
    cl->inertia_iso = s->inertia_iso ? cd_cl_buffer(cl, (N + 1) * sizeof(cd_real), "allocating the state") : NULL;
    /* the host's force and torque for the first advance (or the whole run
     * on an MPI rank; kernels/cols.h): released after that advance */
    cl->force = cd_cl_buffer(cl, (N + 1) * sizeof(cd_vec3), "allocating the state");
    cl->torque = cd_cl_buffer(cl, (N + 1) * sizeof(cd_vec3), "allocating the state");
    cl->walls = cd_cl_buffer(cl, (W > 0 ? W : 1) * sizeof(cd_wall), "allocating the walls");
    cl->flags = cd_cl_buffer(cl, 3 * sizeof(cd_int), "allocating the flags");
    cl->scratch_real = cd_cl_buffer(cl, sizeof(cd_real), "allocating a result");
    cl->load_part = cd_cl_buffer(cl, (P / CD_LOAD_CHUNK + 1) * sizeof(cd_real), "allocating the wall-load sums");
    cl->obs_touch = cd_cl_buffer(cl, (N + 1) * sizeof(cd_int), "allocating the observables' sums");
    cl->obs_total = cd_cl_buffer(cl, CD_OBS_SLOTS * sizeof(cd_real), "allocating the observables' sums");
    cl->obs_cap_blocks = 0; /* obs_part: at the first sum (cl_observe) */
    cl->partial =
        cd_cl_buffer(cl, 7 * (size_t)cd_nb_box_scratch((cd_long)N) * sizeof(cd_real), "allocating the neighbour list");
    cl->grid = cd_cl_buffer(cl, sizeof(cd_grid), "allocating the neighbour list");
    /* The grid has at most 8 N + 64 <= 8 P + 64 cells (cd_grid_make), so
     * the cell arrays never grow and the host never needs the cell count. */
    cl->cell_cap = 8 * P + 64;
    cl->part_cell = cd_cl_buffer(cl, N * sizeof(cd_int), "allocating the cell lists");
    cl->cell_parts = cd_cl_buffer(cl, N * sizeof(cd_int), "allocating the cell lists");
    cl->part_bound = cd_cl_buffer(cl, N * sizeof(cd_real), "allocating the cell lists");
    cl->cell_count = cd_cl_buffer(cl, cl->cell_cap * sizeof(cd_int), "allocating the cell lists");
    cl->cell_cursor = cd_cl_buffer(cl, cl->cell_cap * sizeof(cd_int), "allocating the cell lists");
    cl->cell_start = cd_cl_buffer(cl, (cl->cell_cap + 1) * sizeof(cd_int), "allocating the cell lists");
    cl->pair_count = cd_cl_buffer(cl, P * sizeof(cd_int), "allocating the neighbour list");
    cl->pair_offset = cd_cl_buffer(cl, (P + 1) * sizeof(cd_int), "allocating the neighbour list");
    /* 32 candidates per primitive cover a dense packing of hexapods with a
     * skin of 0.1 d; the slots double whenever one overflows.
     * CAPDEM_OPENCL_SLOTS sets the first size (test hook for the overflow
     * path). */
    const char *slots = getenv("CAPDEM_OPENCL_SLOTS");
    cl->slot = slots && atoi(slots) > 0 ? atoi(slots) : 32;
    cl->cand = cd_cl_buffer(cl, P * (size_t)cl->slot * sizeof(cd_prim_id), "allocating the neighbour list");
    /* the longest scan: the cells */
    cl->block_sum_cap = (size_t)cd_scan_scratch((cd_long)cl->cell_cap);
    cl->block_sum = cd_cl_buffer(cl, cl->block_sum_cap * sizeof(cd_int), "allocating the scan");
    cl->gather_count = cd_cl_buffer(cl, N * sizeof(cd_int), "allocating the gather lists");
    cl->gather_cursor = cd_cl_buffer(cl, N * sizeof(cd_int), "allocating the gather lists");
    cl->gather_start = cd_cl_buffer(cl, (N + 1) * sizeof(cd_int), "allocating the gather lists");
    cl->wall_count = cd_cl_buffer(cl, N * sizeof(cd_int), "allocating the wall lists");
    cl->wall_start = cd_cl_buffer(cl, (N + 1) * sizeof(cd_int), "allocating the wall lists");
    cl->cap_wall_rows = 0; /* wall_rows, wall_out: sized by the builds */
    if (cl->status || cd_cl_reserve_wall_rows(cl, 1)) return -1;
    cd_cl_keep_wall_rows(cl); /* the same for the old ones */
    if (cd_cl_reserve_wall_rows(cl, 1)) return -1;
    return cd_cl_bind_cols(cl);
}

/* Enqueues a copy of bytes from src into buf; src must stay as it is until
 * the queue is finished (cd_cl_buffers_upload finishes it once at its end:
 * one wait for every column instead of one each, which an MPI rank pays at
 * every migration, docs/mpi.md "OpenCL ranks"). */
static int write(cd_cl *cl, cl_mem buf, size_t bytes, const void *src, const char *what)
{
    if (cl->status) return -1;
    if (bytes == 0) return 0;
    cl_int rc = clEnqueueWriteBuffer(cl->queue, buf, CL_FALSE, 0, bytes, src, 0, NULL, NULL);
    return cd_cl_check(cl, rc, what) ? -1 : 0;
}

int cd_cl_buffers_upload(cd_cl *cl, cd_sim *sim)
{
    cd_state *s = &sim->s;
    for (int f = 0; f < CD_CL_N_FIELDS; f++) {
        size_t rows = cd_state_rows(s, cd_fields[f].group); /* pairs: n_pairs rows */
        void *host = *cd_field_ptr(s, &cd_fields[f]);
        write(cl, cd_cl_col(cl, f), rows * cd_fields[f].elem_size, host, "uploading the state");
    }
    if (!cl->arms_all) write(cl, cl->prim_arm, s->n_prims * sizeof(cd_int), s->prim_arm, "uploading the state");
    write(cl, cl->arm, s->n_arms * sizeof(cd_arm), s->arm, "uploading the state");
    if (cl->inertia) write(cl, cl->inertia, s->n_particles * sizeof(cd_vec3), s->step_inertia, "uploading the state");
    if (cl->inertia_iso)
        write(cl, cl->inertia_iso, s->n_particles * sizeof(cd_real), s->inertia_iso, "uploading the state");
    if (cl->force) write(cl, cl->force, s->n_particles * sizeof(cd_vec3), s->force, "uploading the state");
    if (cl->torque) write(cl, cl->torque, s->n_particles * sizeof(cd_vec3), s->torque, "uploading the state");
    write(cl, cl->walls, s->n_walls * sizeof(cd_wall), s->walls, "uploading the walls");
    cd_int flags[3] = {0, -1, 0};
    write(cl, cl->flags, sizeof flags, flags, "uploading the flags");
    cl->n_pairs = s->n_pairs;
    /* Keys of the rows handed over (sorted, as every list capdem writes),
     * so that the first rebuild finds their history. */
    cd_int n = (cd_int)cl->n_pairs;
    cl_mem keys = cl->hist[cl->cur].keys;
    cd_cl_arg(cl, CD_CLK_PAIR_KEYS, CD_CL_N_COLS, sizeof n, &n);
    cd_cl_arg(cl, CD_CLK_PAIR_KEYS, CD_CL_N_COLS + 1, sizeof keys, &keys);
    cd_cl_run(cl, CD_CLK_PAIR_KEYS, cl->n_pairs);
    /* The wall rows in contact as the candidates of a build before, so
     * that the first rebuild carries their history over. */
    size_t nw = cd_state_wall_entries(s, NULL, NULL);
    cd_int *rows = malloc((nw + 1) * sizeof *rows);
    cd_wall_entry *ent = malloc((nw + 1) * sizeof *ent);
    if (!rows || !ent) cd_cl_check(cl, CL_OUT_OF_HOST_MEMORY, "uploading the wall contacts");
    if (!cl->status && !cd_cl_reserve_wall_rows(cl, nw)) {
        cd_state_wall_entries(s, rows, ent);
        write(cl, cl->wall_rows, nw * sizeof *rows, rows, "uploading the wall contacts");
        write(cl, cl->wall_out, nw * sizeof *ent, ent, "uploading the wall contacts");
        cl->n_wall_rows = (cd_int)nw;
    }
    cl_int finished = clFinish(cl->queue); /* (before rows, ent and flags go, whatever failed) */
    cd_cl_check(cl, finished, "uploading the state");
    free(rows);
    free(ent);
    return cl->status ? -1 : 0;
}

/* Is the column at offset (in cd_state) among the n at offsets only
 * (NULL: every column)? */
static int wanted_at(size_t offset, const size_t *only, size_t n)
{
    if (!only) return 1;
    for (size_t k = 0; k < n; k++)
        if (offset == only[k]) return 1;
    return 0;
}

/* Is column f among them? */
static int wanted(int f, const size_t *only, size_t n) { return wanted_at(cd_fields[f].offset, only, n); }

int cd_cl_buffers_download(cd_cl *cl, cd_sim *sim) { return cd_cl_buffers_download_cols(cl, sim, NULL, 0); }

/* Where the step holds no force and torque (one process, after the first
 * advance) and the rows hold a force evaluation: the two summed from the
 * rows into the host's columns by the gather kernel (mode 0, cd_item_gather)
 * in two buffers made for it, the sums the next call's first advance makes
 * (kernels/cols.h); the OpenCL backend keeps the particles in user order. */
static void force_summed_to_host(cd_cl *cl, cd_sim *sim)
{
    cd_state *s = &sim->s;
    size_t bytes = s->n_particles * sizeof(cd_vec3);
    if (cl->force || !cl->wall_out_valid || !bytes || cl->status) return;
    cl_mem f = cd_cl_buffer(cl, bytes, "allocating the force sums"),
           t = cd_cl_buffer(cl, bytes, "allocating the force sums");
    cd_int mode = 0; /* (every call of forces sets the mode anew) */
    if (!cl->status && !cd_cl_bind_force(cl, f, t)) {
        cd_cl_arg(cl, CD_CLK_GATHER_KICK, CD_CL_N_COLS + 6, sizeof mode, &mode);
        cd_cl_run(cl, CD_CLK_GATHER_KICK, s->n_particles);
        if (!cl->status)
            cd_cl_check(cl, clEnqueueReadBuffer(cl->queue, f, CL_FALSE, 0, bytes, s->force, 0, NULL, NULL),
                        "downloading the force");
        if (!cl->status)
            cd_cl_check(cl, clEnqueueReadBuffer(cl->queue, t, CL_TRUE, 0, bytes, s->torque, 0, NULL, NULL),
                        "downloading the torque");
    }
    cd_cl_bind_force(cl, NULL, NULL);
    release(&f);
    release(&t);
}

int cd_cl_buffers_download_cols(cd_cl *cl, cd_sim *sim, const size_t *only, size_t n_only)
{
    cd_state *s = &sim->s;
    if (cl->status) return -1;
    if (cd_state_reserve_pairs(s, cl->n_pairs)) {
        cd_cl_check(cl, CL_OUT_OF_HOST_MEMORY, "making room for the contacts on the host");
        return -1;
    }
    s->n_pairs = cl->n_pairs;
    for (int f = 0; f < CD_CL_N_FIELDS && !cl->status; f++) {
        size_t bytes = cd_state_rows(s, cd_fields[f].group) * cd_fields[f].elem_size;
        if (bytes == 0 || !wanted(f, only, n_only)) continue;
        void *host = *cd_field_ptr(s, &cd_fields[f]);
        cl_int rc = clEnqueueReadBuffer(cl->queue, cd_cl_col(cl, f), CL_FALSE, 0, bytes, host, 0, NULL, NULL);
        cd_cl_check(cl, rc, "downloading the state");
    }
    /* the force and torque: where the step holds them, theirs; else
     * summed from the rows (a whole download only) */
    size_t fb = s->n_particles * sizeof(cd_vec3);
    if (!cl->status && cl->force && fb && wanted_at(offsetof(cd_state, force), only, n_only)) {
        cd_cl_check(cl, clEnqueueReadBuffer(cl->queue, cl->force, CL_FALSE, 0, fb, s->force, 0, NULL, NULL),
                    "downloading the state");
        if (!cl->status)
            cd_cl_check(cl, clEnqueueReadBuffer(cl->queue, cl->torque, CL_FALSE, 0, fb, s->torque, 0, NULL, NULL),
                        "downloading the state");
    }
    if (!only) force_summed_to_host(cl, sim);
    if (!cl->status && s->n_arms) /* the arms, expanded into the host's rows below */
        cd_cl_check(
            cl, clEnqueueReadBuffer(cl->queue, cl->arm, CL_FALSE, 0, s->n_arms * sizeof(cd_arm), s->arm, 0, NULL, NULL),
            "downloading the state");
    /* Not the walls: the host's copy is current after every call of step
     * and may since have been changed by a protocol (docs/opencl.md). */
    if (!cl->status) cd_cl_check(cl, clFinish(cl->queue), "downloading the state");
    if (cl->status) return -1;
    cd_state_arms_expand(s, s->prim_arm, s->arm);
    /* the wall contacts the step keeps per candidate, into the host's rows */
    size_t n = (size_t)cl->n_wall_rows;
    if (!cl->wall_out_pending || !s->n_walls) return 0;
    cd_int *rows = malloc((n + 1) * sizeof *rows);
    cd_wall_entry *out = malloc((n + 1) * sizeof *out);
    if (!rows || !out) cd_cl_check(cl, CL_OUT_OF_HOST_MEMORY, "downloading the wall contacts");
    if (!cl->status && n) {
        cd_cl_check(cl,
                    clEnqueueReadBuffer(cl->queue, cl->wall_rows, CL_TRUE, 0, n * sizeof *rows, rows, 0, NULL, NULL),
                    "downloading the wall contacts");
        if (!cl->status)
            cd_cl_check(cl,
                        clEnqueueReadBuffer(cl->queue, cl->wall_out, CL_TRUE, 0, n * sizeof *out, out, 0, NULL, NULL),
                        "downloading the wall contacts");
    }
    if (!cl->status) {
        cd_state_expand_wall_entries(s, rows, out, n);
        cl->wall_out_pending = 0;
    }
    free(rows);
    free(out);
    return cl->status ? -1 : 0;
}

void cd_cl_buffers_release(cd_cl *cl)
{
    for (int f = 0; f < CD_CL_N_FIELDS; f++) release(&cl->col[f]);
    release(&cl->prim_arm);
    release(&cl->arm);
    release(&cl->inertia);
    release(&cl->inertia_iso);
    release(&cl->force);
    release(&cl->torque);
    for (int h = 0; h < 2; h++) {
        release(&cl->hist[h].active);
        release(&cl->hist[h].shear);
        release(&cl->hist[h].keys);
        cl->hist[h].cap = 0;
    }
    cl_mem *other[] = {
        &cl->walls,          &cl->flags,        &cl->scratch_real,  &cl->load_part,     &cl->partial,
        &cl->grid,           &cl->part_cell,    &cl->part_bound,    &cl->cell_count,    &cl->cell_start,
        &cl->cell_cursor,    &cl->cell_parts,   &cl->pair_count,    &cl->pair_offset,   &cl->block_sum,
        &cl->cand,           &cl->gather_count, &cl->gather_start,  &cl->gather_cursor, &cl->gather_rows,
        &cl->wall_count,     &cl->wall_start,   &cl->wall_rows,     &cl->obs_touch,     &cl->obs_part,
        &cl->obs_total,      &cl->wall_out,     &cl->old_wall_rows, &cl->old_wall_out,  &cl->halo_send_list,
        &cl->halo_recv_list, &cl->halo_send,    &cl->halo_recv,     &cl->wall_fn};
    for (size_t i = 0; i < sizeof other / sizeof other[0]; i++) release(other[i]);
    release(&cl->pair_visit);
    release(&cl->visit_starts);
    cl->cap_pairs = cl->gather_cap = cl->obs_cap_blocks = 0;
    cl->cap_visit = cl->cap_visit_starts = cl->n_visit = cl->block_sum_cap = 0;
    cl->cap_wall_rows = cl->cap_old_wall_rows = 0;
    cl->halo_ns = cl->halo_nr = 0;
}
