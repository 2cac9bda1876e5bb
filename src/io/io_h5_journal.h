/* Atomic commits for run files: an HDF5 file driver ("capdem-journal")
 * that keeps the bytes of the last commit untouched until the next one.
 *
 * Why: HDF5 (without SWMR) rewrites metadata and partly filled chunks in
 * place while it writes, so a run killed between two flushes could leave
 * rows committed earlier unreadable.  This driver writes new bytes (past
 * the committed end of allocation) straight to the file but holds every
 * write into the committed part in memory; cdh5_commit() then writes
 * those held writes into a redo journal beside the file (<file>-journal,
 * checksummed), syncs it, applies them in place and empties the journal.
 * A kill at any moment leaves either the last commit (the file as it is,
 * readable by any HDF5 tool) or a complete journal whose replay gives the
 * new commit; capdem's readers replay it in memory, a writer that opens
 * the file replays it in place.  Design and proof: docs/output.md,
 * "Crash safety". */
#ifndef CD_IO_H5_JOURNAL_H
#define CD_IO_H5_JOURNAL_H
#include <stddef.h>
#include <hdf5.h>

/* A file access property list for run files (capdem's driver, strong close
 * degree); the caller closes it.  H5I_INVALID_HID when HDF5 refuses. */
hid_t cdh5_fapl(void);

/* Makes everything HDF5 holds for the file the new commit: H5Fflush, then
 * the journaled write of what was held back.  0, or -1 with a message. */
int cdh5_commit(hid_t file, const char *path, char *err, size_t errlen);

/* What H5Fclose does with writes made after the last commit: commit them
 * (the default, as a plain HDF5 close would) or drop them, so that a file
 * whose writing failed keeps exactly its last commit. */
void cdh5_drop_on_close(hid_t file);

/* HDF5's end of allocation of a file open through this driver (H5Fget_eoa
 * wants a SWMR driver); -1 for other drivers. */
int cdh5_journal_eoa(hid_t file, haddr_t *eoa);

/* The main file was renamed to new_path: the journal follows it. */
int cdh5_journal_follow(hid_t file, const char *new_path, char *err, size_t errlen);

/* Brings a file left by a killed writer to its last commit in place
 * (replays a complete journal, removes it): 1 when something was replayed,
 * 0 when nothing was needed, -1 with a message. */
int cdh5_recover(const char *path, char *err, size_t errlen);

/* Tests only: the n-th write, truncation or sync of a file or journal from
 * now on writes half of its bytes and kills the process (n <= 0: never);
 * cdh5_io_count() counts them all since the start. */
void cdh5_fault_after(long long n);
long long cdh5_io_count(void);

#endif
