/* capdem render: runs host/render.py (matplotlib) on a run file.
 *
 * The drawing is done in Python because matplotlib gives antialiased,
 * depth-sorted polygons and PNG output for free; the C side only finds the
 * script and the interpreter and passes the arguments through unchanged
 * (execv, no shell, so file names with spaces or quotes need no care).
 * The interpreter is /usr/bin/python3 on purpose: python3-matplotlib,
 * python3-h5py and python3-numpy are Debian packages installed for it, and
 * the python3 first on PATH may be another interpreter without them. */
#define _XOPEN_SOURCE 700
#include <errno.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>
#include "export/export.h"

#define CD_RENDER_PYTHON "/usr/bin/python3"

/* Where render.py is: in an installed prefix, P/share/capdem/host beside
 * P/bin/capdem (`cmake --install`); else next to the sources the binary
 * was built from (CAPDEM_SOURCE_DIR, set by CMake); else where the
 * environment variable CAPDEM_SOURCE_DIR says (a moved source tree, or a
 * build without the macro).  CAPDEM_RENDER_SCRIPT names the script itself,
 * for trying a changed copy. */
static int cd_render_find_script(char *dst, size_t n)
{
    char installed[4096] = "";
    ssize_t len = readlink("/proc/self/exe", installed, sizeof installed - 1);
    if (len > 0) {
        installed[len] = 0;
        char *slash = strrchr(installed, '/');
        if (slash) *slash = 0; /* P/bin */
        slash = strrchr(installed, '/');
        if (slash) snprintf(slash, sizeof installed - (size_t)(slash - installed), "/share/capdem");
        else installed[0] = 0;
    }
    const char *dirs[3] = {installed, NULL, getenv("CAPDEM_SOURCE_DIR")};
#ifdef CAPDEM_SOURCE_DIR
    dirs[1] = CAPDEM_SOURCE_DIR;
#endif
    const char *direct = getenv("CAPDEM_RENDER_SCRIPT");
    if (direct && direct[0] && access(direct, R_OK) == 0) {
        snprintf(dst, n, "%s", direct);
        return 0;
    }
    for (int i = 0; i < 3; i++) {
        if (!dirs[i] || !dirs[i][0]) continue;
        snprintf(dst, n, "%s/host/render.py", dirs[i]);
        if (access(dst, R_OK) == 0) return 0;
    }
    return -1;
}

/* Exit status of `python3 -c 'import ...'`: 0 when the modules load. */
static int cd_render_python_has(const char *python, const char *code)
{
    pid_t pid = fork();
    if (pid < 0) return -1;
    if (pid == 0) {
        /* The check's own traceback would only repeat what we say. */
        FILE *devnull = freopen("/dev/null", "w", stderr);
        (void)devnull;
        execl(python, python, "-I", "-c", code, (char *)NULL);
        _exit(127);
    }
    int st;
    while (waitpid(pid, &st, 0) < 0)
        if (errno != EINTR) return -1;
    return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

int cd_cmd_render(int argc, char **argv)
{
    const char *python = getenv("CAPDEM_PYTHON");
    if (!python || !python[0]) python = CD_RENDER_PYTHON;
    char script[4096];
    if (cd_render_find_script(script, sizeof script)) {
        fprintf(stderr,
                "capdem render: cannot find host/render.py: looked in the source folder this binary was built from"
#ifdef CAPDEM_SOURCE_DIR
                " (" CAPDEM_SOURCE_DIR ")"
#endif
                " and in $CAPDEM_SOURCE_DIR; set CAPDEM_SOURCE_DIR to the capdem source folder\n");
        return 2;
    }
    if (access(python, X_OK) != 0) {
        fprintf(stderr,
                "capdem render: %s is missing (%s); install Debian's python3, python3-matplotlib, "
                "python3-h5py and python3-numpy\n",
                python, strerror(errno));
        return 2;
    }
    /* Checked here as well as in render.py so that the message names the
     * Debian packages even when render.py cannot start at all. */
    if (cd_render_python_has(python, "import matplotlib, numpy, h5py") != 0) {
        fprintf(stderr,
                "capdem render: %s cannot import matplotlib, numpy and h5py; install them with\n"
                "  apt-get install python3-matplotlib python3-numpy python3-h5py\n",
                python);
        return 2;
    }
    /* Python isolated (-I): neither the current folder (for -c) or the
     * script's folder nor PYTHON* variables or the user's site-packages
     * enter its import path, so an h5py.py lying in the folder a run file
     * came in cannot run as capdem. */
    char **args = calloc((size_t)argc + 4, sizeof *args);
    if (!args) {
        fprintf(stderr, "capdem render: out of memory\n");
        return 1;
    }
    args[0] = (char *)python;
    args[1] = "-I";
    args[2] = script;
    for (int i = 0; i < argc; i++) args[i + 3] = argv[i];
    fflush(stdout);
    fflush(stderr);
    pid_t pid = fork();
    if (pid < 0) {
        fprintf(stderr, "capdem render: cannot start %s (%s)\n", python, strerror(errno));
        free(args);
        return 1;
    }
    if (pid == 0) {
        execv(python, args);
        fprintf(stderr, "capdem render: cannot run %s (%s)\n", python, strerror(errno));
        _exit(1);
    }
    free(args);
    int st;
    while (waitpid(pid, &st, 0) < 0) {
        if (errno != EINTR) {
            fprintf(stderr, "capdem render: lost %s (%s)\n", python, strerror(errno));
            return 1;
        }
    }
    if (WIFEXITED(st)) return WEXITSTATUS(st);
    int sig = WIFSIGNALED(st) ? WTERMSIG(st) : 0;
    fprintf(stderr, "capdem render: %s %s was killed by signal %d (%s)%s\n", python, script, sig, strsignal(sig),
            sig == SIGSEGV || sig == SIGFPE || sig == SIGBUS
                ? "; a corrupted run file can make libhdf5 (under h5py) fault like this: `capdem analyze` "
                  "checks the file and names what is wrong"
                : "");
    return 1;
}
