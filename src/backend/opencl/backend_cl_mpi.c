/* The OpenCL backend's part of an MPI run (backend_cl_mpi.h; docs/mpi.md,
 * "GPUs"): the halo packed and unpacked on the device by the kernels of
 * kernels/cl/halo.cl (the items of kernels/halo_items.h, which the host
 * and the offload device run too), a wall load's F_n per primitive read
 * there, and the columns an observation sums brought back alone.  The MPI
 * messages are host buffers (no device-aware MPI assumed): per step a rank
 * reads its sent halo from the device and writes its received halo. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "backend/opencl/backend_cl.h"
#include "backend/opencl/backend_cl_mpi.h"
#include "halo_items.h"

#define F CD_CL_N_COLS /* first kernel argument after the columns */

static cd_cl *cl_of(const cd_sim *sim)
{
    return sim->backend == &cd_backend_opencl ? (cd_cl *)sim->backend_data : NULL;
}

int cd_cl_mpi_started(const cd_sim *sim) { return cl_of(sim) != NULL; }

void cd_cl_device_slot(const cd_sim *sim, char *name, size_t len, int *index, int *count)
{
    const cd_cl *cl = cl_of(sim);
    name[0] = 0;
    *index = *count = 0;
    if (!cl) return;
    if (clGetDeviceInfo(cl->device, CL_DEVICE_NAME, len, name, NULL) != CL_SUCCESS) name[0] = 0;
    name[len - 1] = 0;
    *index = cl->device_index;
    *count = cl->device_count;
}

/* A new buffer of bytes in *buf (the old one let go), filled from src
 * (NULL: left as it is) without waiting: src must stay until the queue
 * drains (the halo's lists live until the next migration, whose download
 * finishes the queue; the pack's read and the unpack's write wait before). */
static int put(cd_cl *cl, cl_mem *buf, size_t bytes, const void *src, const char *what)
{
    if (cl->status) return -1;
    if (*buf) clReleaseMemObject(*buf);
    *buf = cd_cl_buffer(cl, bytes + sizeof(cd_real), what);
    if (*buf && src && bytes)
        cd_cl_check(cl, clEnqueueWriteBuffer(cl->queue, *buf, CL_FALSE, 0, bytes, src, 0, NULL, NULL), what);
    return cl->status ? -1 : 0;
}

int cd_cl_halo_lists(cd_sim *sim, const int *send, int ns, const int *recv, int nr)
{
    cd_cl *cl = cl_of(sim);
    if (!cl) return -1;
    size_t row = CD_HALO_REALS * sizeof(cd_real);
    put(cl, &cl->halo_send_list, (size_t)ns * sizeof(cd_int), send, "uploading the halo's lists");
    put(cl, &cl->halo_recv_list, (size_t)nr * sizeof(cd_int), recv, "uploading the halo's lists");
    put(cl, &cl->halo_send, (size_t)ns * row, NULL, "allocating the halo's rows");
    put(cl, &cl->halo_recv, (size_t)nr * row, NULL, "allocating the halo's rows");
    cl->halo_ns = (size_t)ns;
    cl->halo_nr = (size_t)nr;
    return cl->status ? -1 : 0;
}

/* One of the halo kernels over n rows of list and buf. */
static void halo_run(cd_cl *cl, enum cd_cl_kernel k, size_t n, cl_mem list, cl_mem buf)
{
    cd_int rows = (cd_int)n;
    if (cl->cols_dirty) cd_cl_bind_cols(cl);
    cd_cl_arg(cl, k, F, sizeof rows, &rows);
    cd_cl_arg(cl, k, F + 1, sizeof list, &list);
    cd_cl_arg(cl, k, F + 2, sizeof buf, &buf);
    cd_cl_run(cl, k, n);
}

int cd_cl_halo_pack(cd_sim *sim, double *out)
{
    cd_cl *cl = cl_of(sim);
    if (!cl || !cl->halo_send) return -1;
    if (!cl->halo_ns) return 0;
    halo_run(cl, CD_CLK_HALO_PACK, cl->halo_ns, cl->halo_send_list, cl->halo_send);
    if (!cl->status)
        cd_cl_check(cl,
                    clEnqueueReadBuffer(cl->queue, cl->halo_send, CL_TRUE, 0,
                                        cl->halo_ns * CD_HALO_REALS * sizeof(cd_real), out, 0, NULL, NULL),
                    "reading the halo");
    return cl->status ? -1 : 0;
}

int cd_cl_halo_unpack(cd_sim *sim, const double *in)
{
    cd_cl *cl = cl_of(sim);
    if (!cl || !cl->halo_recv) return -1;
    if (!cl->halo_nr) return 0;
    /* (blocking: in is the MPI receive buffer, written again at the next refresh) */
    if (!cl->status)
        cd_cl_check(cl,
                    clEnqueueWriteBuffer(cl->queue, cl->halo_recv, CL_TRUE, 0,
                                         cl->halo_nr * CD_HALO_REALS * sizeof(cd_real), in, 0, NULL, NULL),
                    "writing the halo");
    halo_run(cl, CD_CLK_HALO_UNPACK, cl->halo_nr, cl->halo_recv_list, cl->halo_recv);
    return cl->status ? -1 : 0;
}

int cd_cl_wall_fn(cd_sim *sim, int w, double *fn, char *err, size_t errlen)
{
    cd_cl *cl = cl_of(sim);
    if (!cl) return 1;
    if (!cl->wall_out_valid) return 1; /* no forces since the start: the host's columns */
    size_t P = sim->s.n_prims;
    if (!P) return 0;
    if (!cl->wall_fn) cl->wall_fn = cd_cl_buffer(cl, P * sizeof(cd_real), "allocating a wall load");
    cd_int n = (cd_int)P, W = (cd_int)sim->s.n_walls, ww = w;
    if (cl->cols_dirty) cd_cl_bind_cols(cl);
    cd_cl_arg(cl, CD_CLK_WALL_FN, F, sizeof n, &n);
    cd_cl_arg(cl, CD_CLK_WALL_FN, F + 1, sizeof W, &W);
    cd_cl_arg(cl, CD_CLK_WALL_FN, F + 2, sizeof ww, &ww);
    cd_cl_arg(cl, CD_CLK_WALL_FN, F + 3, sizeof cl->wall_start, &cl->wall_start);
    cd_cl_arg(cl, CD_CLK_WALL_FN, F + 4, sizeof cl->wall_rows, &cl->wall_rows);
    cd_cl_arg(cl, CD_CLK_WALL_FN, F + 5, sizeof cl->wall_out, &cl->wall_out);
    cd_cl_arg(cl, CD_CLK_WALL_FN, F + 6, sizeof cl->wall_fn, &cl->wall_fn);
    cd_cl_run(cl, CD_CLK_WALL_FN, P);
    if (!cl->status)
        cd_cl_check(cl, clEnqueueReadBuffer(cl->queue, cl->wall_fn, CL_TRUE, 0, P * sizeof(cd_real), fn, 0, NULL, NULL),
                    "reading a wall load");
    if (!cl->status) return 0;
    cd_cl_report(cl, err, errlen);
    return -1;
}

int cd_cl_observe_cols(cd_sim *sim, char *err, size_t errlen)
{
    cd_cl *cl = cl_of(sim);
    if (!cl) return 0;
    /* (the pair rows' overlaps come from the primitives' stored ends:
     * prim_a, and the arms for end b, kernels/step_items.h) */
    static const size_t read[] = {
        offsetof(cd_state, position),    offsetof(cd_state, velocity),    offsetof(cd_state, angmom),
        offsetof(cd_state, orientation), offsetof(cd_state, prim_a),      offsetof(cd_state, pair_prim_i),
        offsetof(cd_state, pair_prim_j), offsetof(cd_state, pair_active), offsetof(cd_state, pair_shear)};
    if (!cd_cl_buffers_download_cols(cl, sim, read, sizeof read / sizeof read[0])) return 0;
    cd_cl_report(cl, err, errlen);
    return -1;
}
