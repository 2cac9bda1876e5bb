/* Private to `capdem export`: export_xdmf.c (the command and the .xmf
 * file), export_read.c (the run file: counts, clock, contact offsets and
 * the columns to show) and export_viz.c (the helper datasets under
 * /visualization).  The design and the /visualization layout are described
 * at the top of export_xdmf.c. */
#ifndef CAPDEM_EXPORT_INTERNAL_H
#define CAPDEM_EXPORT_INTERNAL_H
#include <stdio.h>
#include <hdf5.h>

#define CD_EXPORT_LAYOUT     1
#define CD_EXPORT_MAX_FIELDS 64
#define CD_EXPORT_MAX_COMP   16
#define CD_EXPORT_PATH       4200 /* > PATH_MAX: room for a resolved path and a suffix */

enum { CD_EXPORT_OK = 0, CD_EXPORT_FAIL = 1, CD_EXPORT_BAD_INPUT = 2 };

typedef struct {
    char name[96]; /* attribute name shown in ParaView */
    char src[300]; /* dataset in the run file */
    int rank;
    hsize_t dims[3];
    int ncomp;           /* values per row: product of the dims after the row axis/axes */
    char number_type[8]; /* XDMF NumberType: Float, Int, UInt */
    int precision;       /* bytes */
} cd_export_field;

typedef struct {
    const char *path;             /* run file as given */
    hid_t f;                      /* run file */
    hid_t vf;                     /* file holding /visualization: f or the sidecar */
    hid_t viz;                    /* /visualization */
    char vds_src[CD_EXPORT_PATH]; /* run file as the virtual datasets name it */
    char h5_ref[CD_EXPORT_PATH];  /* run file as the .xmf names it */
    char viz_ref[CD_EXPORT_PATH]; /* file holding /visualization as the .xmf names it */
    int S;                        /* complete snapshots */
    hsize_t N, P;
    long long *off; /* S + 1 contact row offsets */
    long long *step;
    double *time;
    cd_export_field pt[CD_EXPORT_MAX_FIELDS];
    int npt; /* per snapshot, per particle */
    cd_export_field pf[CD_EXPORT_MAX_FIELDS];
    int npf; /* fixed, per particle */
    cd_export_field cf[CD_EXPORT_MAX_FIELDS];
    int ncf; /* per contact row */
    cd_export_field position, prim_a, prim_b, prim_radius, prim_particle;
    long long bad_contacts;    /* rows whose particle_i/j was -1 */
    struct cd_export_mpm *mpm; /* a run file of solver mpm: its datasets (export_mpm.c); NULL otherwise */
    int status;                /* exit status of the first failure */
    char err[1536];
} cd_export_ctx;

/* Records the first failure (later ones are usually consequences). */
int cd_export_fail(cd_export_ctx *x, int status, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;
/* HDF5's innermost message into buf (256 bytes), for a failure's "why". */
const char *cd_export_h5_reason(char *buf);

/* export_read.c: reads the counts, the clock and the contact offsets. */
int cd_export_read_run(cd_export_ctx *x);
/* export_read.c: sorts the run's datasets into the per-snapshot, fixed and
 * per-contact column lists; checks the per-arm datasets. */
int cd_export_discover(cd_export_ctx *x);
/* export_viz.c: creates or updates /visualization for every snapshot. */
int cd_export_helpers(cd_export_ctx *x);

/* ---- shared by the DEM and the mpm exports ---- */

/* One block of a virtual dataset: the source's hyperslab (start, count) goes
 * to the virtual hyperslab (vstart, vcount); both hold the same number of
 * elements.  Elements no block maps read as 0 (the fill value). */
typedef struct {
    const cd_export_field *src;
    hsize_t start[3], count[3];
    hsize_t vstart[3], vcount[3];
} cd_export_block;
/* export_viz.c: the virtual dataset parent/name of shape dims from the
 * blocks (kept when one of that shape is there).  0, or -1 with x failed. */
int cd_export_vds(cd_export_ctx *x, hid_t parent, const char *name, int rank, const hsize_t *dims, int nblock,
                  const cd_export_block *blocks);
/* export_viz.c: real int32 / float64 helper datasets (overwritten in place
 * when one of that shape is there), with a unit attribute ("1" for ints). */
int cd_export_ints(cd_export_ctx *x, hid_t parent, const char *name, int rank, const hsize_t *dims, const int *v);
int cd_export_doubles(cd_export_ctx *x, hid_t parent, const char *name, int rank, const hsize_t *dims, const double *v,
                      const char *unit);
/* Opens parent/name when it is a dataset of the given layout and shape;
 * otherwise removes whatever is there and returns 0. */
/* export_viz.c: /visualization/snapshots made, and its groups that are not
 * a snapshot 0 .. S-1 of the run removed (a resume cut them away). */
int cd_export_snapshots_group(cd_export_ctx *x);
/* export_read.c: shape and XDMF number type of dataset path; -1 when it is
 * missing or not a plain integer or floating-point array of rank 1..3. */
int cd_export_describe(hid_t f, const char *path, cd_export_field *fl);
hid_t cd_export_reuse(hid_t parent, const char *name, H5D_layout_t layout, int rank, const hsize_t *dims);
int cd_export_read_attr_ll(hid_t loc, const char *name, long long *v, int n);
/* export_viz.c: opens /visualization when its int64 attributes names[0..n-1]
 * hold want[], else makes a fresh one with them, the string attributes
 * solver (when not NULL) and about.  0, or -1 with x failed. */
int cd_export_open_viz_with(cd_export_ctx *x, int n, const char *const *names, const long long *want,
                            const char *solver, const char *about);
void cd_export_write_attr(hid_t loc, const char *name, hid_t ftype, hid_t mtype, int n, const void *v);

/* export_xdmf.c: the .xmf's pieces.  A <DataItem> naming file:path of
 * shape (rows, ncomp); an <Attribute> of field fl's type and shape; a
 * <Time>; a <Topology> of n cells of nodes points each from the int32
 * helper cells; the grid's time of snapshot k. */
void cd_export_xml_item(FILE *o, const char *indent, const char *file, const char *path, hsize_t rows, int ncomp,
                        const char *number_type, int precision);
void cd_export_xml_attr(FILE *o, const char *name, const char *center, const char *file, const char *path, hsize_t rows,
                        const cd_export_field *fl);
void cd_export_xml_time(FILE *o, const cd_export_ctx *x, int k);
void cd_export_xml_topology(FILE *o, const cd_export_ctx *x, const char *type, int nodes, hsize_t n, const char *cells);
void cd_export_xml_geometry(FILE *o, const cd_export_ctx *x, int k, const char *points, hsize_t n);
/* Writes out through a new file beside it (mkstemp), renamed over out at
 * the end: body writes the <Domain>'s grids.  0, or -1 with x failed. */
int cd_export_write_xml_with(cd_export_ctx *x, const char *out, const char *comment,
                             void (*body)(FILE *, const cd_export_ctx *));

/* export_mpm.c: the export of a run file of solver mpm (docs/visualization.md,
 * "Material point runs"): reads it and writes /visualization; then the .xmf. */
int cd_export_mpm_helpers(cd_export_ctx *x);
int cd_export_mpm_write_xml(cd_export_ctx *x, const char *out);
void cd_export_mpm_free(cd_export_ctx *x);

#endif
