/* Hostile-file guards shared by every reader of run files (io_h5_read.c,
 * host/analyze_*.c, host/export_*.c): a dataset's number class, rank and
 * extents are checked against what the layout allows before anything is
 * allocated for it or read from it, and sizes derived from extents are
 * multiplied with overflow checks.  Implemented in io_h5_check.c. */
#ifndef CD_IO_H5_CHECK_H
#define CD_IO_H5_CHECK_H
#include <stddef.h>
#include <hdf5.h>

#define CD_H5_ANY_CLASS H5T_NO_CLASS

/* 0 when dataset d (dpath in file) holds values of class cls
 * (CD_H5_ANY_CLASS: any), has rank `rank` (0..3) and, for each k < rank,
 * lo[k] <= dims[k] <= hi[k] (lo NULL: no lower bound; hi NULL or hi[k] 0:
 * no upper bound); its extents go into dims (unused ones 1, dims may be
 * NULL).  Otherwise -1 and a message naming file and dpath in err. */
int cd_h5_check_dset(hid_t d, const char *file, const char *dpath, H5T_class_t cls, int rank, const hsize_t *lo,
                     const hsize_t *hi, hsize_t dims[3], char *err, size_t errlen);

/* 0 when the dataset (attr 0) or attribute (attr 1) obj holds exactly one
 * string (a scalar or a one-element space) of at most max_bytes when it is
 * fixed-length; otherwise -1 and a message naming file and what. */
int cd_h5_check_string(hid_t obj, int attr, const char *file, const char *what, size_t max_bytes, char *err,
                       size_t errlen);

/* 0 when attribute a (named what in file) holds exactly one integer or
 * floating-point number; otherwise -1 and a message naming file and what. */
int cd_h5_check_number_attr(hid_t a, const char *file, const char *what, char *err, size_t errlen);

/* 1 when what dataset d stores covers rows row0..row0+nrows-1 (clipped to
 * its extent; a scalar whole) as its extent and type imply, so HDF5 can
 * read them without running past a stored buffer; 0 otherwise (a
 * corrupted file).  Every reader calls it before H5Dread. */
int cdh5_storage_fits(hid_t d, hsize_t row0, hsize_t nrows);

/* *out = a * b * c; -1 (and *out 0) when the product overflows size_t. */
int cd_h5_mul(size_t *out, size_t a, size_t b, size_t c);

#endif
