/* Fatal signals inside libhdf5 while a user's file is read become a
 * refusal of that file (io_h5_guard.h says why). */
#define _XOPEN_SOURCE 700 /* sigaltstack, SA_ONSTACK */
#include "io/io_h5_guard.h"
#include <signal.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

static const int guarded[] = {SIGSEGV, SIGBUS, SIGFPE, SIGILL};
#define N_GUARDED (sizeof guarded / sizeof guarded[0])

static struct sigaction previous[N_GUARDED];
static int armed, disabled;
/* The message is assembled when the guard is armed: a signal handler may
 * only call async-signal-safe functions (write, _exit), not snprintf. */
static char head[1200];
static size_t head_len;
/* An alternate stack, so that a stack overflow inside libhdf5 (a runaway
 * recursion on a looping object tree) still reaches the handler. */
static char alt_stack[1 << 16];

static const char *signal_name(int sig)
{
    switch (sig) {
    case SIGSEGV:
        return "SIGSEGV (invalid memory access)";
    case SIGBUS:
        return "SIGBUS (invalid memory access)";
    case SIGFPE:
        return "SIGFPE (arithmetic fault)";
    default:
        return "SIGILL (illegal instruction)";
    }
}

static void on_fatal_signal(int sig)
{
    static const char tail[] =
        " while the HDF5 library read it: the file's metadata is corrupted in a way libhdf5 does not check "
        "(docs/testing.md, \"Sanitizers and fuzzing\"); the file is refused and left as it was\n";
    const char *name = signal_name(sig);
    ssize_t ignored = write(STDERR_FILENO, head, head_len);
    ignored = write(STDERR_FILENO, name, strlen(name));
    ignored = write(STDERR_FILENO, tail, sizeof tail - 1);
    (void)ignored;
    _exit(2);
}

void cdh5_guard_begin(const char *tool, const char *path)
{
    if (disabled) return;
    int n = snprintf(head, sizeof head, "capdem %s: %s: stopped by ", tool, path);
    head_len = n < 0 ? 0 : (size_t)n < sizeof head ? (size_t)n : sizeof head - 1;
    if (armed) return;
    stack_t st;
    memset(&st, 0, sizeof st);
    st.ss_sp = alt_stack;
    st.ss_size = sizeof alt_stack;
    sigaltstack(&st, NULL);
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_fatal_signal;
    sa.sa_flags = SA_ONSTACK | SA_RESETHAND; /* a fault in the handler itself then ends as a plain crash */
    sigemptyset(&sa.sa_mask);
    for (size_t k = 0; k < N_GUARDED; k++) sigaction(guarded[k], &sa, &previous[k]);
    armed = 1;
}

void cdh5_guard_end(void)
{
    if (!armed) return;
    for (size_t k = 0; k < N_GUARDED; k++) sigaction(guarded[k], &previous[k], NULL);
    armed = 0;
}

void cdh5_guard_disable(void)
{
    cdh5_guard_end();
    disabled = 1;
}
