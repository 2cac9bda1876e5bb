/* The bytes one time step moves, kernel by kernel, counted from the code of
 * kernels/step_items.h: what a bandwidth-bound device (a GPU) must move at
 * least, so that throughput can be held against the memory bandwidth
 * (docs/performance.md, "Bytes per step").
 *
 * The count is the compulsory traffic of each loop: every column element a
 * loop touches counts once per loop (a particle's pose read by its seven
 * primitives, or a primitive's ends read by its pair rows, counts once, as
 * it would from a cache with good locality), except the pair rows' force
 * and point, which the gather reads once from each of the row's two
 * particles.  Sizes: cd_real 8 B, cd_int 4 B, cd_vec3 24 B, cd_quat 32 B,
 * a pair row's flag (cd_flag) 1 B.
 * The amortised neighbour-list rebuild is not counted; what runs once per
 * call of the step (its first advance on omp, the blow-up check) is
 * divided by the steps of the call.  When a kernel of
 * step_items.h changes what it reads or writes, this table changes with
 * it. */
#include "bench_traffic.h"
#include "../kernels/broadphase.h"
#include "../kernels/step_items.h"

void cd_bench_traffic(const cd_sim *sim, double steps_per_call, cd_traffic out[CD_TRAFFIC_KERNELS])
{
    const cd_state *s = &sim->s;
    double N = (double)s->n_particles, P = (double)s->n_prims, R = (double)s->n_pairs;
    double A = 0, Aw = 0;                /* active pair rows, active wall rows */
    const double flag = sizeof(cd_flag); /* a pair row's contact flag (1 B; kernels/defs.h) */
    for (size_t k = 0; k < s->n_pairs; k++) A += s->pair_active[k] != 0;
    for (size_t r = 0; r < s->n_prims * s->n_walls; r++) Aw += s->wallc_active[r] != 0;
    /* wall candidates as the next build would choose them
     * (cd_item_wall_candidates), Ca of them of primitives with an arm; the
     * primitives with an arm (cd_arm, kernels/cols.h: all but a sphere's
     * ball) */
    double C = 0, Ca = 0, Arms = 0;
    for (size_t i = 0; i < s->n_prims; i++) {
        int arm = !cd_ends_at_origin(s->prim_a_body[i], s->prim_b_body[i]);
        Arms += arm;
        for (size_t w = 0; w < s->n_walls; w++) {
            int cand = cd_bp_wall_candidate(&s->walls[w], s->prim_a[i], s->prim_b[i], s->prim_radius[i], sim->nb.skin);
            C += cand;
            Ca += cand && arm;
        }
    }
    /* A primitive's ends in every loop that reads them: end a (24) and
     * its arm index (4; none where every primitive has an arm:
     * cd_prim_arm_of); an arm's end b (24) besides.  Its skin test reads
     * end a at the last build (24), an arm's b too (24); its world ends from
     * the pose: an arm's body-frame ends (48). */
    double idx = cd_state_arms_all(s) ? 0 : 4;
    /* The moments of inertia a pass reads: one value a particle where
     * every particle is isotropic (cd_inertia_of, kernels/cols.h: 16 B
     * less than the three counted below) */
    double iso = s->inertia_iso ? 16 : 0;
    double ends = P * (24 + idx) + Arms * 24, advance_prims = P * (idx + 24) + Arms * (48 + 24);
    double advance_writes = P * 24 + Arms * 24;
    /* the gather's part: per wall candidate its entry and flag (8), per
     * active wall row force and torque (48); per pair row two entries (8)
     * and, active or not (an inactive row adds its zero force: no branch),
     * its force and point from each side (2 x 48); where the gather skips
     * the rows out of contact (CD_GATHER_SKIPS_INACTIVE: the offload
     * variants) the row's flag from each side (2 x 1) and the force and
     * point of the active rows only */
    double gather_rows = C * 8 + Aw * 48 + R * 8 + (CD_GATHER_SKIPS_INACTIVE ? R * 2 * flag + A * 96 : R * 96);
    /* advance (cd_item_advance: kick, drift, primitive ends, skin test):
     * reads v, L, x (24 each), m (8), q (32), I (24) and per primitive
     * advance_prims, and the force and torque summed from the rows as the
     * gather sums them (the two CSR starts, 8, and gather_rows; one process
     * holds no force and torque between calls, kernels/cols.h: an MPI rank
     * reads its two columns, 48, instead); writes x, q, v, L, omega and the
     * primitives' world ends (advance_writes). */
    cd_traffic advance = {"advance", N * (136 - iso + 8) + advance_prims + gather_rows, N * 128 + advance_writes};
    /* CD_ENDS_FROM_POSE (the offload variants, step_items.h): no world ends
     * written and no primitive read by the skin test, which reads the pose
     * at the last build (64 B a particle) and its primitives only when its
     * bound does not settle it (near a rebuild: not counted); the passes
     * that use the ends read the particle's orientation (32) besides an
     * arm's body-frame ends (48) in place of the world ends (end a and an
     * arm's b). */
    if (CD_ENDS_FROM_POSE) advance = (cd_traffic){"advance", N * (136 - iso + 8 + 64) + gather_rows, N * 128};
    double pose = CD_ENDS_FROM_POSE ? 32 : 0; /* the orientation, per particle a pass reads */
    if (CD_ENDS_FROM_POSE) ends = P * idx + Arms * 48;
    /* cd_item_pair_force: every row its primitives and flag (8 + 1); the
     * primitives' particle (4), ends and radius (8); an active row its
     * history (24) and its particles' x, v, omega, m (80 per particle,
     * counted for every particle; with CD_ENDS_FROM_POSE the orientation
     * too); writes flag, history, point, force (1 + 72; the flag only when
     * it changes with CD_ENDS_FROM_POSE: 72), and F_n (8) at the last step
     * of a call only (the overlap is derived where it is read). */
    /* In a mixture the rows are visited kind by kind: 4 B a row read for
     * the visiting order (kernels/neighbor_items.h, pass 11). */
    double visit = cd_neighbors_pair_visit(sim, NULL) ? 4 : 0;
    out[0] = (cd_traffic){"pair_forces", R * (8 + flag + visit) + P * 12 + ends + A * 24 + N * (80 + pose),
                          A * (CD_ENDS_FROM_POSE ? 72 : 72 + flag) + A * 8 / steps_per_call};
    /* cd_item_wall_row over the wall candidates: per candidate its row,
     * its entry's flag and its primitive (particle, radius, end a, arm
     * index: 4 + 4 + 40; an arm's b: 24; an upper bound when a primitive
     * has several; with CD_ENDS_FROM_POSE the arm index, an arm's body-frame
     * ends (48) and the particle's x and q (56) in place of the world ends);
     * an active row its history (24) and the particle's x, v, omega, m
     * (80); writes flag, history, force, torque, overlap, F_n. */
    double wall_cand = CD_ENDS_FROM_POSE ? C * (20 + idx + 56) + Ca * 48 : C * (44 + idx) + Ca * 24;
    out[1] = (cd_traffic){"wall_forces", wall_cand + Aw * (24 + 80), Aw * 92};
    /* The gather, the second kick and the next step's advance in one item
     * (cd_item_gather_kick_advance; omp on host threads and offload, and
     * OpenCL's cd_cl_gather_kick in mode 2) reading the particle once: m,
     * x, the two CSR starts (40), v, L, q, I (104), its primitive range
     * (8), its primitives' as the advance (advance_prims); writes v, L, x,
     * omega (96), q (32) and the primitives' world ends (advance_writes);
     * no F, T (one process holds none between calls: kernels/cols.h; an
     * MPI rank writes them at its last step).  The advance of its own runs
     * once per call of the step. */
    out[2] =
        (cd_traffic){"gather_kick_advance", N * (152 - iso) + advance_prims + gather_rows, N * 128 + advance_writes};
    /* with CD_ENDS_FROM_POSE: the pose at the build (64) instead of the
     * primitive range and the primitives' ends (8 + advance_prims), no ends
     * written */
    if (CD_ENDS_FROM_POSE) out[2] = (cd_traffic){"gather_kick_advance", N * (144 - iso + 64) + gather_rows, N * 128};
    out[3] = (cd_traffic){"advance", advance.read / steps_per_call, advance.write / steps_per_call};
    /* the blow-up check at the end of each call of the step (x, v, L) */
    out[4] = (cd_traffic){"finite_check", N * 72 / steps_per_call, 0};
}

void cd_bench_row_kinds(const cd_sim *sim, const cd_int *visit, double kinds[3], double *mixed, double *groups)
{
    const cd_state *s = &sim->s;
    kinds[0] = kinds[1] = kinds[2] = *mixed = *groups = 0;
    int seen = 0; /* bit k: kind k in the current group */
    for (size_t v = 0; v < s->n_pairs; v++) {
        size_t k = visit ? (size_t)visit[v] : v;
        cd_prim_id i = s->pair_prim_i[k], j = s->pair_prim_j[k];
        int kind = 2 - cd_segseg_is_point(s->prim_a[i], s->prim_b[i]) - cd_segseg_is_point(s->prim_a[j], s->prim_b[j]);
        kinds[kind]++;
        seen |= 1 << kind;
        if ((v + 1) % CD_BENCH_WARP == 0 || v + 1 == s->n_pairs) {
            *groups += 1;
            *mixed += (seen & (seen - 1)) != 0; /* more than one bit */
            seen = 0;
        }
    }
}
