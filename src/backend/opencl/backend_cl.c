/* The OpenCL backend (docs/opencl.md): the operations of backend.h.  One
 * step enqueues the kernels of kernels/cl/step.cl in the order of
 * src/backend/omp/step_omp.c (three a step: pair rows, wall candidates, the
 * gather with the kick and the next advance); the state stays on the device,
 * and the host reads one int per step (the skin flag), the pair count at a
 * rebuild, and the walls and a blow-up flag once per call of step. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "backend/opencl/backend_cl.h"
#include "backend/opencl/backend_cl_mpi.h"
#include "observe_items.h"
#include "broadphase.h"
#include "step_items.h"

#define F CD_CL_N_COLS /* first kernel argument after the columns */

/* Arguments that change only with sim->p or the buffers: set at every call
 * of step (sim->p may change between calls, e.g. gravity in capdem-bench). */
static void set_step_args(cd_cl *cl, const cd_sim *sim)
{
    const cd_state *s = &sim->s;
    const cd_step_params *p = &sim->p;
    cd_int N = (cd_int)s->n_particles, W = (cd_int)s->n_walls;
    cd_real dt = p->dt, limit2 = cd_bp_skin_limit2(sim->nb.skin);
    if (cl->cols_dirty) cd_cl_bind_cols(cl);
    cd_cl_arg(cl, CD_CLK_ADVANCE, F, sizeof cl->walls, &cl->walls);
    cd_cl_arg(cl, CD_CLK_ADVANCE, F + 1, sizeof W, &W);
    cd_cl_arg(cl, CD_CLK_ADVANCE, F + 2, sizeof N, &N);
    cd_cl_arg(cl, CD_CLK_ADVANCE, F + 3, sizeof dt, &dt);
    cd_cl_arg(cl, CD_CLK_ADVANCE, F + 4, sizeof limit2, &limit2);
    cd_cl_arg(cl, CD_CLK_ADVANCE, F + 5, sizeof cl->flags, &cl->flags);
    /* the gather's, for the force and torque summed from the rows
     * (cd_item_advance; gather_rows and wall_out: set_list_args) */
    cd_cl_arg(cl, CD_CLK_ADVANCE, F + 6, sizeof cl->gather_start, &cl->gather_start);
    cd_cl_arg(cl, CD_CLK_ADVANCE, F + 8, sizeof cl->wall_start, &cl->wall_start);
    cd_cl_arg(cl, CD_CLK_ADVANCE, F + 10, sizeof p->gravity, &p->gravity);
    cd_cl_arg(cl, CD_CLK_ADVANCE, F + 11, sizeof p->dimension, &p->dimension);
    cd_cl_arg(cl, CD_CLK_ADVANCE, F + 12, sizeof p->fixed_spheres, &p->fixed_spheres);
    cd_cl_arg(cl, CD_CLK_PAIR_FORCES, F + 1, sizeof p->law, &p->law);
    cd_cl_arg(cl, CD_CLK_PAIR_FORCES, F + 2, sizeof dt, &dt);
    cd_cl_arg(cl, CD_CLK_PAIR_FORCES, F + 3, sizeof p->sin_parallel, &p->sin_parallel);
    cd_cl_arg(cl, CD_CLK_PAIR_FORCES, F + 4, sizeof p->parallel_blend, &p->parallel_blend);
    cd_cl_arg(cl, CD_CLK_WALL_FORCES, F + 2, sizeof cl->walls, &cl->walls);
    cd_cl_arg(cl, CD_CLK_WALL_FORCES, F + 3, sizeof W, &W);
    cd_cl_arg(cl, CD_CLK_WALL_FORCES, F + 4, sizeof p->wall_law, &p->wall_law);
    cd_cl_arg(cl, CD_CLK_WALL_FORCES, F + 5, sizeof dt, &dt);
    cd_cl_arg(cl, CD_CLK_WALL_FORCES, F + 6, sizeof p->sin_parallel, &p->sin_parallel);
    cd_cl_arg(cl, CD_CLK_WALL_FORCES, F + 7, sizeof p->parallel_blend, &p->parallel_blend);
    cd_cl_arg(cl, CD_CLK_GATHER_KICK, F, sizeof N, &N);
    cd_cl_arg(cl, CD_CLK_GATHER_KICK, F + 1, sizeof cl->gather_start, &cl->gather_start);
    cd_cl_arg(cl, CD_CLK_GATHER_KICK, F + 3, sizeof cl->wall_start, &cl->wall_start);
    cd_cl_arg(cl, CD_CLK_GATHER_KICK, F + 4, sizeof p->gravity, &p->gravity);
    cd_cl_arg(cl, CD_CLK_GATHER_KICK, F + 5, sizeof p->dimension, &p->dimension);
    cd_cl_arg(cl, CD_CLK_GATHER_KICK, F + 7, sizeof dt, &dt);
    cd_cl_arg(cl, CD_CLK_GATHER_KICK, F + 9, sizeof limit2, &limit2);
    cd_cl_arg(cl, CD_CLK_GATHER_KICK, F + 10, sizeof cl->walls, &cl->walls);
    cd_cl_arg(cl, CD_CLK_GATHER_KICK, F + 11, sizeof W, &W);
    cd_cl_arg(cl, CD_CLK_GATHER_KICK, F + 12, sizeof cl->flags, &cl->flags);
    cd_cl_arg(cl, CD_CLK_GATHER_KICK, F + 13, sizeof p->fixed_spheres, &p->fixed_spheres);
    cd_cl_arg(cl, CD_CLK_CHECK_FINITE, F, sizeof N, &N);
    cd_cl_arg(cl, CD_CLK_CHECK_FINITE, F + 1, sizeof cl->flags, &cl->flags);
}

/* Arguments that change when the list is rebuilt. */
static void set_list_args(cd_cl *cl)
{
    cd_int n = (cd_int)cl->n_pairs;
    if (cl->cols_dirty) cd_cl_bind_cols(cl);
    cd_cl_arg(cl, CD_CLK_PAIR_FORCES, F, sizeof n, &n);
    /* a mixture: the rows kind by kind (pass 11); else null, the rows in order */
    cl_mem visit = cl->n_visit && cl->n_visit == cl->n_pairs ? cl->pair_visit : NULL;
    cd_cl_arg(cl, CD_CLK_PAIR_FORCES, F + 6, sizeof visit, &visit);
    cd_cl_arg(cl, CD_CLK_WALL_FORCES, F, sizeof cl->n_wall_rows, &cl->n_wall_rows);
    cd_cl_arg(cl, CD_CLK_GATHER_KICK, F + 2, sizeof cl->gather_rows, &cl->gather_rows);
    /* the wall candidates' lists, sized by the last build */
    cd_cl_arg(cl, CD_CLK_WALL_FORCES, F + 1, sizeof cl->wall_rows, &cl->wall_rows);
    cd_cl_arg(cl, CD_CLK_WALL_FORCES, F + 8, sizeof cl->wall_out, &cl->wall_out);
    cd_cl_arg(cl, CD_CLK_GATHER_KICK, F + 8, sizeof cl->wall_out, &cl->wall_out);
    cd_cl_arg(cl, CD_CLK_ADVANCE, F + 7, sizeof cl->gather_rows, &cl->gather_rows);
    cd_cl_arg(cl, CD_CLK_ADVANCE, F + 9, sizeof cl->wall_out, &cl->wall_out);
}

/* Rebuild of the list, then steps 5-8 (forces, gather, second kick) and
 * the next step's 1-4, by mode (cd_cl_gather_kick): 0 the forces of a
 * start, 1 the last step of a call, 2 a step with the next one's advance.
 * The pair rows' F_n is written where a call ends (modes 0
 * and 1). */
static int forces(cd_cl *cl, cd_sim *sim, int rebuild, cd_int mode)
{
    const cd_state *s = &sim->s;
    cd_int outputs = mode != 2;
    if (rebuild) {
        if (cd_cl_neighbors_build(cl, sim)) return -1;
        set_list_args(cl);
    }
    cd_cl_arg(cl, CD_CLK_PAIR_FORCES, F + 5, sizeof outputs, &outputs);
    cd_cl_arg(cl, CD_CLK_GATHER_KICK, F + 6, sizeof mode, &mode);
    cd_cl_run(cl, CD_CLK_PAIR_FORCES, cl->n_pairs);
    if (cl->n_wall_rows) cd_cl_run(cl, CD_CLK_WALL_FORCES, (size_t)cl->n_wall_rows);
    cl->wall_out_valid = cl->wall_out_pending = 1;
    return cd_cl_run(cl, CD_CLK_GATHER_KICK, s->n_particles > s->n_walls ? s->n_particles : s->n_walls);
}

static void cl_stop(cd_sim *sim)
{
    cd_cl *cl = sim->backend_data;
    sim->nb.visit_get = NULL; /* the visiting order goes with the buffers */
    if (!cl) return;
    if (cl->queue) clFinish(cl->queue);
    cd_cl_buffers_release(cl);
    cd_cl_close(cl);
    free(cl);
    sim->backend_data = NULL;
}

static int fail(cd_sim *sim, char *err, size_t errlen)
{
    cd_cl_report(sim->backend_data, err, errlen);
    return -1;
}

static int cl_start(cd_sim *sim, int compute_forces, char *err, size_t errlen)
{
    if (sim->backend_data) cl_stop(sim);
    cd_cl *cl = calloc(1, sizeof *cl);
    if (!cl) {
        snprintf(err, errlen, "out of memory starting the OpenCL backend");
        return -1;
    }
    sim->backend_data = cl;
    snprintf(cl->desc, sizeof cl->desc, "OpenCL");
    if (cd_cl_open(cl, sim->device_request, err, errlen)) {
        cl_stop(sim);
        return -1;
    }
    /* As the omp backend: angular velocities and primitive ends from the
     * poses on the host, and a rebuild before the first forces. */
    if (cd_state_arms_derive(&sim->s)) {
        snprintf(err, errlen, "out of memory while setting up the primitives' arms");
        cl_stop(sim);
        return -1;
    }
    cd_sim_refresh(sim);
    if (cd_cl_buffers_create(cl, sim) || cd_cl_buffers_upload(cl, sim)) return fail(sim, err, errlen);
    set_step_args(cl, sim);
    set_list_args(cl);
    memcpy(cl->host_walls, sim->s.walls, sizeof cl->host_walls);
    if (compute_forces) forces(cl, sim, 1, 0);
    /* Not compute_forces: the forces of the checkpoint are kept and the
     * list is rebuilt at the first step (sim->nb.force_rebuild is set), as
     * on the omp backend.  Otherwise the new forces and contacts are copied
     * back once, so that the host state is current after start on every
     * backend (tests and tools read energies right after it). */
    if (compute_forces) cd_cl_buffers_download(cl, sim);
    if (!cl->status) cd_cl_check(cl, clFinish(cl->queue), "starting");
    return cl->status ? fail(sim, err, errlen) : 0;
}

int cd_cl_reload(cd_sim *sim, char *err, size_t errlen)
{
    cd_cl *cl = sim->backend_data;
    if (cd_state_arms_derive(&sim->s)) {
        snprintf(err, errlen, "out of memory while setting up the primitives' arms");
        return -1;
    }
    /* The walls as the device moved them this step (the host's columns
     * hold them as the last call of step ended). */
    cd_wall walls[CD_MAX_WALLS];
    size_t W = sim->s.n_walls;
    if (W && !cl->status)
        cd_cl_check(cl,
                    clEnqueueReadBuffer(cl->queue, cl->walls, CL_TRUE, 0, W * sizeof(cd_wall), walls, 0, NULL, NULL),
                    "reading the walls");
    if (!cl->status) cd_cl_buffers_release(cl);
    if (cl->status || cd_cl_buffers_create(cl, sim) || cd_cl_buffers_upload(cl, sim)) return fail(sim, err, errlen);
    if (W)
        cd_cl_check(cl,
                    clEnqueueWriteBuffer(cl->queue, cl->walls, CL_TRUE, 0, W * sizeof(cd_wall), walls, 0, NULL, NULL),
                    "uploading the walls");
    set_step_args(cl, sim);
    set_list_args(cl);
    /* the candidates are the host's wall rows in contact, which the build
     * that follows carries over (the forces of the last step are the
     * host's: no wall load reads the device before it) */
    cl->wall_out_valid = cl->wall_out_pending = 0;
    return cl->status ? fail(sim, err, errlen) : 0;
}

static int cl_sync(cd_sim *sim, char *err, size_t errlen)
{
    cd_cl *cl = sim->backend_data;
    if (!cl) return 0;
    return cd_cl_buffers_download(cl, sim) ? fail(sim, err, errlen) : 0;
}

static int cl_step(cd_sim *sim, long long n, char *err, size_t errlen)
{
    cd_cl *cl = sim->backend_data;
    cd_state *s = &sim->s;
    if (!cl) {
        snprintf(err, errlen, "the OpenCL backend was not started (cd_sim_start)");
        return -1;
    }
    if (n <= 0) return 0;
    /* The host's walls are current after every call (read back below); a
     * protocol may have changed their motion since. */
    if (s->n_walls)
        cd_cl_check(cl,
                    clEnqueueWriteBuffer(cl->queue, cl->walls, CL_FALSE, 0, s->n_walls * sizeof(cd_wall), s->walls, 0,
                                         NULL, NULL),
                    "uploading the walls");
    set_step_args(cl, sim);
    memcpy(cl->host_walls, s->walls, sizeof cl->host_walls);
    size_t items = s->n_particles > s->n_walls ? s->n_particles : s->n_walls;
    /* the first step's advance; the next ones run inside the gather
     * (mode 2 of cd_cl_gather_kick).  Its force and torque: the host's
     * after a start (cl->force, then released: one process holds none
     * after it), else summed from the rows (kernels/cols.h) */
    cd_cl_run(cl, CD_CLK_ADVANCE, items);
    if (!cd_sim_keeps_force(sim)) cd_cl_force_release(cl);
    for (long long it = 0; it < n && !cl->status; it++) {
        /* the walls move on the device; their host mirror (the same
         * arithmetic) tells whether one moved far enough for a rebuild */
        int rebuild = sim->nb.force_rebuild;
        for (size_t w = 0; w < s->n_walls; w++) {
            cl->host_walls[w] = cd_wall_advanced(cl->host_walls[w], sim->p.dt);
            rebuild |= cd_bp_wall_moved(cl->host_walls[w], sim->nb.walls_ref[w]) > CD_R(0.5) * sim->nb.skin;
        }
        if (!rebuild && !cl->status) {
            cd_int moved = 0; /* the one read per step */
            cd_cl_check(cl, clEnqueueReadBuffer(cl->queue, cl->flags, CL_TRUE, 0, sizeof moved, &moved, 0, NULL, NULL),
                        "reading the skin flag");
            rebuild = moved != 0;
        }
        /* an MPI run decides the rebuild with all ranks and migrates the
         * particles first (src/mpi/mpi_backend.c; cd_cl_reload) */
        if (sim->rebuild_hook && !cl->status && (rebuild = sim->rebuild_hook(sim, rebuild, err, errlen)) < 0) return -1;
        forces(cl, sim, rebuild, it + 1 == n ? 1 : 2);
        s->step++;
        s->time += sim->p.dt;
    }
    cd_int flags[2] = {0, -1};
    cd_cl_run(cl, CD_CLK_CHECK_FINITE, s->n_particles);
    if (s->n_walls && !cl->status)
        cd_cl_check(cl,
                    clEnqueueReadBuffer(cl->queue, cl->walls, CL_FALSE, 0, s->n_walls * sizeof(cd_wall), s->walls, 0,
                                        NULL, NULL),
                    "reading the walls");
    if (!cl->status)
        cd_cl_check(cl, clEnqueueReadBuffer(cl->queue, cl->flags, CL_TRUE, 0, sizeof flags, flags, 0, NULL, NULL),
                    "reading the state check");
    if (cl->status) return fail(sim, err, errlen);
    if (flags[1] >= 0) {
        /* blown up: the host check names the particle, step and time */
        if (cd_cl_buffers_download(cl, sim)) return fail(sim, err, errlen);
        return cd_sim_check_state(sim, err, errlen);
    }
    return 0;
}

static const char *cl_device(const cd_sim *sim)
{
    const cd_cl *cl = sim->backend_data;
    return cl ? cl->desc : "OpenCL (not started)";
}

/* Sum of wall w's normal forces, in the order of every backend (chunks of
 * CD_LOAD_CHUNK primitives in parallel, then the chunks in order), without
 * a full download: one double comes back. */
static int cl_wall_load(cd_sim *sim, int w, double *load, char *err, size_t errlen)
{
    cd_cl *cl = sim->backend_data;
    if (!cl) {
        snprintf(err, errlen, "the OpenCL backend was not started (cd_sim_start)");
        return -1;
    }
    if (!cl->wall_out_valid) { /* no forces since the start: the host columns are current */
        *load = cd_sim_wall_load_host(sim, w);
        return 0;
    }
    cd_int P = (cd_int)sim->s.n_prims, W = (cd_int)sim->s.n_walls, ww = w;
    cd_int nch = (P + CD_LOAD_CHUNK - 1) / CD_LOAD_CHUNK;
    cd_cl_arg(cl, CD_CLK_WALL_LOAD, F + 5, sizeof cl->wall_start, &cl->wall_start);
    cd_cl_arg(cl, CD_CLK_WALL_LOAD, F + 6, sizeof cl->wall_rows, &cl->wall_rows);
    cd_cl_arg(cl, CD_CLK_WALL_LOAD, F + 7, sizeof cl->wall_out, &cl->wall_out);
    cd_cl_arg(cl, CD_CLK_WALL_LOAD, F, sizeof P, &P);
    cd_cl_arg(cl, CD_CLK_WALL_LOAD, F + 1, sizeof W, &W);
    cd_cl_arg(cl, CD_CLK_WALL_LOAD, F + 2, sizeof ww, &ww);
    cd_cl_arg(cl, CD_CLK_WALL_LOAD, F + 3, sizeof cl->load_part, &cl->load_part);
    cd_cl_arg(cl, CD_CLK_WALL_LOAD, F + 4, sizeof nch, &nch);
    cd_cl_run(cl, CD_CLK_WALL_LOAD, (size_t)nch);
    cd_cl_arg(cl, CD_CLK_WALL_LOAD_SUM, 0, sizeof cl->load_part, &cl->load_part);
    cd_cl_arg(cl, CD_CLK_WALL_LOAD_SUM, 1, sizeof nch, &nch);
    cd_cl_arg(cl, CD_CLK_WALL_LOAD_SUM, 2, sizeof cl->scratch_real, &cl->scratch_real);
    cd_cl_run(cl, CD_CLK_WALL_LOAD_SUM, 1);
    cd_real v = 0;
    if (!cl->status)
        cd_cl_check(cl, clEnqueueReadBuffer(cl->queue, cl->scratch_real, CL_TRUE, 0, sizeof v, &v, 0, NULL, NULL),
                    "reading the wall load");
    if (cl->status) return fail(sim, err, errlen);
    *load = v;
    return 0;
}

/* The observables on the device (kernels/cl/observe.cl): CD_OBS_SLOTS
 * doubles come back instead of the state. */
static int cl_observe(cd_sim *sim, double *slots, char *err, size_t errlen)
{
    cd_cl *cl = sim->backend_data;
    if (!cl || !cl->wall_out_valid) { /* not started, or no forces since: the host columns are current */
        cd_observables_slots(sim, slots);
        return 0;
    }
    const cd_state *s = &sim->s;
    cd_long N = (cd_long)s->n_particles, K = (cd_long)cl->n_pairs, R = (cd_long)(s->n_prims * s->n_walls);
    cd_long P = (cd_long)s->n_prims;
    cd_long bp = (N + CD_OBS_BLOCK - 1) / CD_OBS_BLOCK, bk = cd_obs_pair_blocks(P);
    cd_long bw = (R + CD_OBS_BLOCK - 1) / CD_OBS_BLOCK, n_blocks = bp + bk + bw, first = 0;
    cd_int W = (cd_int)s->n_walls, n_pairs = (cd_int)K;
    size_t tree = (size_t)cd_obs_tree_blocks(n_blocks) + 1;
    if (tree > cl->obs_cap_blocks) {
        if (cl->obs_part) clReleaseMemObject(cl->obs_part);
        cl->obs_cap_blocks = tree + tree / 4;
        cl->obs_part =
            cd_cl_buffer(cl, cl->obs_cap_blocks * CD_OBS_SLOTS * sizeof(cd_real), "allocating the observables' sums");
    }
    cd_cl_fill_int(cl, cl->obs_touch, 0, 0, (size_t)N);
    cd_cl_arg(cl, CD_CLK_OBS_TOUCH_PAIRS, F, sizeof n_pairs, &n_pairs);
    cd_cl_arg(cl, CD_CLK_OBS_TOUCH_PAIRS, F + 1, sizeof cl->obs_touch, &cl->obs_touch);
    cd_cl_run(cl, CD_CLK_OBS_TOUCH_PAIRS, (size_t)K);
    cd_long n_cand = W ? cl->n_wall_rows : 0;
    cd_cl_arg(cl, CD_CLK_OBS_TOUCH_WALLS, F, sizeof n_cand, &n_cand);
    cd_cl_arg(cl, CD_CLK_OBS_TOUCH_WALLS, F + 1, sizeof W, &W);
    cd_cl_arg(cl, CD_CLK_OBS_TOUCH_WALLS, F + 2, sizeof cl->wall_rows, &cl->wall_rows);
    cd_cl_arg(cl, CD_CLK_OBS_TOUCH_WALLS, F + 3, sizeof cl->wall_out, &cl->wall_out);
    cd_cl_arg(cl, CD_CLK_OBS_TOUCH_WALLS, F + 4, sizeof cl->obs_touch, &cl->obs_touch);
    cd_cl_run(cl, CD_CLK_OBS_TOUCH_WALLS, (size_t)n_cand);
    cd_cl_arg(cl, CD_CLK_OBS_PARTICLES, F, sizeof N, &N);
    cd_cl_arg(cl, CD_CLK_OBS_PARTICLES, F + 1, sizeof sim->p.gravity, &sim->p.gravity);
    cd_cl_arg(cl, CD_CLK_OBS_PARTICLES, F + 2, sizeof cl->obs_touch, &cl->obs_touch);
    cd_cl_arg(cl, CD_CLK_OBS_PARTICLES, F + 3, sizeof cl->obs_part, &cl->obs_part);
    cd_cl_arg(cl, CD_CLK_OBS_PARTICLES, F + 4, sizeof first, &first);
    cd_cl_run(cl, CD_CLK_OBS_PARTICLES, (size_t)bp);
    first = bp;
    cd_cl_arg(cl, CD_CLK_OBS_PAIRS, F, sizeof K, &K);
    cd_cl_arg(cl, CD_CLK_OBS_PAIRS, F + 1, sizeof sim->p.law, &sim->p.law);
    cd_cl_arg(cl, CD_CLK_OBS_PAIRS, F + 2, sizeof cl->obs_part, &cl->obs_part);
    cd_cl_arg(cl, CD_CLK_OBS_PAIRS, F + 3, sizeof first, &first);
    cd_cl_arg(cl, CD_CLK_OBS_PAIRS, F + 4, sizeof P, &P);
    cd_cl_arg(cl, CD_CLK_OBS_PAIRS, F + 5, sizeof sim->p.sin_parallel, &sim->p.sin_parallel);
    cd_cl_arg(cl, CD_CLK_OBS_PAIRS, F + 6, sizeof sim->p.parallel_blend, &sim->p.parallel_blend);
    cd_cl_run(cl, CD_CLK_OBS_PAIRS, (size_t)bk);
    first = bp + bk;
    cd_cl_arg(cl, CD_CLK_OBS_WALLS, F, sizeof R, &R);
    cd_cl_arg(cl, CD_CLK_OBS_WALLS, F + 1, sizeof W, &W);
    cd_cl_arg(cl, CD_CLK_OBS_WALLS, F + 2, sizeof sim->p.wall_law, &sim->p.wall_law);
    cd_cl_arg(cl, CD_CLK_OBS_WALLS, F + 3, sizeof cl->obs_part, &cl->obs_part);
    cd_cl_arg(cl, CD_CLK_OBS_WALLS, F + 4, sizeof first, &first);
    cd_cl_arg(cl, CD_CLK_OBS_WALLS, F + 5, sizeof cl->wall_start, &cl->wall_start);
    cd_cl_arg(cl, CD_CLK_OBS_WALLS, F + 6, sizeof cl->wall_rows, &cl->wall_rows);
    cd_cl_arg(cl, CD_CLK_OBS_WALLS, F + 7, sizeof cl->wall_out, &cl->wall_out);
    cd_cl_run(cl, CD_CLK_OBS_WALLS, (size_t)bw);
    /* the tree of the leaves (kernels/observe_items.h), level by level,
     * as src/backend/omp/observe.c runs it */
    for (cd_long at = 0, n = n_blocks;;) {
        cd_long m = n > CD_OBS_FANIN ? (n + CD_OBS_FANIN - 1) / CD_OBS_FANIN : 1, up = m == 1 ? 0 : at + n;
        cl_mem out = m == 1 ? cl->obs_total : cl->obs_part;
        cd_cl_arg(cl, CD_CLK_OBS_MERGE, 0, sizeof cl->obs_part, &cl->obs_part);
        cd_cl_arg(cl, CD_CLK_OBS_MERGE, 1, sizeof at, &at);
        cd_cl_arg(cl, CD_CLK_OBS_MERGE, 2, sizeof n, &n);
        cd_cl_arg(cl, CD_CLK_OBS_MERGE, 3, sizeof out, &out);
        cd_cl_arg(cl, CD_CLK_OBS_MERGE, 4, sizeof up, &up);
        cd_cl_run(cl, CD_CLK_OBS_MERGE, (size_t)m);
        if (m == 1) break;
        at = up;
        n = m;
    }
    if (!cl->status)
        cd_cl_check(cl,
                    clEnqueueReadBuffer(cl->queue, cl->obs_total, CL_TRUE, 0, CD_OBS_SLOTS * sizeof(double), slots, 0,
                                        NULL, NULL),
                    "reading the observables");
    if (cl->status) return fail(sim, err, errlen);
    return 0;
}

const cd_backend cd_backend_opencl = {
    .name = "opencl",
    .start = cl_start,
    .step = cl_step,
    .sync = cl_sync,
    .stop = cl_stop,
    .device = cl_device,
    .wall_load = cl_wall_load,
    .observe = cl_observe,
};
