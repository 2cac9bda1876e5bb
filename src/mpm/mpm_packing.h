/* The disks of a capdem DEM run file, the start of the mpm set-up
 * `packing` (docs/mpm.md). */
#ifndef CD_MPM_PACKING_H
#define CD_MPM_PACKING_H
#include <stddef.h>

typedef struct {
    size_t n;           /* disks */
    double *x, *y, *r;  /* centres and radii [m] */
    long long snapshot; /* the snapshot read (the last committed one) */
} cd_mpm_packing;

/* Reads the centres and radii of the last committed snapshot of the run
 * file at path, which must hold spheres of a 2D run (every centre at one
 * z).  key_where names the config for messages.  0, or -1 with a message
 * naming the file, the key and what was expected. */
int cd_mpm_read_packing(const char *path, const char *key_where, cd_mpm_packing *pk, char *err, size_t errlen);
void cd_mpm_packing_free(cd_mpm_packing *pk);

#endif
