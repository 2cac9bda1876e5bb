/* The MPI decomposition where a rank's local state lives on a device
 * (docs/mpi.md, "GPUs"): the omp backend's offload variant or the OpenCL
 * backend.  Each rank takes one device, that of its node-local rank modulo
 * the node's devices; its local state lives there between migrations, and
 * the ghost refresh of every step packs the rows its neighbours need on the
 * device, brings only those to the host (the MPI messages are host
 * buffers: no CUDA-aware MPI is assumed), and unpacks the received ghosts
 * there (the items of kernels/halo_items.h on either).  A migration (at a
 * neighbour-list rebuild) copies the local state back, rebuilds it on the
 * host (src/mpi/mpi_migrate.c) and puts it on the device again.  On host
 * threads every function here says "host" and the refresh packs on the
 * host (src/mpi/mpi_halo.c).  The offload variant's functions are off_*,
 * the OpenCL backend's are in src/backend/opencl/backend_cl_mpi.c; the
 * cd_mpi_dev_* at the end choose. */
#include <stddef.h>
#include <stdio.h>
#include "mpi/mpi_halo.h"
#include "backend/omp/omp_loops.h"
#include "step_items.h"
#ifdef CAPDEM_HAVE_OPENCL
#include "backend/opencl/backend_cl_mpi.h"
#endif

/* Rows sent and received per refresh (the lists of plan_refresh, over all
 * ranks). */
static inline int total_rows(const int *count, const int *displ, int R) { return displ[R - 1] + count[R - 1]; }

/* This rank's rank among the ranks of its node (MPI_COMM_TYPE_SHARED).
 * Collective. */
static inline int node_local_rank(cd_mpi_ctx *x)
{
    MPI_Comm node;
    int local = 0;
    if (MPI_Comm_split_type(x->comm, MPI_COMM_TYPE_SHARED, 0, MPI_INFO_NULL, &node) == MPI_SUCCESS) {
        MPI_Comm_rank(node, &local);
        MPI_Comm_free(&node);
    }
    return local;
}

#if CD_OFFLOAD
/* Is the local state mapped on the device?  (The inner backend's data is
 * its mapping: src/backend/omp/step_omp.c.) */
static int on_device(const cd_mpi_ctx *x) { return x->loc.backend_data != NULL; }
static void off_free(cd_mpi_ctx *x);

/* The lists on the device, copied again after a migration re-planned them;
 * the buffers with them. */
static int dev_lists(cd_mpi_ctx *x, int ns, int nr)
{
    if (!x->dev_stale && x->dev_send_list) return 0;
    off_free(x);
    int G = CD_HALO_REALS;
    x->dev_send_list = cd_dev_alloc(((size_t)ns + 1) * sizeof(int));
    x->dev_recv_list = cd_dev_alloc(((size_t)nr + 1) * sizeof(int));
    x->dev_send_buf = cd_dev_alloc(((size_t)ns * G + 1) * sizeof(double));
    x->dev_recv_buf = cd_dev_alloc(((size_t)nr * G + 1) * sizeof(double));
    if (!x->dev_send_list || !x->dev_recv_list || !x->dev_send_buf || !x->dev_recv_buf) return -1;
    if ((ns && cd_dev_put(x->dev_send_list, x->send_list, (size_t)ns * sizeof(int))) ||
        (nr && cd_dev_put(x->dev_recv_list, x->recv_list, (size_t)nr * sizeof(int))))
        return -1;
    x->dev_stale = 0;
    return 0;
}

static int off_pack(cd_mpi_ctx *x)
{
    if (!on_device(x)) return 1;
    int ns = total_rows(x->send_count, x->send_displ, x->size), nr = total_rows(x->recv_count, x->recv_displ, x->size);
    if (dev_lists(x, ns, nr)) return -1;
    if (!ns) return 0;
    cd_cols c = cd_sim_step_cols(&x->loc);
    int *list = x->dev_send_list;
    double *buf = x->dev_send_buf;
    CD_WIDE_MIN
    CD_STEP_FOR(ns, firstprivate(c) is_device_ptr(list, buf))
    for (int e = 0; e < ns; e++) cd_item_ghost_io(c, list[e], buf + (size_t)e * CD_HALO_REALS, 1);
    return cd_dev_get(x->send_buf, buf, (size_t)ns * CD_HALO_REALS * sizeof(double)) ? -1 : 0;
}

static int off_unpack(cd_mpi_ctx *x)
{
    if (!on_device(x)) return 1;
    int nr = total_rows(x->recv_count, x->recv_displ, x->size);
    if (!nr) return 0;
    cd_cols c = cd_sim_step_cols(&x->loc);
    int *list = x->dev_recv_list;
    double *buf = x->dev_recv_buf;
    if (cd_dev_put(buf, x->recv_buf, (size_t)nr * CD_HALO_REALS * sizeof(double))) return -1;
    CD_WIDE_MIN
    CD_STEP_FOR(nr, firstprivate(c) is_device_ptr(list, buf))
    for (int e = 0; e < nr; e++) cd_item_ghost_io(c, list[e], buf + (size_t)e * CD_HALO_REALS, 0);
    return 0;
}

static void off_free(cd_mpi_ctx *x)
{
    cd_dev_free(x->dev_send_list);
    cd_dev_free(x->dev_recv_list);
    cd_dev_free(x->dev_send_buf);
    cd_dev_free(x->dev_recv_buf);
    x->dev_send_list = x->dev_recv_list = NULL;
    x->dev_send_buf = x->dev_recv_buf = NULL;
    x->dev_stale = 1;
}

static void off_choose(cd_mpi_ctx *x, char *desc, size_t len)
{
    int local = node_local_rank(x), devices = omp_get_num_devices();
    if (devices > 0) {
        omp_set_default_device(local % devices);
        snprintf(desc, len, "%s offload device %d of %d (node-local rank %d)", CAPDEM_OFFLOAD_VARIANT, local % devices,
                 devices, local);
    } else
        snprintf(desc, len, "host (built for %s offload, no device; node-local rank %d)", CAPDEM_OFFLOAD_VARIANT,
                 local);
}

static int off_wall_fn(cd_mpi_ctx *x, int w, double *fn)
{
    cd_sim *loc = &x->loc;
    if (!on_device(x) || !loc->nb.wall_out_valid || cd_step_memory_is_host()) return 1;
    size_t P = loc->s.n_prims;
    cd_int W = (cd_int)loc->s.n_walls;
    double *d = cd_dev_alloc((P + 1) * sizeof *d); /* [N] */
    if (!d) return -1;
    cd_cols c = cd_sim_step_cols(loc);
    const cd_int *prim_at = cd_sim_step_order(loc).prim_at, *ws = loc->nb.d.wall_start, *wr = loc->nb.d.wall_rows;
    const cd_wall_entry *wo = loc->nb.d.wall_out;
    CD_WIDE_MIN
    CD_STEP_FOR(P, firstprivate(c) is_device_ptr(d, prim_at, ws, wr, wo))
    for (size_t i = 0; i < P; i++) d[i] = cd_item_wall_fn(c, (cd_long)i, W, w, prim_at, ws, wr, wo);
    int rc = P && cd_dev_get(fn, d, P * sizeof *d) ? -1 : 0;
    cd_dev_free(d);
    return rc;
}

static int off_observe_cols(cd_mpi_ctx *x)
{
    cd_sim *loc = &x->loc;
    cd_state *s = &loc->s;
    /* (the local state is never reordered: reorder is off under MPI) */
    if (!on_device(x) || cd_step_memory_is_host() || loc->nb.reorder) return 1;
    /* (the pair rows' overlaps are derived from the pose: CD_ENDS_FROM_POSE,
     * kernels/observe_items.h) */
    const size_t read[] = {offsetof(cd_state, position),    offsetof(cd_state, velocity),
                           offsetof(cd_state, angmom),      offsetof(cd_state, orientation),
                           offsetof(cd_state, pair_prim_i), offsetof(cd_state, pair_prim_j),
                           offsetof(cd_state, pair_active), offsetof(cd_state, pair_shear)};
    for (size_t f = 0; f < cd_n_fields; f++)
        for (size_t k = 0; k < sizeof read / sizeof read[0]; k++) {
            const void *dev = cd_sim_step_field(loc, f);
            size_t bytes = cd_state_rows(s, cd_fields[f].group) * cd_fields[f].elem_size;
            if (cd_fields[f].offset == read[k] && dev && bytes &&
                cd_dev_get(*cd_field_ptr(s, &cd_fields[f]), dev, bytes))
                return -1;
        }
    /* the wall contacts kept per candidate into the host's rows, as the
     * inner backend's sync expands them */
    if (loc->nb.wall_out_valid) loc->nb.wall_out_pending = 1;
    return cd_neighbors_wall_out_to_host(loc) ? -1 : 0;
}

static int off_leave(cd_mpi_ctx *x, char *err, size_t errlen)
{
    if (!on_device(x)) return 0;
    if (x->inner->sync(&x->loc, err, errlen)) return -1;
    x->inner->stop(&x->loc);
    return 1;
}

static int off_return(cd_mpi_ctx *x, char *err, size_t errlen) { return cd_sim_step_remap(&x->loc, err, errlen); }
#else
static int off_pack(cd_mpi_ctx *x)
{
    (void)x;
    return 1;
}

static int off_unpack(cd_mpi_ctx *x)
{
    (void)x;
    return 1;
}

static void off_free(cd_mpi_ctx *x) { (void)x; }

static void off_choose(cd_mpi_ctx *x, char *desc, size_t len)
{
    (void)x;
    snprintf(desc, len, "host");
}

static int off_wall_fn(cd_mpi_ctx *x, int w, double *fn)
{
    (void)x;
    (void)w;
    (void)fn;
    return 1;
}

static int off_observe_cols(cd_mpi_ctx *x)
{
    (void)x;
    return 1;
}

static int off_leave(cd_mpi_ctx *x, char *err, size_t errlen)
{
    (void)x;
    (void)err;
    (void)errlen;
    return 0;
}

static int off_return(cd_mpi_ctx *x, char *err, size_t errlen)
{
    (void)x;
    (void)err;
    (void)errlen;
    return 0;
}
#endif

/* ---- the device the local state is on: OpenCL's or the offload variant's */

#ifdef CAPDEM_HAVE_OPENCL
static int on_cl(const cd_mpi_ctx *x) { return x->inner == &cd_backend_opencl; }

/* The halo's lists on the OpenCL device, after a start or a migration
 * planned them anew (and its buffers with them: a migration reloads the
 * device's state, cd_cl_reload, which lets them go). */
static int cl_lists(cd_mpi_ctx *x)
{
    if (!x->dev_stale) return 0;
    int ns = total_rows(x->send_count, x->send_displ, x->size), nr = total_rows(x->recv_count, x->recv_displ, x->size);
    if (cd_cl_halo_lists(&x->loc, x->send_list, ns, x->recv_list, nr)) return -1;
    x->dev_stale = 0;
    return 0;
}
#else
static int on_cl(const cd_mpi_ctx *x)
{
    (void)x;
    return 0;
}
#endif

int cd_mpi_dev_pack(cd_mpi_ctx *x)
{
#ifdef CAPDEM_HAVE_OPENCL
    if (on_cl(x)) return cl_lists(x) || cd_cl_halo_pack(&x->loc, x->send_buf) ? -1 : 0;
#endif
    return off_pack(x);
}

int cd_mpi_dev_unpack(cd_mpi_ctx *x)
{
#ifdef CAPDEM_HAVE_OPENCL
    if (on_cl(x)) return cd_cl_halo_unpack(&x->loc, x->recv_buf) ? -1 : 0;
#endif
    return off_unpack(x);
}

void cd_mpi_dev_free(cd_mpi_ctx *x)
{
    off_free(x);
    x->dev_stale = 1; /* (the OpenCL backend's halo buffers go with its state) */
}

void cd_mpi_dev_choose(cd_mpi_ctx *x, char *desc, size_t len)
{
    if (!on_cl(x)) {
        off_choose(x, desc, len);
        return;
    }
#ifdef CAPDEM_HAVE_OPENCL
    x->node_rank = node_local_rank(x);
    cd_cl_use_nth_device(x->node_rank); /* (taken at the start: cd_cl_open) */
    snprintf(desc, len, "the OpenCL device of node-local rank %d", x->node_rank);
#endif
}

int cd_mpi_dev_started(cd_mpi_ctx *x, char *desc, size_t len)
{
    if (!on_cl(x)) return 0;
#ifdef CAPDEM_HAVE_OPENCL
    char name[128];
    int index, count;
    cd_cl_device_slot(&x->loc, name, sizeof name, &index, &count);
    snprintf(desc, len, "OpenCL device %d of %d '%s' (node-local rank %d)", index, count, name, x->node_rank);
#endif
    (void)desc;
    (void)len;
    return 1;
}

int cd_mpi_dev_wall_fn(cd_mpi_ctx *x, int w, double *fn, char *err, size_t errlen)
{
#ifdef CAPDEM_HAVE_OPENCL
    if (on_cl(x)) return cd_cl_wall_fn(&x->loc, w, fn, err, errlen);
#endif
    int rc = off_wall_fn(x, w, fn);
    if (rc < 0) snprintf(err, errlen, "out of memory while summing the load on wall %d", w);
    return rc;
}

int cd_mpi_dev_observe_cols(cd_mpi_ctx *x, char *err, size_t errlen)
{
#ifdef CAPDEM_HAVE_OPENCL
    if (on_cl(x)) return cd_cl_observe_cols(&x->loc, err, errlen);
#endif
    int rc = off_observe_cols(x);
    if (rc < 0) snprintf(err, errlen, "out of memory while summing the observables");
    return rc;
}

int cd_mpi_dev_leave(cd_mpi_ctx *x, char *err, size_t errlen)
{
    if (on_cl(x)) return x->inner->sync(&x->loc, err, errlen) ? -1 : 1;
    return off_leave(x, err, errlen);
}

int cd_mpi_dev_return(cd_mpi_ctx *x, char *err, size_t errlen)
{
#ifdef CAPDEM_HAVE_OPENCL
    if (on_cl(x)) return cd_cl_reload(&x->loc, err, errlen);
#endif
    return off_return(x, err, errlen);
}
