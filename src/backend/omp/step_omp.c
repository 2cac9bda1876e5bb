/* The time step through OpenMP: every loop is one item per primitive, pair
 * or particle calling the shared kernel headers (kernels/step_items.h, the
 * same functions the OpenCL kernels call), and forces reach particles by a
 * gather in fixed order (no floating-point atomics), so results are bitwise
 * identical for any thread count.  A step: pair forces, wall forces, and
 * the gather with the second kick and the next step's advance (kick,
 * drift, primitive ends, skin test); a call's first step has an advance
 * of its own, and a neighbour-list rebuild comes before the forces when
 * the skin test asks for it.  On host threads the three share one
 * parallel region, on an offload device they are three launches
 * (forces_and_advance) whose arguments live on the device (cd_off_args,
 * src/backend/omp/step_device.c).
 *
 * Two variants of the same loops (src/backend/omp/omp_loops.h, docs/offload.md): on
 * host threads over the host columns of sim->s, or on an offload device
 * over device copies of the columns, mapped once at start (target enter
 * data over the cd_fields table), kept on the device across steps and
 * copied back only by sync (CAPDEM_OFFLOAD=host runs the same on LLVM's
 * x86-64 offload devices, whose memory is separate from the program's, to
 * test the mapping without a GPU).  The neighbour-list rebuild runs where
 * the steps run (src/backend/omp/neighbors.c). */
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "backend/omp/omp_loops.h"
#include "backend/omp/step_device.h"
#include "step_items.h"
#include "broadphase.h"

long cd_parallel_min_rows = 4096;

/* ---- the loops of a step ------------------------------------------------ */

#if CD_OFFLOAD
/* The device's skin flag (1: an end moved beyond half the skin since it
 * was cleared), allocated and cleared at its first use. */
static cd_int *skin_flag(cd_sim *sim)
{
    cd_int zero = 0;
    if (!sim->nb.d.skin_flag && (sim->nb.d.skin_flag = cd_dev_alloc(sizeof(cd_int))) &&
        cd_dev_put(sim->nb.d.skin_flag, &zero, sizeof zero)) {
        cd_dev_free(sim->nb.d.skin_flag);
        sim->nb.d.skin_flag = NULL;
    }
    return sim->nb.d.skin_flag;
}

/* The skin flag's one int back.  A step that set it is followed by a
 * build, whose first pass over primitives clears it on the device
 * (src/backend/omp/neighbors.c; it was a copy of its own). */
static int skin_flag_read(cd_sim *sim)
{
    cd_int moved = 1;
    if (cd_dev_get(&moved, sim->nb.d.skin_flag, sizeof moved)) return 1;
    return moved != 0;
}
#endif

/* The rows of the host's force and torque for each memory slot where the
 * first advance reads them (cd_item_advance): the host's columns are in
 * user order (each slot's user id, where the loops run; null where memory
 * order is user order, as always on an MPI rank, whose step's columns
 * they are). */
static const cd_int *host_force_order(cd_sim *sim)
{
    return cd_sim_keeps_force(sim) ? NULL : cd_sim_step_order(sim).part_uid;
}

/* After the first advance of a call: the next one sums the force and
 * torque from the rows (kernels/cols.h), and a device lets go of the
 * host's copy it held since the start (an MPI rank keeps its columns). */
static void host_force_used(cd_sim *sim)
{
    sim->nb.force_summed = 1;
#if CD_OFFLOAD
    if (!cd_sim_keeps_force(sim)) cd_off_force_map(sim, 0);
#endif
}

/* Steps 1-4 in one pass per particle (cd_item_advance): half kick, drift,
 * world ends of its primitives and the skin test.  Returns 1 when some end
 * moved more than half the skin; on the offload device one int comes
 * back.  (Run once per call of the step; the next steps' advance is fused
 * into the gather: cd_item_gather_kick_advance.)  Its force and torque: summed
 * from the rows of the last force evaluation, or where the step holds
 * them (a start's first advance, an MPI rank) read (cd_item_advance). */
static int advance_particles(cd_sim *sim)
{
    size_t n = sim->s.n_particles;
    int moved = 0;
    CD_WIDE_MIN
#if CD_OFFLOAD
    /* The flag lives on the device (set to 1, never summed: the same
     * whatever order the items run in), so one int comes back per step
     * and none goes out; a `reduction(|)` mapped tofrom cost a copy each
     * way and a cross-team combine (docs/offload.md, "Per-step copies"). */
    if (!skin_flag(sim)) return 1; /* without the flag: a rebuild each step, still correct */
    CD_ARGS(sim)
    const cd_int *uid = host_force_order(sim);
    CD_STEP_FOR(n, CD_ARGS_IN is_device_ptr(uid))
    for (size_t q = 0; q < n; q++)
        if (cd_item_advance(CD_A.c, (cd_particle_id)q, CD_A.d.gather_start, CD_A.d.gather_rows, CD_A.d.wall_start,
                            CD_A.d.wall_out, CD_A.gravity, CD_A.dimension, uid, CD_A.dt, CD_A.limit2, CD_A.d.ref_pose,
                            CD_A.fixed_spheres)) {
#pragma omp atomic write
            CD_A.d.skin_flag[0] = 1;
        }
    moved = skin_flag_read(sim);
#else
    CD_ARGS(sim)
    const cd_int *uid = host_force_order(sim);
    CD_STEP_FOR(n, CD_ARGS_IN firstprivate(uid) reduction(| : moved))
    for (size_t q = 0; q < n; q++)
        moved |= cd_item_advance(CD_A.c, (cd_particle_id)q, CD_A.d.gather_start, CD_A.d.gather_rows, CD_A.d.wall_start,
                                 CD_A.d.wall_out, CD_A.gravity, CD_A.dimension, uid, CD_A.dt, CD_A.limit2,
                                 CD_A.d.ref_pose, CD_A.fixed_spheres);
#endif
    host_force_used(sim);
    return moved;
}

/* The walls move on the host (after the particles' advance, moved: its
 * skin test).  Returns 1 when the neighbour list must be rebuilt (some
 * primitive end or wall moved more than half the skin, or a rebuild was
 * asked for). */
static int advance_walls(cd_sim *sim, int moved)
{
    cd_state *s = &sim->s;
    cd_real dt = sim->p.dt;
    for (size_t w = 0; w < s->n_walls; w++) {
        s->walls[w] = cd_wall_advanced(s->walls[w], dt);
        moved |= cd_bp_wall_moved(s->walls[w], sim->nb.walls_ref[w]) > CD_R(0.5) * sim->nb.skin;
    }
    return moved || sim->nb.force_rebuild;
}

/* Does the pair pass visit the rows through the build's visiting order
 * (rows grouped by kind: a mixture; kernels/neighbor_items.h, pass 11)?
 * Else the direct loop.  Either way each row is computed once by the same
 * item: the same bits. */
static int visit_by_kind(const cd_sim *sim) { return sim->nb.n_visit && sim->nb.n_visit == sim->s.n_pairs; }

/* One work item per pair of the Verlet list: narrow phase + contact law;
 * in a mixture the items visit the rows kind by kind (d.pair_visit). */
static void pair_forces(cd_sim *sim, cd_int outputs)
{
    size_t n = sim->s.n_pairs;
    CD_WIDE_MIN
    CD_ARGS(sim)
    cd_int visit = visit_by_kind(sim);
    CD_STEP_FOR(n, CD_ARGS_IN)
    for (size_t v = 0; v < n; v++)
        cd_item_pair_force(CD_A.c, (cd_pair_id)cd_map(visit ? CD_A.d.pair_visit : NULL, (cd_long)v), CD_A.law, CD_A.dt,
                           CD_A.sin_parallel, CD_A.blend, outputs);
}

/* One work item per wall candidate of the last build (cd_item_wall_row).
 * The walls stay host data (the protocol drives them): those in use go
 * out in the argument block when they moved (cd_off_args). */
static void wall_forces(cd_sim *sim)
{
    size_t n = sim->s.n_walls ? sim->nb.n_wall_rows : 0;
    CD_WIDE_MIN
    CD_ARGS(sim)
    CD_STEP_FOR(n, CD_ARGS_IN)
    for (size_t e = 0; e < n; e++)
        cd_item_wall_row(CD_A.c, CD_A.d.wall_rows[e], CD_A.d.wall_out + e, CD_A.walls, CD_A.n_walls, CD_A.wall_law,
                         CD_A.dt, CD_A.sin_parallel, CD_A.blend);
    sim->nb.wall_out_valid = sim->nb.wall_out_pending = 1;
}

/* One work item per particle: gravity plus its contacts in fixed order
 * (step 7; the forces of a start, without a kick). */
static void gather(cd_sim *sim)
{
    size_t n = sim->s.n_particles;
    CD_WIDE_MIN
    CD_ARGS(sim)
    CD_STEP_FOR(n, CD_ARGS_IN)
    for (size_t q = 0; q < n; q++)
        cd_item_gather(CD_A.c, (cd_particle_id)q, CD_A.d.gather_start, CD_A.d.gather_rows, CD_A.d.wall_start,
                       CD_A.d.wall_out, CD_A.gravity, CD_A.dimension);
}

/* Forces for the current positions (neighbour list up to date), without
 * a kick (a start): into the step's force and torque (the host's columns,
 * or a device's copy of them: the start maps them), which the first
 * advance need not read: it sums them again from the rows. */
static void compute_forces(cd_sim *sim)
{
    pair_forces(sim, 1);
    wall_forces(sim);
    gather(sim);
    host_force_used(sim);
}

/* The particles' force and torque into the host's columns, in user order,
 * summed from the rows as the next call's first advance sums them
 * (cd_item_gather_to): at sync, where the step holds none (one process)
 * and the rows hold a force evaluation since the start (else the host's
 * columns are current: a start without forces).  Host memory: once after
 * steps (a second sync finds the columns in user order, host_user, and
 * the force written); an offload device: at every sync, into a copy
 * mapped for it, outside the step's columns (the host's columns, which
 * every sync moves to user order, are written anew each time as the wall
 * rows are; the loops' argument block stays as it is). */
static void force_to_host(cd_sim *sim)
{
    size_t n = sim->s.n_particles;
    int device = !cd_step_memory_is_host();
    if (cd_sim_keeps_force(sim) || !sim->nb.force_summed || !n || (!device && sim->nb.host_user)) return;
    cd_vec3 *F = sim->s.force, *T = sim->s.torque;
#if CD_OFFLOAD
    if (device) cd_off_force_sums(sim, 1, &F, &T);
#endif
    CD_WIDE_MIN
    CD_ARGS(sim)
    CD_STEP_FOR(n, CD_ARGS_IN CD_DEV(is_device_ptr(F, T)))
    for (size_t q = 0; q < n; q++)
        cd_item_gather_to(CD_A.c, (cd_particle_id)q, CD_A.d.gather_start, CD_A.d.gather_rows, CD_A.d.wall_start,
                          CD_A.d.wall_out, CD_A.gravity, CD_A.dimension, CD_A.order.part_uid, F, T);
#if CD_OFFLOAD
    if (device) cd_off_force_sums(sim, 0, &F, &T);
#endif
}

void cd_sim_force_before_build(cd_sim *sim)
{
    if (sim->nb.in_step || !sim->nb.force_summed || cd_sim_keeps_force(sim)) return;
    force_to_host(sim);
    sim->nb.force_summed = 0;
#if CD_OFFLOAD
    cd_off_force_map(sim, 1);
#endif
}

#if CD_OFFLOAD
/* Rows (the most of pair rows, wall candidates and particles) up to which
 * a step's three loops run as one launch of one team (CD_ONE_TEAM): the
 * launches of a small system cost more than its work (on an H100 about
 * 8 us each, synchronous; the GPU test runs of 2026-11-26/27 left small
 * cases unfinished in 300 s).  256: about two rows a thread of a team of
 * LLVM 16's default 128 threads (its register budget, 65,536 / 128, holds
 * the step's 196-212 registers a thread); CAPDEM_ONE_TEAM_ROWS=N sets it
 * (0: never), so that a GPU run can compare. */
static size_t one_team_rows(void)
{
    static long rows = -1;
    if (rows < 0) {
        const char *v = getenv("CAPDEM_ONE_TEAM_ROWS");
        rows = v && *v ? atol(v) : 256;
        if (rows < 0) rows = 0;
    }
    return (size_t)rows;
}

CD_DEVICE_BEGIN
/* Particle q's gather, second kick and, with next, the next step's
 * advance, from the device's argument block; the skin flag set when q's
 * ends moved beyond half the skin and the flag is there (flagged). */
CD_INLINE_ALWAYS void gather_kick_advance_item(size_t q, int next, int flagged)
{
    if (cd_item_gather_kick_advance(CD_A.c, (cd_particle_id)q, CD_A.d.gather_start, CD_A.d.gather_rows,
                                    CD_A.d.wall_start, CD_A.d.wall_out, CD_A.gravity, CD_A.dimension, CD_A.dt,
                                    CD_A.limit2, CD_A.d.ref_pose, CD_A.fixed_spheres, next) &&
        flagged) {
#pragma omp atomic write
        CD_A.d.skin_flag[0] = 1;
    }
}
CD_DEVICE_END

/* The offload step of a small system: pair rows, wall candidates, then
 * (a barrier) the gather with the kick and the next advance, the items of
 * the three launches in one; each row is computed by the same item as
 * there, so the same bits; the skin flag is written on the device when
 * flagged, as there. */
static void forces_and_advance_one_team(cd_sim *sim, int next, int flagged)
{
    size_t n_pairs = sim->s.n_pairs, n_walls = sim->s.n_walls ? sim->nb.n_wall_rows : 0, n = sim->s.n_particles;
    size_t most = n_pairs > n ? n_pairs : n;
    most = n_walls > most ? n_walls : most;
    cd_int outputs = !next, visit = visit_by_kind(sim);
    CD_WIDE_MIN
    CD_ARGS(sim)
    CD_ONE_TEAM(most, CD_ARGS_IN)
    {
        CD_TEAM_FOR(nowait) /* the wall rows write other rows and read only the particles */
        for (size_t k = 0; k < n_pairs; k++)
            cd_item_pair_force(CD_A.c, (cd_pair_id)cd_map(visit ? CD_A.d.pair_visit : NULL, (cd_long)k), CD_A.law,
                               CD_A.dt, CD_A.sin_parallel, CD_A.blend, outputs);
        CD_TEAM_FOR()
        for (size_t e = 0; e < n_walls; e++)
            cd_item_wall_row(CD_A.c, CD_A.d.wall_rows[e], CD_A.d.wall_out + e, CD_A.walls, CD_A.n_walls, CD_A.wall_law,
                             CD_A.dt, CD_A.sin_parallel, CD_A.blend);
        CD_TEAM_FOR(nowait)
        for (size_t q = 0; q < n; q++) gather_kick_advance_item(q, next, flagged);
    }
    sim->nb.wall_out_valid = sim->nb.wall_out_pending = 1;
}
#endif

/* Steps 5-8 (forces, second half kick) and, with next = 1, steps 1-4 of
 * the next step (its advance; returns its skin test); next = 0 (the call's
 * last step): the pair rows' F_n is written too.
 * Host threads: one parallel region (docs/performance.md, "One parallel
 * region per step"), in which each thread sweeps its range of particles
 * (above, "The sweep") and, with two threads or more, after one barrier
 * its range's edges; the next step's advance of particle q is in the same
 * item as q's gather and kick (it reads only q's own rows).  Each item
 * does the arithmetic it did in its own loop, in the same order: the same
 * bits.  The edges are marked at the first step after a build, or when
 * the region's thread count changes (every thread tests the same
 * numbers, so all or none meet the barrier).  An offload device runs
 * three launches: pair rows, wall candidates, and the gather with the
 * kick and the next advance (the same item as on host threads; the skin
 * flag stays on the device, one int back); a small system (up to
 * one_team_rows() rows) the same loops in one launch of one team. */
static int forces_and_advance(cd_sim *sim, int next)
{
#if CD_OFFLOAD
    size_t n = sim->s.n_particles, most = sim->s.n_pairs > n ? sim->s.n_pairs : n;
    if (sim->s.n_walls && sim->nb.n_wall_rows > most) most = sim->nb.n_wall_rows;
    int flagged = next && skin_flag(sim);
    if (most <= one_team_rows()) {
        forces_and_advance_one_team(sim, next, flagged);
    } else {
        pair_forces(sim, !next);
        wall_forces(sim);
        CD_WIDE_MIN
        CD_ARGS(sim)
        CD_STEP_FOR(n, CD_ARGS_IN)
        for (size_t q = 0; q < n; q++) gather_kick_advance_item(q, next, flagged);
    }
    if (!next) return 0;
    return flagged ? skin_flag_read(sim) : 1; /* without the flag: a rebuild, still correct */
#else
    return cd_omp_sweep(sim, next);
#endif
}

void cd_sim_refresh(cd_sim *sim)
{
    cd_state *s = &sim->s;
    for (size_t q = 0; q < s->n_particles; q++)
        s->angvel[q] = cd_rigid_angvel(s->orientation[q], s->angmom[q], s->inertia[q]);
    cd_cols c = cd_sim_host_cols(s);
    size_t n = s->n_prims;
    CD_HOST_FOR(n, firstprivate(c))
    for (size_t i = 0; i < n; i++) cd_item_prim_ends(c, (cd_prim_id)i);
    cd_state_arms_expand(s, s->prim_arm, s->arm); /* the host's prim_b current too */
    sim->nb.force_rebuild = 1;
}

/* bad: the user id of a particle that blew up (-1: none). */
static int report_bad(const cd_state *s, long bad, char *err, size_t errlen)
{
    if (bad < 0) return 0;
    snprintf(err, errlen,
             "non-finite position or velocity of particle %ld at step %lld (t = %.9g s): "
             "the run blew up; reduce run.dt or check the material parameters",
             bad, s->step, s->time);
    return -1;
}

/* A run that blew up must stop before it writes garbage. */
int cd_sim_check_state(const cd_sim *sim, char *err, size_t errlen)
{
    const cd_state *s = &sim->s;
    cd_cols c = cd_sim_host_cols((cd_state *)s); /* read only */
    long bad = -1;
    size_t n = s->n_particles;
    CD_HOST_FOR(n, reduction(max : bad))
    for (size_t q = 0; q < n; q++)
        if (cd_item_not_finite(c, (cd_particle_id)q)) bad = (long)q > bad ? (long)q : bad;
    /* host memory: the host columns may be in memory order */
    if (bad >= 0 && cd_step_memory_is_host()) bad = (long)cd_map(cd_sim_step_order(sim).part_uid, bad);
    return report_bad(s, bad, err, errlen);
}

/* The same check on the columns the steps work on (the device's). */
static int check_step_state(cd_sim *sim, char *err, size_t errlen)
{
#if CD_OFFLOAD
    long bad = -1;
    size_t n = sim->s.n_particles;
    CD_WIDE_MIN
    CD_ARGS(sim)
    CD_STEP_FOR(n, CD_ARGS_IN reduction(max : bad) map(tofrom : bad))
    for (size_t q = 0; q < n; q++)
        if (cd_item_not_finite(CD_A.c, (cd_particle_id)q)) bad = (long)q > bad ? (long)q : bad;
    cd_int uid = (cd_int)bad;
    if (bad >= 0 && sim->nb.ordered) cd_dev_get(&uid, sim->nb.d.part_uid + bad, sizeof uid);
    return report_bad(&sim->s, uid, err, errlen);
#else
    return cd_sim_check_state(sim, err, errlen);
#endif
}

/* CD_ENDS_FROM_POSE (offload): the steps do not store the primitives'
 * world ends (kernels/step_items.h); before the state goes back to the
 * host they are computed from the poses where the steps run, one launch
 * (the values the steps used: the same function on the same numbers). */
static void store_ends(cd_sim *sim)
{
#if CD_OFFLOAD && CD_ENDS_FROM_POSE
    size_t n = sim->s.n_particles;
    if (!sim->backend_data) return;
    CD_WIDE_MIN
    CD_ARGS(sim)
    CD_STEP_FOR(n, CD_ARGS_IN)
    for (size_t q = 0; q < n; q++) cd_item_particle_ends(CD_A.c, (cd_particle_id)q);
#else
    (void)sim;
#endif
}

/* The primitives' arms into the host's PRIM_ARM rows (cd_state_arms_expand)
 * while the host columns are in the step's order: before
 * cd_reorder_to_user moves them; a second sync without a step between
 * finds them in user order (host_user) and the rows already written. */
static void arms_to_host(cd_sim *sim)
{
    cd_state *s = &sim->s;
    if (s->prim_arm && !sim->nb.host_user) cd_state_arms_expand(s, s->prim_arm, s->arm);
}

/* The arms anew from the host's columns (in user order: after omp_stop). */
static int arms_from_host(cd_sim *sim, char *err, size_t errlen)
{
    if (!cd_state_arms_derive(&sim->s)) return 0;
    snprintf(err, errlen, "out of memory while setting up the primitives' arms");
    return -1;
}

/* The backend lets go of the state: in host memory (host threads, or an
 * offload build's host fallback) the host columns go back to user order
 * (they are the current state); an offload device's state is dropped (the
 * host keeps what the last sync brought). */
static void omp_stop(cd_sim *sim)
{
    /* the host keeps the step's wall-contact outputs and arms too */
    if (cd_step_memory_is_host()) {
        store_ends(sim);
        arms_to_host(sim);
    }
    if (cd_step_memory_is_host() && (cd_neighbors_wall_out_to_host(sim) || cd_reorder_to_user(sim)))
        fprintf(stderr, "capdem: out of memory putting the particles in user order\n");
    cd_reorder_forget(sim);
#if CD_OFFLOAD
    cd_off_release(sim);
#endif
    sim->nb.wall_out_valid = sim->nb.wall_out_pending = 0;
    sim->nb.force_summed = 0; /* the next first advance: the host's force and torque */
}

static int omp_sync(cd_sim *sim, char *err, size_t errlen);

int cd_sim_step_remap(cd_sim *sim, char *err, size_t errlen)
{
#if CD_OFFLOAD
    omp_stop(sim);
    if (arms_from_host(sim, err, errlen)) return -1;
    return cd_off_acquire(sim, err, errlen);
#else
    (void)sim;
    (void)err;
    (void)errlen;
    return 0;
#endif
}

static int omp_start(cd_sim *sim, int compute, char *err, size_t errlen)
{
    omp_stop(sim);
    if (arms_from_host(sim, err, errlen)) return -1;
    cd_sim_refresh(sim);
    /* the host's wall rows hold the contacts to carry on (a resumed run, a
     * state put back): the first build turns them into candidate entries */
    sim->nb.walls_from_host = 1;
#if CD_OFFLOAD
    if (cd_off_acquire(sim, err, errlen)) return -1;
#endif
    if (compute && cd_neighbors_build(sim)) {
        snprintf(err, errlen, "out of memory while building the first neighbour list");
        return -1;
    }
    /* without compute the neighbour list is rebuilt at the first step */
    if (compute) {
        compute_forces(sim);
        /* The new forces, contacts and wall contacts were computed on the
         * device: copy them back once, so that the host state is current
         * after start (tests and tools read energies right after it), as
         * the OpenCL backend does. */
        return omp_sync(sim, err, errlen);
    }
    return 0;
}

static int step_calls(cd_sim *sim, long long n, char *err, size_t errlen);

static int omp_step(cd_sim *sim, long long n, char *err, size_t errlen)
{
    cd_state *s = &sim->s;
#if CD_OFFLOAD
    /* the state is on the device only after a start (the OpenCL backend
     * refuses the same way); host threads step the host's columns */
    if (!sim->backend_data) {
        snprintf(err, errlen, "the omp offload backend was not started (cd_sim_start)");
        return -1;
    }
#endif
    /* a state stepped without a start (tests): its arms from its columns */
    if ((!s->prim_arm || (!s->inertia_iso && !s->step_inertia)) && arms_from_host(sim, err, errlen)) return -1;
    /* host threads after a sync: the columns back in the lists' order */
    if (cd_reorder_to_memory(sim)) {
        snprintf(err, errlen, "out of memory putting the particles in memory order");
        return -1;
    }
    /* (a build inside a call takes no force from the rows: the first
     * advance has used them; cd_sim_force_before_build) */
    sim->nb.in_step = 1;
    int rc = step_calls(sim, n, err, errlen);
    sim->nb.in_step = 0;
    return rc ? rc : check_step_state(sim, err, errlen);
}

/* omp_step's steps, after the columns are in memory order. */
static int step_calls(cd_sim *sim, long long n, char *err, size_t errlen)
{
    cd_state *s = &sim->s;
    int moved = n > 0 ? advance_particles(sim) : 0;
    for (long long it = 0; it < n; it++) {
        int rebuild = advance_walls(sim, moved);
        if (sim->rebuild_hook && (rebuild = sim->rebuild_hook(sim, rebuild, err, errlen)) < 0) return -1;
        int rc = rebuild ? cd_neighbors_build(sim) : 0;
        if (rc == CD_NB_BLOWUP) {
            snprintf(err, errlen,
                     "particle centres spread beyond any container (or not finite) at step %lld (t = "
                     "%.9g s): the run blew up; reduce run.dt or check the material parameters",
                     s->step, s->time);
            return -1;
        }
        if (rc) {
            snprintf(err, errlen, "out of memory while building the neighbour list (%zu pairs)", s->n_pairs);
            return -1;
        }
        moved = forces_and_advance(sim, it + 1 < n);
        s->step++;
        s->time += sim->p.dt;
    }
    return 0;
}

static int omp_sync(cd_sim *sim, char *err, size_t errlen)
{
    store_ends(sim);
    force_to_host(sim); /* (one process; an MPI rank's below, with the columns) */
#if CD_OFFLOAD
    /* The only full copy back: every device column, rows in use. */
    cd_off *o = sim->backend_data;
    if (o)
        for (size_t f = 0; f < cd_n_fields; f++) {
#if defined(CAPDEM_PLANT_MISSING_UPDATE) && CAPDEM_PLANT_MISSING_UPDATE
            /* tests/offload builds capdem-planted with the velocities left
             * on the device: snapshots, observables and resumes see stale
             * ones; the offload checks must fail on it */
            if (*cd_field_ptr(&sim->s, &cd_fields[f]) == (void *)sim->s.velocity) continue;
#endif
            if (o->host[f])
                cd_off_from(*cd_field_ptr(&sim->s, &cd_fields[f]),
                            cd_state_rows(&sim->s, cd_fields[f].group) * cd_fields[f].elem_size);
        }
    /* the arms in the step's order: expanded below (arms_to_host); the
     * step's inertia too, which cd_reorder_to_user moves with the rows */
    if (o)
        for (int k = 0; k < CD_OFF_DERIVED; k++) cd_off_from(o->arm_host[k], o->arm_bytes[k]);
    /* an MPI rank's force and torque (kernels/cols.h; its local state is
     * never reordered: user order) */
    if (cd_sim_keeps_force(sim)) cd_off_force_from(sim);
    /* The host's wall rows anew as well, whenever the step has entries:
     * cd_reorder_to_user below moves every host column from memory order
     * at every sync, so rows not written again (a second sync without a
     * step between) would be moved twice.  In host memory (the host
     * fallback) the columns are the step's: a second sync finds them in
     * user order and moves nothing, as on host threads. */
    if (sim->nb.wall_out_valid && !cd_step_memory_is_host()) sim->nb.wall_out_pending = 1;
#endif
    /* the wall contacts kept per candidate and the arms into the host's
     * rows, then the host columns in user order (src/backend/omp/reorder.c) */
    arms_to_host(sim);
    if (cd_neighbors_wall_out_to_host(sim) || cd_reorder_to_user(sim)) {
        snprintf(err, errlen, "out of memory putting the particles in user order");
        return -1;
    }
    return 0;
}

static const char *omp_device(const cd_sim *sim)
{
    static char buf[96];
#if CD_OFFLOAD
    if (omp_get_num_devices() > 0)
        snprintf(buf, sizeof buf, "%s offload device %d of %d", CAPDEM_OFFLOAD_VARIANT, omp_get_default_device(),
                 omp_get_num_devices());
    else snprintf(buf, sizeof buf, "host (built for %s offload, no offload device found)", CAPDEM_OFFLOAD_VARIANT);
#else
    snprintf(buf, sizeof buf, "host, %d OpenMP thread(s)", sim->threads);
#endif
    (void)sim;
    return buf;
}


const cd_backend cd_backend_omp = {"omp",    omp_start,  omp_step,         omp_sync,
                                   omp_stop, omp_device, cd_omp_wall_load, cd_omp_observe};
