/* Where a run file may be written: checks that an output is not an input,
 * not someone else's running output and not replaced before the new file
 * holds a snapshot; the locks and the write-aside-then-rename of
 * CD_OUTPUT_REPLACE.  Rules: docs/output.md, "Output safety". */
#define _GNU_SOURCE /* flock, F_OFD_SETLK */
#include "io/io_h5.h"
#include "io/io_h5_internal.h"
#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

/* capdem's mark on a file it writes: a read lock over the whole file held
 * by the open file description (F_OFD_SETLK), taken right after the file is
 * created or opened and kept until it is closed.  It does not conflict with
 * the flock HDF5 takes on its own descriptor (flock and fcntl locks are
 * separate on Linux), so it is held whether or not HDF5 locks
 * (HDF5_USE_FILE_LOCKING), and cdh5_target_lock finds it with F_OFD_GETLK. */
#ifdef F_OFD_SETLK
#define CD_SETLK F_OFD_SETLK
#define CD_GETLK F_OFD_GETLK
#else
#define CD_SETLK F_SETLK
#define CD_GETLK F_GETLK
#endif

int cdh5_mark(int fd)
{
    struct flock l;
    memset(&l, 0, sizeof l);
    l.l_type = F_RDLCK;
    l.l_whence = SEEK_SET;
    return fcntl(fd, CD_SETLK, &l);
}

/* Whether another open file (another capdem) holds its mark on fd's file. */
static int marked(int fd)
{
    struct flock l;
    memset(&l, 0, sizeof l);
    l.l_type = F_WRLCK;
    l.l_whence = SEEK_SET;
    return fcntl(fd, CD_GETLK, &l) == 0 && l.l_type != F_UNLCK;
}

int cdh5_target_lock(const char *path, unsigned long long *dev, unsigned long long *ino, char *err, size_t errlen)
{
    int fd = open(path, O_RDONLY | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) {
        if (errno == ENOENT) return -2;
        snprintf(err, errlen, "%s: cannot open it to check it: %s", path, strerror(errno));
        return -1;
    }
    struct stat st, now;
    if (fstat(fd, &st) < 0 || !S_ISREG(st.st_mode)) {
        snprintf(err, errlen, "%s is not a regular file (a run file must be one)", path);
        close(fd);
        return -1;
    }
    if (flock(fd, LOCK_EX | LOCK_NB) < 0) {
        int e = errno;
        if (e == EWOULDBLOCK || e == EAGAIN) {
            snprintf(err, errlen,
                     "%s is in use by another process (a running capdem, or another program that has "
                     "it open through HDF5): refused, the file is left as it is",
                     path);
            close(fd);
            return -1;
        }
        /* file systems without flock: HDF5 goes on without a lock as well ("best effort") */
        if (e != ENOLCK && e != EINVAL && e != ENOSYS && e != EOPNOTSUPP) {
            snprintf(err, errlen, "%s: cannot lock it: %s", path, strerror(e));
            close(fd);
            return -1;
        }
    }
    if (marked(fd)) {
        snprintf(err, errlen, "%s is in use by another process (a running capdem): refused, the file is left as it is",
                 path);
        close(fd);
        return -1;
    }
    /* the name must still lead to the file locked (not to one renamed over it meanwhile) */
    if (stat(path, &now) < 0 || now.st_dev != st.st_dev || now.st_ino != st.st_ino) {
        snprintf(err, errlen, "%s was replaced by another process while it was being checked: refused", path);
        close(fd);
        return -1;
    }
    *dev = (unsigned long long)st.st_dev;
    *ino = (unsigned long long)st.st_ino;
    return fd;
}

/* Folder part of path ("." when none) into buf. */
static void folder_of(const char *path, char *buf, size_t len)
{
    const char *slash = strrchr(path, '/');
    if (!slash) snprintf(buf, len, ".");
    else if (slash == path) snprintf(buf, len, "/");
    else snprintf(buf, len, "%.*s", (int)(slash - path), path);
}

int cdh5_target_aside(const char *path, char *tmp, size_t len, char *err, size_t errlen, int *fd_out)
{
    char dir[1024];
    folder_of(path, dir, sizeof dir);
    const char *slash = strrchr(path, '/'), *base = slash ? slash + 1 : path;
    if ((size_t)snprintf(tmp, len, "%s/.%s.XXXXXX", dir, base) >= len) {
        snprintf(err, errlen, "%s: path too long", path);
        return -1;
    }
    int fd = mkstemp(tmp);
    if (fd < 0) {
        snprintf(err, errlen, "%s: cannot create a file beside it to write the new run into (%s): %s", path, tmp,
                 strerror(errno));
        tmp[0] = 0;
        return -1;
    }
    mode_t mask = umask(0); /* mkstemp gives 0600; a plain create 0666 & ~umask */
    umask(mask);
    fchmod(fd, 0666 & ~mask);
    cdh5_mark(fd);
    *fd_out = fd;
    return 0;
}

static int publish(cd_output *o);

/* Parallel output: rank 0 renames, every rank learns how it went. */
int cdh5_target_publish(cd_output *o)
{
    int rc = cdh5_par_root() ? publish(o) : 0;
    if (cdh5_par_max(rc != 0)) return -1;
    o->tmp_path[0] = 0;
    return 0;
}

static int publish(cd_output *o)
{
    struct stat now;
    if (stat(o->path, &now) == 0 &&
        (o->old_fd < 0 || (unsigned long long)now.st_dev != o->old_dev || (unsigned long long)now.st_ino != o->old_ino))
        return FAIL("%s was replaced by another process during the run; this run's file stays at %s", o->path,
                    o->tmp_path);
    if (rename(o->tmp_path, o->path) < 0)
        return FAIL("%s: cannot rename %s to it: %s; this run's file stays at %s", o->path, o->tmp_path,
                    strerror(errno), o->tmp_path);
    o->tmp_path[0] = 0;
    /* (MPI-IO has no journal; asking would be collective) */
    if (!cdh5_par_on() && cdh5_journal_follow(o->file, o->path, o->err, sizeof o->err)) return cdh5_report(o);
    if (o->old_fd >= 0) close(o->old_fd);
    o->old_fd = -1;
    return 0;
}

int cd_output_check_target(const char *path, enum cd_output_mode how, const char *const *inputs, int n_inputs,
                           char *err, size_t errlen)
{
    struct stat st;
    if (!path || !*path) {
        snprintf(err, errlen, "the output path is empty");
        return -1;
    }
    if (stat(path, &st) < 0) {
        if (errno != ENOENT) {
            snprintf(err, errlen, "%s: %s", path, strerror(errno));
            return -1;
        }
        if (how == CD_OUTPUT_RESUME) {
            snprintf(err, errlen, "%s: no such run file", path);
            return -1;
        }
        char dir[1024];
        struct stat ds;
        folder_of(path, dir, sizeof dir);
        if (stat(dir, &ds) < 0 || !S_ISDIR(ds.st_mode)) {
            snprintf(err, errlen, "%s: folder %s does not exist", path, dir);
            return -1;
        }
        return 0;
    }
    for (int i = 0; i < n_inputs; i++) {
        struct stat is;
        if (inputs[i] && stat(inputs[i], &is) == 0 && is.st_dev == st.st_dev && is.st_ino == st.st_ino) {
            snprintf(err, errlen, "%s is the same file as the input %s: refused (an output never replaces an input)",
                     path, inputs[i]);
            return -1;
        }
    }
    if (!S_ISREG(st.st_mode)) {
        snprintf(err, errlen, "%s exists and is not a regular file: refused", path);
        return -1;
    }
    if (how == CD_OUTPUT_NEW) {
        snprintf(err, errlen,
                 "%s exists: refused, the file is left as it is (pass --overwrite to replace it once "
                 "the new run's first snapshot is written, --resume to continue it, or choose another --output)",
                 path);
        return -1;
    }
    unsigned long long dev, ino;
    int fd = cdh5_target_lock(path, &dev, &ino, err, errlen);
    if (fd == -2) return how == CD_OUTPUT_RESUME ? (snprintf(err, errlen, "%s: no such run file", path), -1) : 0;
    if (fd < 0) return -1;
    close(fd);
    return 0;
}

unsigned long long cdh5_growth(hid_t d, unsigned long long add)
{
    if (d < 0 || add == 0) return 0;
    hsize_t ch[3] = {1, 1, 1}, dims[3] = {0, 1, 1};
    hid_t pl = H5Dget_create_plist(d);
    int rank = pl < 0 ? -1 : H5Pget_chunk(pl, 3, ch);
    if (pl >= 0) H5Pclose(pl);
    if (rank <= 0 || cdh5_dims(d, dims) != rank) {
        H5Eclear2(H5E_DEFAULT);
        return 0;
    }
    hid_t t = H5Dget_type(d);
    unsigned long long chunk = t < 0 ? 0 : H5Tget_size(t), across = 1;
    if (t >= 0) H5Tclose(t);
    for (int k = 0; k < rank && k < 3; k++) chunk *= ch[k];
    for (int k = 1; k < rank && k < 3; k++) across *= (dims[k] + ch[k] - 1) / ch[k] ? (dims[k] + ch[k] - 1) / ch[k] : 1;
    unsigned long long before = (dims[0] + ch[0] - 1) / ch[0], after = (dims[0] + add + ch[0] - 1) / ch[0];
    unsigned long long fresh = (after - before) * across;
    /* the new chunks, and room for the chunk index to grow by a node */
    return fresh ? fresh * chunk + 8192 : 0;
}

int cdh5_reserve(cd_output *o, unsigned long long bytes, const char *what)
{
    haddr_t eoa = 0;
    void *handle = NULL;
    /* MPI-IO: no descriptor to reserve through (docs/mpi.md, "One file") */
    if (cdh5_par_on()) return 0;
    if (cdh5_journal_eoa(o->file, &eoa) < 0 || H5Fget_vfd_handle(o->file, H5P_DEFAULT, &handle) < 0 || !handle) {
        H5Eclear2(H5E_DEFAULT);
        return 0; /* a driver without a plain descriptor: no reservation */
    }
    int e = posix_fallocate(*(int *)handle, (off_t)eoa, (off_t)bytes);
    if (e == 0 || e == EINVAL || e == EOPNOTSUPP || e == ENOSYS) return 0;
    o->io_failed = 1;
    return FAIL("%s: no room to write %s (up to %.2f MiB more): %s", o->path, what, (double)bytes / 1048576.0,
                strerror(e));
}

int cdh5_check_linked(cd_output *o)
{
    void *handle = NULL;
    struct stat st;
    if (cdh5_par_on()) { /* rank 0 looks at its descriptor of the file (MPI-IO's handle is no descriptor) */
        int gone = cdh5_par_root() && o->own_lock >= 0 && fstat(o->own_lock, &st) == 0 && st.st_nlink == 0;
        if (!cdh5_par_max(gone)) return 0;
    } else if (H5Fget_vfd_handle(o->file, H5P_DEFAULT, &handle) < 0 || !handle || fstat(*(int *)handle, &st) < 0) {
        H5Eclear2(H5E_DEFAULT);
        return 0;
    } else if (st.st_nlink > 0) {
        return 0;
    }
    o->io_failed = 1;
    return FAIL("%s was deleted during the run (the file or its folder): the run stops, as what it writes could not "
                "be read by anyone",
                o->tmp_path[0] ? o->tmp_path : o->path);
}
