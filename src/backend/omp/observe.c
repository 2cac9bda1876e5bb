/* Observables of the state: energies, momentum, wall forces, contact
 * counts, largest overlap, as the fixed-order reductions of
 * kernels/observe_items.h: on the host columns (cd_sim_observe, after a
 * sync), or where the steps run (cd_sim_observe_step: on the offload
 * device only the merged slots come back, so a thermo line or a
 * relaxation check costs no state copy).  Both give the same bits. */
#include <stdlib.h>
#include <string.h>
#include <math.h>
#include "backend/omp/omp_loops.h"
#include "backend/omp/step_device.h"
#include "observe_items.h"

/* Leaves of the three reductions, in merge order. */
typedef struct {
    cd_long particles, pairs, walls;
} obs_blocks;

static cd_long leaves(obs_blocks n) { return n.particles + n.pairs + n.walls; }

/* The tree of kernels/observe_items.h over the n leaves at part (the
 * levels above them written after them) into total, on the offload device
 * (dev) or on host threads: one loop a level, 1 up to 16 leaves, 2 up to
 * 256, 3 up to 4,096. */
static void merge_tree(cd_real *part, cd_long n, cd_real *total, int dev)
{
    CD_WIDE_MIN
    for (cd_real *in = part;;) {
        cd_long m = n > CD_OBS_FANIN ? (n + CD_OBS_FANIN - 1) / CD_OBS_FANIN : 1, n_in = n;
        cd_real *out = m == 1 ? total : in + n * CD_OBS_SLOTS;
        if (dev) {
            CD_STEP_FOR(m, CD_DEV(is_device_ptr(in, out)))
            for (cd_long g = 0; g < m; g++) cd_obs_item_merge(in, n_in, g, out);
        } else {
            CD_HOST_FOR(m, firstprivate(in, out))
            for (cd_long g = 0; g < m; g++) cd_obs_item_merge(in, n_in, g, out);
        }
        if (m == 1) return;
        in = out;
        n = m;
    }
}

static obs_blocks count_blocks(const cd_state *s)
{
    obs_blocks n;
    n.particles = ((cd_long)s->n_particles + CD_OBS_BLOCK - 1) / CD_OBS_BLOCK;
    n.pairs = cd_obs_pair_blocks((cd_long)s->n_prims);
    n.walls = ((cd_long)(s->n_prims * s->n_walls) + CD_OBS_BLOCK - 1) / CD_OBS_BLOCK;
    return n;
}

/* The merged slots into cd_observables: one member per SUM or MAX row of
 * kernels/observables.def, all of its slots (those of walls a run does not
 * have hold 0). */
static void unpack(const double *t, cd_observables *o)
{
#define CD_OBS_UNPACK_(id, member)    memcpy(&o->member, &t[CD_OBS_##id], sizeof o->member);
#define CD_OBS_UNPACK_SUM(id, member) CD_OBS_UNPACK_(id, member)
#define CD_OBS_UNPACK_MAX(id, member) CD_OBS_UNPACK_(id, member)
#define CD_OBS_UNPACK_WALLS(id, member)
#define CD_OBS_UNPACK_PROTOCOL(id, member)
#define CD_OBSERVABLE(id, name, unit, count, source, member, meaning) CD_OBS_UNPACK_##source(id, member)
#include "observables.def"
}

/* The host's wall contacts in the form of the step's candidate lists
 * (kernels/step_items.h, cd_wall_out_place): per particle the rows in
 * contact of its primitives, ascending, with their history and outputs
 * from the host's columns.  0, or -1 (out of memory). */
static int host_wall_lists(const cd_state *s, cd_int **start, cd_int **rows, cd_wall_entry **out)
{
    size_t N = s->n_particles, W = s->n_walls, n = 0;
    for (size_t r = 0; r < s->n_prims * W; r++) n += s->wallc_active[r] != 0;
    *start = malloc((N + 1) * sizeof **start);
    *rows = malloc((n + 1) * sizeof **rows);
    *out = malloc((n + 1) * sizeof **out);
    if (!*start || !*rows || !*out) return -1;
    cd_int e = 0;
    for (size_t q = 0; q < N; q++) {
        (*start)[q] = e;
        size_t first = (size_t)s->prim_first[q], last = first + (size_t)s->prim_count[q];
        for (size_t r = first * W; r < last * W; r++) {
            if (!s->wallc_active[r]) continue;
            (*rows)[e] = (cd_int)r;
            (*out)[e++] = cd_state_wall_entry(s, r);
        }
    }
    (*start)[N] = e;
    return 0;
}

void cd_observables_slots(const cd_sim *sim, double *total)
{
    const cd_state *s = &sim->s;
    cd_cols c = cd_sim_host_cols((cd_state *)s); /* read only */
    obs_blocks nb = count_blocks(s);
    cd_long N = (cd_long)s->n_particles, K = (cd_long)s->n_pairs, R = (cd_long)(s->n_prims * s->n_walls),
            P = (cd_long)s->n_prims;
    cd_int W = (cd_int)s->n_walls;
    cd_vec3 g = sim->p.gravity;
    cd_law_params law = sim->p.law, wall_law = sim->p.wall_law;
    cd_order o = cd_sim_host_order(sim);
    cd_int *touch = calloc((size_t)N + 1, sizeof(cd_int));
    double *part = malloc((size_t)(cd_obs_tree_blocks(leaves(nb)) + 1) * CD_OBS_SLOTS * sizeof(double));
    cd_int *wall_start = NULL, *wall_rows = NULL;
    cd_wall_entry *out = NULL;
    if (!touch || !part || host_wall_lists(s, &wall_start, &wall_rows, &out)) {
        /* without memory: what is known is nothing */
        free(touch);
        free(part);
        free(wall_start);
        free(wall_rows);
        free(out);
        for (int k = 0; k < CD_OBS_SLOTS; k++) total[k] = NAN;
        return;
    }
    /* Rattlers move freely in their cages (without gravity and friction
     * forever): relaxation criteria look at the particles that touch. */
    CD_HOST_FOR(K, firstprivate(c))
    for (cd_long k = 0; k < K; k++) cd_obs_item_touch_pair(c, k, touch);
    cd_long n_cand = wall_start[N];
    CD_HOST_FOR(n_cand, firstprivate(c, wall_rows, out))
    for (cd_long e = 0; e < n_cand; e++) cd_obs_item_touch_wall(c, e, W, wall_rows, out, touch);
    double *pp = part, *pk = part + nb.particles * CD_OBS_SLOTS, *pw = pk + nb.pairs * CD_OBS_SLOTS;
    CD_HOST_FOR(N, firstprivate(c, o))
    for (cd_long b = 0; b < nb.particles; b++) cd_obs_block_particles(c, b, N, g, touch, pp + b * CD_OBS_SLOTS, o);
    /* The overlaps from the step's columns (the arms: cd_state_arms_derive);
     * a state whose arms were never derived (set up by hand) from the host's
     * columns, as at sync (src/io/pair_output.c): the same bits. */
    const double *overlap = NULL;
    if (!s->prim_arm) {
        cd_sim_derive_pair_output((cd_sim *)sim);
        overlap = s->pair_overlap;
    }
    cd_real sin_parallel = sim->p.sin_parallel;
    cd_int blend = sim->p.parallel_blend;
    CD_HOST_FOR(P, firstprivate(c, o, overlap, sin_parallel, blend))
    for (cd_long b = 0; b < nb.pairs; b++)
        cd_obs_block_pairs(c, b, K, law, pk + b * CD_OBS_SLOTS, o, overlap, sin_parallel, blend);
    CD_HOST_FOR(R, firstprivate(c, o))
    for (cd_long b = 0; b < nb.walls; b++)
        cd_obs_block_walls(c, b, R, W, wall_law, pw + b * CD_OBS_SLOTS, o, wall_start, wall_rows, out);
    merge_tree(part, leaves(nb), total, 0);
    free(touch);
    free(part);
    free(wall_start);
    free(wall_rows);
    free(out);
}

void cd_sim_observe(const cd_sim *sim, cd_observables *o)
{
    double total[CD_OBS_SLOTS];
    cd_observables_slots(sim, total);
    unpack(total, o);
}

#if CD_OFFLOAD
/* The same reductions on the offload device (the omp backend's observe
 * operation in the offload variant); the scratch stays allocated there,
 * grown when the pair rows grow. */
static int observe_device(cd_sim *sim, double *slots, char *err, size_t errlen)
{
    const cd_state *s = &sim->s;
    /* not started, or no forces since the start: the host columns are
     * current (the wall contacts' outputs are on the device from the first
     * forces on) */
    if (!sim->backend_data || !sim->nb.wall_out_valid) {
        cd_observables_slots(sim, slots);
        return 0;
    }
    cd_sim_obs_scratch *x = &sim->obs;
    obs_blocks nb = count_blocks(s);
    size_t blocks = (size_t)cd_obs_tree_blocks(leaves(nb)) + 1;
    snprintf(err, errlen, "out of device memory while summing the observables");
    if (!x->touch) {
        x->touch = cd_dev_alloc((s->n_particles + 1) * sizeof(cd_int));
        x->total = cd_dev_alloc(CD_OBS_SLOTS * sizeof(cd_real));
        if (!x->touch || !x->total) return -1;
    }
    if (blocks > x->cap_blocks) {
        cd_dev_free(x->partial);
        x->cap_blocks = blocks + blocks / 4;
        x->partial = cd_dev_alloc(x->cap_blocks * CD_OBS_SLOTS * sizeof(cd_real));
        if (!x->partial) return -1;
    }
    cd_long N = (cd_long)s->n_particles, K = (cd_long)s->n_pairs, R = (cd_long)(s->n_prims * s->n_walls),
            P = (cd_long)s->n_prims;
    cd_int W = (cd_int)s->n_walls;
    cd_int *touch = x->touch;
    cd_real *part = x->partial, *total = x->total;
    cd_long pk = nb.particles * CD_OBS_SLOTS, pw = pk + nb.pairs * CD_OBS_SLOTS;
    cd_long n_cand = W ? (cd_long)sim->nb.n_wall_rows : 0;
    CD_WIDE_MIN
    CD_ARGS(sim) /* the step's block: columns, lists, order, laws, gravity */
    CD_STEP_FOR(N, is_device_ptr(touch))
    for (cd_long q = 0; q < N; q++) touch[q] = 0;
    CD_STEP_FOR(K, CD_ARGS_IN is_device_ptr(touch))
    for (cd_long k = 0; k < K; k++) cd_obs_item_touch_pair(CD_A.c, k, touch);
    CD_STEP_FOR(n_cand, CD_ARGS_IN is_device_ptr(touch))
    for (cd_long e = 0; e < n_cand; e++) cd_obs_item_touch_wall(CD_A.c, e, W, CD_A.d.wall_rows, CD_A.d.wall_out, touch);
    CD_STEP_FOR(N, CD_ARGS_IN is_device_ptr(touch, part))
    for (cd_long b = 0; b < nb.particles; b++)
        cd_obs_block_particles(CD_A.c, b, N, CD_A.gravity, touch, part + b * CD_OBS_SLOTS, CD_A.order);
    CD_STEP_FOR(P, CD_ARGS_IN is_device_ptr(part))
    for (cd_long b = 0; b < nb.pairs; b++)
        cd_obs_block_pairs(CD_A.c, b, K, CD_A.law, part + pk + b * CD_OBS_SLOTS, CD_A.order, NULL, CD_A.sin_parallel,
                           CD_A.blend);
    CD_STEP_FOR(R, CD_ARGS_IN is_device_ptr(part))
    for (cd_long b = 0; b < nb.walls; b++)
        cd_obs_block_walls(CD_A.c, b, R, W, CD_A.wall_law, part + pw + b * CD_OBS_SLOTS, CD_A.order, CD_A.d.wall_start,
                           CD_A.d.wall_rows, CD_A.d.wall_out);
    merge_tree(part, leaves(nb), total, 1);
    return cd_dev_get(slots, total, CD_OBS_SLOTS * sizeof(double)) ? -1 : 0;
}
#endif

/* Host memory (host threads, or an offload build's host fallback): the
 * host columns are the step's, summed in user order whatever their memory
 * order, without a sync (which would put them in user order and back); the
 * wall contacts' F_n from the candidate lists while these are newer than
 * the host's rows (steps since the last sync), in the same order. */
static int host_wall_load(cd_sim *sim, int w, double *load, char *err, size_t errlen)
{
    (void)err;
    (void)errlen;
    if (!sim->nb.wall_out_pending) {
        *load = cd_sim_wall_load_host(sim, w);
        return 0;
    }
    cd_cols c = cd_sim_step_cols(sim);
    cd_nb_lists d = sim->nb.d;
    cd_long P = (cd_long)sim->s.n_prims;
    const cd_int *prim_at = cd_sim_step_order(sim).prim_at;
    double sum = 0;
    for (cd_long ch = 0; ch * CD_LOAD_CHUNK < P; ch++)
        sum += cd_item_wall_load_chunk(c, ch, P, (cd_int)sim->s.n_walls, w, prim_at, d.wall_start, d.wall_rows,
                                       d.wall_out);
    *load = sum;
    return 0;
}

/* The host's columns, with the wall contacts' outputs of the last steps
 * (in the columns' memory order). */
static int host_observe(cd_sim *sim, double *slots, char *err, size_t errlen)
{
    if (cd_neighbors_wall_out_to_host(sim)) {
        snprintf(err, errlen, "out of memory while summing the observables");
        return -1;
    }
    cd_observables_slots(sim, slots);
    return 0;
}

#if CD_OFFLOAD
/* Normal load on wall w summed on the device: per-chunk partial sums in
 * parallel, then the chunks in order (deterministic, one double back). */
int cd_omp_wall_load(cd_sim *sim, int w, double *load, char *err, size_t errlen)
{
    cd_off *o = sim->backend_data;
    if (cd_step_memory_is_host()) return host_wall_load(sim, w, load, err, errlen);
    /* not started, or no forces since: the host columns are current */
    if (!o || !sim->nb.wall_out_valid) {
        *load = cd_sim_wall_load_host(sim, w);
        return 0;
    }
    double *part = o->part;
    size_t P = sim->s.n_prims, W = sim->s.n_walls, nch = (P + CD_LOAD_CHUNK - 1) / CD_LOAD_CHUNK;
    size_t total = o->part_n - 1; /* the slot after the chunks' */
    const cd_int *prim_at = cd_sim_step_order(sim).prim_at;
    CD_WIDE_MIN
    CD_ARGS(sim)
    CD_STEP_FOR(nch, CD_ARGS_IN is_device_ptr(prim_at))
    for (size_t ch = 0; ch < nch; ch++)
        part[ch] = cd_item_wall_load_chunk(CD_A.c, (cd_long)ch, (cd_long)P, (cd_int)W, w, prim_at, CD_A.d.wall_start,
                                           CD_A.d.wall_rows, CD_A.d.wall_out);
        /* the chunks in order into the slot after them, which alone comes
     * back: no mapping made per call, one double copied */
#pragma omp target
    {
        double sum = 0;
        for (size_t ch = 0; ch < nch; ch++) sum += part[ch];
        part[total] = sum;
    }
#pragma omp target update from(part [total:1])
    *load = part[total];
    return 0;
}

/* The observables where the steps run: on the device (observe_device above),
 * or, in the host fallback, as on host threads: the device's lists are in
 * memory order while a sync has put the one set of columns in user order. */
int cd_omp_observe(cd_sim *sim, double *slots, char *err, size_t errlen)
{
    if (cd_step_memory_is_host()) return host_observe(sim, slots, err, errlen);
    return observe_device(sim, slots, err, errlen);
}
#else
int cd_omp_wall_load(cd_sim *sim, int w, double *load, char *err, size_t errlen)
{
    return host_wall_load(sim, w, load, err, errlen);
}

int cd_omp_observe(cd_sim *sim, double *slots, char *err, size_t errlen)
{
    return host_observe(sim, slots, err, errlen);
}
#endif

int cd_sim_observe_step(cd_sim *sim, cd_observables *o, char *err, size_t errlen)
{
    if (sim->backend && sim->backend->observe) {
        double t[CD_OBS_SLOTS];
        if (sim->backend->observe(sim, t, err, errlen)) return -1;
        unpack(t, o);
        return 0;
    }
    if (cd_sim_sync(sim, err, errlen)) return -1;
    cd_sim_observe(sim, o);
    return 0;
}

void cd_sim_observe_free(cd_sim *sim)
{
    cd_dev_free(sim->obs.touch);
    cd_dev_free(sim->obs.partial);
    cd_dev_free(sim->obs.total);
    memset(&sim->obs, 0, sizeof sim->obs);
}
