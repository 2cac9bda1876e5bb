/* Private to `capdem export`: export_xdmf.c (the command and the .xmf
 * file), export_read.c (the run file: counts, clock, contact offsets and
 * the columns to show) and export_viz.c (the helper datasets under
 * /visualization).  The design and the /visualization layout are described
 * at the top of export_xdmf.c. */
#ifndef CAPDEM_EXPORT_INTERNAL_H
#define CAPDEM_EXPORT_INTERNAL_H
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
    long long bad_contacts; /* rows whose particle_i/j was -1 */
    int status;             /* exit status of the first failure */
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

#endif
