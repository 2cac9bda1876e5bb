/* One run file written by every MPI rank (docs/mpi.md, "One file"): the
 * writer's file opened through HDF5's MPI-IO driver (the openmpi flavour
 * of HDF5, linked by the MPI build), every metadata call made by every
 * rank alike, and each dataset write collective: a snapshot's particle,
 * primitive, contact and wall-contact rows written by the rank that owns
 * the particle, everything else (clocks, walls, offsets, time series,
 * header) by rank 0, into the serial layout.  The POSIX side of the
 * output's safety (locks, the exclusive create, the file written aside
 * and renamed, the deleted-file check) is done by rank 0 and its outcome
 * shared.  Without parallel HDF5 (the default build) nothing here is
 * on, and the writer is the serial one, unchanged. */
#define _GNU_SOURCE /* flock */
#include "io/io_h5.h"
#include "io/io_h5_internal.h"
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/file.h>

/* Datasets that HDF5 gives their chunks as they are written (the serial
 * writer's: allocation time "incremental") cannot be appended to from
 * several ranks by HDF5 1.10: its collective write of checksummed chunks
 * reads a chunk that a rank fills only in part, and a chunk not yet
 * written has no address (H5D__filtered_collective_chunk_entry_io: "addr
 * overflow"), so one rank fails while the others wait in the collective
 * (a resume of a serially written file on 2 ranks hung).  Files created
 * through MPI-IO get every chunk when a dataset is extended (allocation
 * time "early", HDF5's rule for parallel files) and are not affected. */
static herr_t incremental_one(hid_t loc, const char *name, const H5O_info_t *info, void *data)
{
    int *found = data;
    if (info->type != H5O_TYPE_DATASET) return 0;
    hid_t d = H5Dopen2(loc, name, H5P_DEFAULT), dcpl = d < 0 ? -1 : H5Dget_create_plist(d);
    H5D_alloc_time_t at = H5D_ALLOC_TIME_EARLY;
    if (dcpl < 0 || H5Pget_alloc_time(dcpl, &at) < 0) *found = -1;
    else if (H5Pget_layout(dcpl) == H5D_CHUNKED && at == H5D_ALLOC_TIME_INCR) *found = 1;
    if (dcpl >= 0) H5Pclose(dcpl);
    if (d >= 0) H5Dclose(d);
    return *found ? 1 : 0;
}

int cdh5_par_appendable(const char *path, char *err, size_t errlen)
{
    cdh5_quiet q;
    cdh5_quiet_begin(&q);
    int found = 0;
    hid_t f = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
    if (f < 0 || H5Ovisit2(f, H5_INDEX_NAME, H5_ITER_NATIVE, incremental_one, &found, H5O_INFO_BASIC) < 0)
        found = found ? found : -1;
    if (f >= 0) H5Fclose(f);
    cdh5_quiet_end(&q);
    if (found < 0) snprintf(err, errlen, "%s: cannot read its datasets' layout", path);
    else if (found)
        snprintf(err, errlen,
                 "%s was written by one process (the serial writer: one process, or mpi.output = rank0), whose "
                 "datasets get their chunks as they are written; several MPI ranks cannot append to it with this "
                 "HDF5 (1.10): resume it with mpi.output: rank0 in the config (it may change on --resume), or "
                 "with one process (docs/mpi.md, \"Resume\")",
                 path);
    return found ? -1 : 0;
}

int cd_output_check_appendable(const char *path, char *err, size_t errlen)
{
    if (errlen) err[0] = 0;
    if (!cdh5_par_on()) return 0;
    return cdh5_par_max(cdh5_par_root() && cdh5_par_appendable(path, err, errlen) < 0) ? -1 : 0;
}

#if defined(CAPDEM_MPI) && CAPDEM_MPI && defined(H5_HAVE_PARALLEL)

static struct {
    int on;
    MPI_Comm comm;
    int rank;
    unsigned long long bytes; /* data bytes this rank wrote into run files */
} par;

unsigned long long cd_output_bytes_written(void) { return par.bytes; }

int cd_output_use_mpi(const void *comm)
{
    par.on = 0;
    if (!comm) return 0;
    par.comm = *(const MPI_Comm *)comm;
    MPI_Comm_rank(par.comm, &par.rank);
    int size = 1;
    MPI_Comm_size(par.comm, &size);
    par.on = size > 1;
    return 0;
}

int cdh5_par_on(void) { return par.on; }

int cdh5_par_root(void) { return !par.on || par.rank == 0; }

hid_t cdh5_par_fapl(void)
{
    hid_t fapl = H5Pcreate(H5P_FILE_ACCESS);
    if (fapl < 0) return H5I_INVALID_HID;
    /* the strong close degree of cdh5_fapl; MPI_INFO_NULL: the MPI
     * library's own hints */
    if (H5Pset_fapl_mpio(fapl, par.comm, MPI_INFO_NULL) < 0 || H5Pset_fclose_degree(fapl, H5F_CLOSE_STRONG) < 0) {
        H5Pclose(fapl);
        return H5I_INVALID_HID;
    }
    return fapl;
}

int cdh5_par_max(int v)
{
    int all = v;
    if (par.on) MPI_Allreduce(&v, &all, 1, MPI_INT, MPI_MAX, par.comm);
    return all;
}

void cdh5_par_bcast(void *buf, size_t bytes)
{
    if (par.on) MPI_Bcast(buf, (int)bytes, MPI_BYTE, 0, par.comm);
}

void cdh5_par_lock(int fd)
{
    /* HDF5's MPI-IO driver takes no flock of its own: rank 0 holds the
     * exclusive one the serial driver holds, so that HDF5 readers (h5py,
     * h5dump) and other writers find the file in use, as they do a serial
     * run's (the mark of cdh5_mark is held as well) */
    if (par.on && par.rank == 0 && fd >= 0) (void)flock(fd, LOCK_EX | LOCK_NB);
}

/* Adds the runs of memory rows r < n_map with map[r] >= 0 (memory row r
 * to row map[r] of the block start..start+cnt of the file, both along
 * dimension dim; map ascending where >= 0) to the selections fs and ms
 * (both none before): one hyperslab per run of rows consecutive in both. */
static herr_t select_runs(hid_t fs, hid_t ms, int rank, const hsize_t *start, const hsize_t *cnt, int dim,
                          const long long *map, size_t n_map)
{
    herr_t e = 0;
    int first = 1;
    for (size_t r = 0; r < n_map && e >= 0;) {
        if (map[r] < 0) {
            r++;
            continue;
        }
        size_t r0 = r;
        for (r++; r < n_map && map[r] == map[r - 1] + 1;) r++;
        hsize_t fstart[3] = {0, 0, 0}, mstart[3] = {0, 0, 0}, c[3] = {1, 1, 1};
        for (int k = 0; k < rank; k++) {
            fstart[k] = start[k];
            c[k] = cnt[k];
        }
        fstart[dim] += (hsize_t)map[r0];
        mstart[dim] = r0;
        c[dim] = r - r0;
        H5S_seloper_t op = first ? H5S_SELECT_SET : H5S_SELECT_OR;
        e = H5Sselect_hyperslab(fs, op, fstart, NULL, c, NULL);
        if (e >= 0) e = H5Sselect_hyperslab(ms, op, mstart, NULL, c, NULL);
        first = 0;
    }
    return e;
}

herr_t cdh5_par_write(const cd_output *o, hid_t d, hid_t mtype, hid_t ms, hid_t fs, int rank, const hsize_t *start,
                      const hsize_t *cnt, const void *buf)
{
    herr_t e = H5Sselect_none(fs);
    if (e >= 0) e = H5Sselect_none(ms);
    if (e >= 0 && o->row_map && rank > o->mask_dim)
        e = select_runs(fs, ms, rank, start, cnt, o->mask_dim, o->row_map, o->map_rows);
    else if (e >= 0 && par.rank == 0 && rank > 0) {
        e = H5Sselect_hyperslab(fs, H5S_SELECT_SET, start, NULL, cnt, NULL);
        if (e >= 0) e = H5Sselect_all(ms);
    } else if (e >= 0 && par.rank == 0) { /* a scalar */
        e = H5Sselect_all(fs);
        if (e >= 0) e = H5Sselect_all(ms);
    }
    /* HDF5 writes filtered (checksummed) chunks collectively only, and only
     * without a type conversion on the way: a memory type that differs from
     * the file's (the padded cd_wall) is converted here first */
    hid_t ftype = H5Dget_type(d), dxpl = H5Pcreate(H5P_DATASET_XFER);
    void *conv = NULL;
    htri_t same = ftype < 0 ? -1 : H5Tequal(mtype, ftype);
    if (same < 0 || dxpl < 0 || H5Pset_dxpl_mpio(dxpl, H5FD_MPIO_COLLECTIVE) < 0) e = -1;
    if (e >= 0 && !same) {
        hssize_t n = H5Sget_simple_extent_npoints(ms);
        size_t msize = H5Tget_size(mtype), fsize = H5Tget_size(ftype), big = msize > fsize ? msize : fsize;
        conv = n < 0 ? NULL : malloc((size_t)(n ? n : 1) * big);
        void *bkg = n < 0 ? NULL : calloc((size_t)(n ? n : 1), big); /* (a compound's conversion wants one) */
        if (!conv || !bkg) e = -1;
        else {
            memcpy(conv, buf, (size_t)n * msize);
            e = H5Tconvert(mtype, ftype, (size_t)n, conv, bkg, H5P_DEFAULT);
            mtype = ftype;
            buf = conv;
        }
        free(bkg);
    }
    /* collective: every rank calls, those with nothing to write with none selected */
    static const double none[1]; /* (a rank without rows may have no column: HDF5 wants an address) */
    if (e >= 0) e = H5Dwrite(d, mtype, ms, fs, dxpl, buf ? buf : none);
    hssize_t sel = e < 0 ? 0 : H5Sget_select_npoints(ms);
    if (sel > 0) par.bytes += (unsigned long long)sel * H5Tget_size(mtype);
    free(conv);
    if (ftype >= 0) H5Tclose(ftype);
    if (dxpl >= 0) H5Pclose(dxpl);
    return e;
}

#else

int cd_output_use_mpi(const void *comm)
{
    /* a build without parallel HDF5 has one writer */
    return comm ? -1 : 0;
}

unsigned long long cd_output_bytes_written(void) { return 0; }
int cdh5_par_on(void) { return 0; }
int cdh5_par_root(void) { return 1; }
hid_t cdh5_par_fapl(void) { return H5I_INVALID_HID; }
int cdh5_par_max(int v) { return v; }
void cdh5_par_bcast(void *buf, size_t bytes)
{
    (void)buf;
    (void)bytes;
}
void cdh5_par_lock(int fd) { (void)fd; }
herr_t cdh5_par_write(const cd_output *o, hid_t d, hid_t mtype, hid_t ms, hid_t fs, int rank, const hsize_t *start,
                      const hsize_t *cnt, const void *buf)
{
    (void)o;
    (void)rank;
    (void)start;
    (void)cnt;
    return H5Dwrite(d, mtype, ms, fs, H5P_DEFAULT, buf);
}

#endif
