/* Residency of the omp backend's state on an offload device and the
 * step's argument block (src/backend/omp/step_device.h): mapped once at
 * start over the cd_fields table, kept on the device across steps, copied
 * back only by sync (src/backend/omp/step_omp.c). */
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "backend/omp/step_device.h"
#include "step_items.h"
#include "broadphase.h"

#if CD_OFFLOAD
/* The loops' argument block (step_device.h).  On an NVIDIA GPU Clang
 * places it in constant memory (64 kB a device; the block is 1.6 kB),
 * which the host writes between launches as CUDA's cudaMemcpyToSymbol
 * does, and which a kernel reads through the constant cache; GCC 12 has
 * no such allocator (`#pragma omp allocate` of a global is not
 * implemented there) and keeps it in global memory, as do LLVM's host
 * offload devices. */
#pragma omp declare target
cd_step_args cd_step_block;
#pragma omp end declare target
#endif

/* The state's device columns for the per-item functions of
 * kernels/step_items.h. */
cd_cols cd_sim_host_cols(cd_state *s)
{
    cd_cols c;
#define CD_FIELD(group, ctype, h5type, ncomp, name, unit, meaning) CD_ON_DEVICE_##group(c.name = s->name;)
#include "fields.def"
#undef CD_FIELD
    c.prim_arm = cd_state_arms_all(s) ? NULL : s->prim_arm; /* kernels/cols.h, cd_prim_arm_of */
    c.arm = s->arm;
    /* the step's inertia (cd_inertia_of); a state whose was never derived
     * (set up by hand, not started) the host's column, in its order */
    c.inertia = s->inertia_iso ? NULL : s->step_inertia ? s->step_inertia : s->inertia;
    c.inertia_iso = s->inertia_iso;
    /* the host's force and torque (the step's: cd_sim_step_cols) */
    c.force = s->force;
    c.torque = s->torque;
    return c;
}

#if CD_OFFLOAD
static void off_map(void *p, size_t bytes)
{
    char *c = p;
    if (c && bytes) {
#pragma omp target enter data map(to : c [0:bytes])
    }
}

static void off_unmap(void *p, size_t bytes)
{
    char *c = p;
    if (c && bytes) {
#pragma omp target exit data map(delete : c [0:bytes])
    }
}

void cd_off_from(void *p, size_t bytes)
{
    char *c = p;
    if (c && bytes) {
#pragma omp target update from(c [0:bytes])
    }
}

static void *off_devptr(void *p)
{
    void *r = p;
#pragma omp target data use_device_ptr(r)
    {
        p = r;
    }
    return p;
}

/* Rows of a group held in memory: the pair columns at their capacity. */
static size_t alloc_rows(const cd_state *s, enum cd_field_group g)
{
    return cd_group_pair_rows(g) ? s->cap_pairs : cd_state_rows(s, g);
}

static void off_refresh_cols(cd_sim *sim, cd_off *o)
{
    cd_state d = sim->s;
    for (size_t f = 0; f < cd_n_fields; f++) {
        void **slot = cd_field_ptr(&d, &cd_fields[f]);
        if (o->host[f]) *slot = off_devptr(o->host[f]);
    }
    d.prim_arm = o->arm_host[0] ? off_devptr(o->arm_host[0]) : NULL;
    d.arm = off_devptr(o->arm_host[1]);
    d.step_inertia = o->arm_host[2] ? off_devptr(o->arm_host[2]) : NULL;
    d.inertia_iso = o->arm_host[3] ? off_devptr(o->arm_host[3]) : NULL;
    d.force = o->force_host[0] ? off_devptr(o->force_host[0]) : NULL;
    d.torque = o->force_host[1] ? off_devptr(o->force_host[1]) : NULL;
    o->dev = cd_sim_host_cols(&d);
}

/* The host's force and torque mapped (to the device: copied there) where
 * the step holds them (kernels/cols.h: an MPI rank, or from a start to its
 * first advance), or unmapped (nothing copied back: an MPI rank's sync
 * copies them, cd_off_force_from); the step's columns follow. */
void cd_off_force_map(cd_sim *sim, int map)
{
    cd_off *o = sim->backend_data;
    if (!o || !map == !o->force_host[0]) return;
    size_t bytes = sim->s.n_particles * sizeof(cd_vec3);
    void *cols[2] = {sim->s.force, sim->s.torque};
    for (int k = 0; k < 2; k++) {
        if (map) off_map(cols[k], bytes);
        else off_unmap(o->force_host[k], o->force_bytes);
        o->force_host[k] = map && bytes ? cols[k] : NULL;
    }
    o->force_bytes = map ? bytes : 0;
    off_refresh_cols(sim, o);
}

void cd_off_force_sums(cd_sim *sim, int map, cd_vec3 **F, cd_vec3 **T)
{
    size_t n = sim->s.n_particles;
    cd_vec3 *f = sim->s.force, *t = sim->s.torque;
    if (map) {
#pragma omp target enter data map(alloc : f [0:n], t [0:n])
        *F = off_devptr(f);
        *T = off_devptr(t);
        return;
    }
#pragma omp target update from(f [0:n], t [0:n])
#pragma omp target exit data map(release : f [0:n], t [0:n])
}

/* The device's force and torque into the host's columns (where mapped). */
void cd_off_force_from(cd_sim *sim)
{
    cd_off *o = sim->backend_data;
    for (int k = 0; o && k < 2; k++) cd_off_from(o->force_host[k], o->force_bytes);
}

/* Maps field f at its current host address and size (none for the
 * output-only columns, kernels/field_groups.h). */
static void off_map_field(cd_sim *sim, cd_off *o, size_t f)
{
    void *p = cd_fields[f].on_device ? *cd_field_ptr(&sim->s, &cd_fields[f]) : NULL;
    size_t bytes = alloc_rows(&sim->s, cd_fields[f].group) * cd_fields[f].elem_size;
    o->host[f] = p && bytes ? p : NULL;
    o->bytes[f] = o->host[f] ? bytes : 0;
    off_map(o->host[f], o->bytes[f]);
}

void cd_off_release(cd_sim *sim)
{
    cd_off *o = sim->backend_data;
    if (!o) return;
    for (size_t f = 0; f < cd_n_fields; f++) off_unmap(o->host[f], o->bytes[f]);
    for (int k = 0; k < CD_OFF_DERIVED; k++) off_unmap(o->arm_host[k], o->arm_bytes[k]);
    for (int k = 0; k < 2; k++) off_unmap(o->force_host[k], o->force_bytes);
    off_unmap(o->part, o->part_n * sizeof(double));
    free(o->part);
    free(o->host);
    free(o->bytes);
    free(o);
    sim->backend_data = NULL;
}

/* Is OMP_TARGET_OFFLOAD set to MANDATORY (any case)?  GCC 12's libgomp
 * falls back to the host without a device even then, so the check is ours. */
static int offload_mandatory(void)
{
    const char *v = getenv("OMP_TARGET_OFFLOAD"), *m = "MANDATORY";
    if (!v) return 0;
    for (; *v && *m; v++, m++)
        if ((*v | 0x20) != (*m | 0x20)) return 0;
    return !*v && !*m;
}

/* Copies every column of the host state to the device, once per run.  A
 * build for offload that finds no device runs on the host, unless
 * OMP_TARGET_OFFLOAD=MANDATORY: then the run fails rather than pass for a
 * device run. */
int cd_off_acquire(cd_sim *sim, char *err, size_t errlen)
{
    static int warned = 0;
    if (omp_get_num_devices() == 0) {
        if (offload_mandatory()) {
            snprintf(err, errlen,
                     "built for %s offload and OMP_TARGET_OFFLOAD=MANDATORY, but the OpenMP runtime "
                     "finds no offload device (docs/offload.md)",
                     CAPDEM_OFFLOAD_VARIANT);
            return -1;
        }
        if (!warned)
            fprintf(stderr, "capdem: built for %s offload but no offload device found: running on the host\n",
                    CAPDEM_OFFLOAD_VARIANT);
        warned = 1;
    }
    snprintf(err, errlen, "out of memory while mapping the state to the offload device");
    cd_off *o = calloc(1, sizeof *o);
    if (!o) return -1;
    sim->backend_data = o;
    o->host = calloc(cd_n_fields, sizeof *o->host);
    o->bytes = calloc(cd_n_fields, sizeof *o->bytes);
    o->part_n = sim->s.n_prims / CD_LOAD_CHUNK + 2; /* the chunks, then their total */
    o->part = calloc(o->part_n, sizeof(double));
    if (!o->host || !o->bytes || !o->part) {
        cd_off_release(sim);
        return -1;
    }
    for (size_t f = 0; f < cd_n_fields; f++) off_map_field(sim, o, f);
    /* the arms (cd_state_arms_derive), one spare row each: mapped even
     * when a state has none */
    int all = cd_state_arms_all(&sim->s); /* then no index column (kernels/cols.h) */
    o->arm_host[0] = all ? NULL : sim->s.prim_arm;
    o->arm_bytes[0] = all ? 0 : (sim->s.n_prims + 1) * sizeof(cd_int);
    o->arm_host[1] = sim->s.arm;
    o->arm_bytes[1] = (sim->s.n_arms + 1) * sizeof(cd_arm);
    /* the step's inertia (cd_state_arms_derive): one of the two */
    size_t n1 = sim->s.n_particles + 1;
    o->arm_host[2] = sim->s.step_inertia;
    o->arm_bytes[2] = sim->s.step_inertia ? n1 * sizeof(cd_vec3) : 0;
    o->arm_host[3] = sim->s.inertia_iso;
    o->arm_bytes[3] = sim->s.inertia_iso ? n1 * sizeof(cd_real) : 0;
    for (int k = 0; k < CD_OFF_DERIVED; k++) off_map(o->arm_host[k], o->arm_bytes[k]);
    off_map(o->part, o->part_n * sizeof(double));
    off_refresh_cols(sim, o);
    /* the host's force and torque for the first advance (a start), or for
     * the whole run on an MPI rank (kernels/cols.h) */
    cd_off_force_map(sim, 1);
    return 0;
}

/* Room for n pair rows: the host columns grow, and when they moved the
 * device copies are re-mapped (every old mapping goes before any new one:
 * a new block may reuse an old address).  Their contents are not carried:
 * the neighbour-list build keeps the history it needs before calling. */
static int off_reserve_pairs(cd_sim *sim, size_t n)
{
    cd_state *s = &sim->s;
    cd_off *o = sim->backend_data;
    if (cd_state_reserve_pairs(s, n)) return -1;
    int moved = 0;
    for (size_t f = 0; f < cd_n_fields; f++) {
        if (cd_fields[f].group != CD_GROUP_PAIR) continue;
        void *p = *cd_field_ptr(s, &cd_fields[f]);
        if (p != o->host[f] || s->cap_pairs * cd_fields[f].elem_size != o->bytes[f]) moved = 1;
    }
    if (!moved) return 0;
    for (size_t f = 0; f < cd_n_fields; f++)
        if (cd_fields[f].group == CD_GROUP_PAIR) {
            off_unmap(o->host[f], o->bytes[f]);
            o->host[f] = NULL;
            o->bytes[f] = 0;
        }
    for (size_t f = 0; f < cd_n_fields; f++)
        if (cd_fields[f].group == CD_GROUP_PAIR) off_map_field(sim, o, f);
    off_refresh_cols(sim, o);
    return 0;
}
#endif

int cd_sim_reserve_step_pairs(cd_sim *sim, size_t n)
{
#if CD_OFFLOAD
    if (sim->backend_data) return off_reserve_pairs(sim, n);
#endif
    return cd_state_reserve_pairs(&sim->s, n);
}

void *cd_sim_step_field(cd_sim *sim, size_t f)
{
#if CD_OFFLOAD
    cd_off *o = sim->backend_data;
    if (o) return o->host[f] ? off_devptr(o->host[f]) : NULL;
#endif
    return *cd_field_ptr(&sim->s, &cd_fields[f]);
}

void cd_sim_step_arg_copies(const cd_sim *sim, long long copies[2], long long bytes[2])
{
    copies[0] = copies[1] = 0;
    if (bytes) bytes[0] = bytes[1] = 0;
#if CD_OFFLOAD
    const cd_off *o = sim->backend_data;
    if (o) memcpy(copies, o->args_copies, sizeof o->args_copies);
    if (o && bytes) memcpy(bytes, o->args_bytes, sizeof o->args_bytes);
#else
    (void)sim;
#endif
}

/* Columns the step loops work on: device addresses in the offload variant,
 * the host columns otherwise. */
cd_cols cd_sim_step_cols(cd_sim *sim)
{
#if CD_OFFLOAD
    if (sim->backend_data) return ((cd_off *)sim->backend_data)->dev;
#endif
    cd_cols c = cd_sim_host_cols(&sim->s);
    /* the force and torque where the step holds them (kernels/cols.h): the
     * host's columns on an MPI rank, and until the first advance after a
     * start; null once the rows hold a force evaluation (summed again) */
    if (!cd_sim_keeps_force(sim) && sim->nb.force_summed) c.force = c.torque = NULL;
    return c;
}

/* The block for the state as it is now, padding zeroed (blocks are
 * compared byte by byte). */
void cd_step_args_fill(cd_sim *sim, cd_step_args *a)
{
    memset(a, 0, sizeof *a);
    a->c = cd_sim_step_cols(sim);
    a->d = sim->nb.d;
    a->order = cd_sim_step_order(sim);
    a->law = sim->p.law;
    a->wall_law = sim->p.wall_law;
    a->gravity = sim->p.gravity;
    a->dt = sim->p.dt;
    a->sin_parallel = sim->p.sin_parallel;
    a->limit2 = cd_bp_skin_limit2(sim->nb.skin);
    a->blend = sim->p.parallel_blend;
    a->dimension = sim->p.dimension;
    a->fixed_spheres = sim->p.fixed_spheres;
    a->n_walls = (cd_int)sim->s.n_walls;
    memcpy(a->walls, sim->s.walls, sim->s.n_walls * sizeof(cd_wall));
}

#if CD_OFFLOAD
/* [*first, *end): the bytes where x and y (n bytes) differ, in 8-byte
 * words; 0 when they are equal. */
static int differing_span(const void *x, const void *y, size_t n, size_t *first, size_t *end)
{
    const unsigned char *p = x, *q = y;
    size_t lo = 0, hi = n;
    while (lo < n && p[lo] == q[lo]) lo++;
    if (lo == n) return 0;
    while (hi > lo && p[hi - 1] == q[hi - 1]) hi--;
    *first = lo / 8 * 8;
    *end = (hi + 7) / 8 * 8 < n ? (hi + 7) / 8 * 8 : n;
    return 1;
}

/* What the device's block holds: 0 until the first block went out (one
 * block a process; a new start finds it as the last launch left it). */
static int args_sent = 0;

/* Copies bytes at host address p to the device: a span of a mapped
 * column or of the mapped global cd_step_block (the runtime finds either
 * in its table). */
static void off_to(void *p, size_t bytes)
{
    char *c = p;
    if (c && bytes) {
#pragma omp target update to(c [0:bytes])
    }
}

/* Sends bytes [lo, hi) of the host's cd_step_block to the device's. */
static void args_put(size_t lo, size_t hi) { off_to((char *)&cd_step_block + lo, hi - lo); }

/* The step's argument block on the device, brought up to date before a
 * launch: what differs from the last block sent goes out (all of it the
 * first time; otherwise the span of the head from its first to its last
 * changed word: the addresses a build or re-map moved, the two swapped
 * wall-candidate lists of every build, a change of the laws, another
 * state's block; the walls in use after they moved), nothing otherwise.
 * The host's cd_step_block is the copy of what the device holds. */
void cd_off_args_or_die(cd_sim *sim)
{
    cd_off *o = sim->backend_data;
    cd_step_args a;
    cd_step_args_fill(sim, &a);
    size_t head = offsetof(cd_step_args, walls), walls = sim->s.n_walls * sizeof(cd_wall), lo = 0, hi = head;
    if (!args_sent || differing_span(&a, &cd_step_block, head, &lo, &hi)) {
        memcpy((char *)&cd_step_block + lo, (const char *)&a + lo, hi - lo);
        args_put(lo, hi);
        o->args_copies[0]++;
        o->args_bytes[0] += (long long)(hi - lo);
    }
    if (walls && (!args_sent || memcmp(a.walls, cd_step_block.walls, walls))) {
        memcpy(cd_step_block.walls, a.walls, walls);
        args_put(head, head + walls);
        o->args_copies[1]++;
        o->args_bytes[1] += (long long)walls;
    }
    args_sent = 1;
}
#endif
