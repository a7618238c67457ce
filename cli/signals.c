/* signals.c - an interrupted command leaves no partial file. The library installs no handler
 * and keeps no table of its temporaries; the command creates them for it (cb_temp_files), in a
 * table its SIGINT, SIGTERM and SIGHUP handlers remove them from, and then ends by the same
 * signal. A signal handler can reach nothing but globals, so this table is the command's one
 * piece of global mutable state: filled and emptied lock-free, read by the handler with
 * async-signal-safe calls only. */
#include "cli.h"
#include "crowdbake/atomic_file.h"

#include <signal.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

enum { TEMP_SLOTS = 64, TEMP_PATH = 4096 };
static char temp_paths[TEMP_SLOTS][TEMP_PATH];
static atomic_int temp_state[TEMP_SLOTS]; /* 0 free, 1 being named, 2 named */

/* Creates the temporary file from `template` (ending in XXXXXX) inside a claimed slot, so the
 * name chosen is visible to the handler before the file can exist. */
static int create_registered(void *ctx, char *template, int *slot)
{
    (void)ctx;
    *slot = -1;
    size_t n = strlen(template) + 1;
    for (int i = 0; i < TEMP_SLOTS && n <= TEMP_PATH; ++i) {
        int expected = 0;
        if (!atomic_compare_exchange_strong(&temp_state[i], &expected, 1)) continue;
        memcpy(temp_paths[i], template, n);
        int fd = cb_atomic_create_temp(temp_paths[i]);
        memcpy(template, temp_paths[i], n);
        if (fd < 0) {
            atomic_store(&temp_state[i], 0);
            return -1;
        }
        atomic_store(&temp_state[i], 2);
        *slot = i;
        return fd;
    }
    return cb_atomic_create_temp(template); /* untracked: still removed on every failure but a signal */
}

static void unregister_temp(void *ctx, int slot)
{
    (void)ctx;
    if (slot >= 0 && slot < TEMP_SLOTS) atomic_store(&temp_state[slot], 0);
}

/* Test hook: CROWDBAKE_TEST_STOP=mid-write stops the process (SIGSTOP) once half of its first
 * write to a temporary file is done; =before-rename stops it when the temporary is complete but
 * not yet renamed. A test then signals the stopped process at that exact point instead of racing
 * a short-lived file (tests/tools/interrupt_mid_write.py). Never set outside tests. */
static void stop_here_for_tests(void *ctx, const char *point)
{
    const char *at = ctx;
    if (strcmp(at, point) == 0) raise(SIGSTOP);
}

static void write_stderr(const char *s) { (void)!write(2, s, strlen(s)); }

static void on_signal(int sig)
{
    int removed = 0;
    for (int i = 0; i < TEMP_SLOTS; ++i) {
        /* a slot being named holds either the template (no such file) or the created name */
        if (atomic_load(&temp_state[i]) != 0 && unlink(temp_paths[i]) == 0) ++removed;
    }
    write_stderr(sig == SIGINT ? "crowdbake: interrupted (SIGINT)" : sig == SIGTERM ? "crowdbake: terminated (SIGTERM)"
                                                                                  : "crowdbake: hung up (SIGHUP)");
    write_stderr(removed ? "; removed the partial output; the previous files are unchanged\n"
                         : "; no partial output was left (each file is the previous one or complete)\n");
    signal(sig, SIG_DFL);
    raise(sig);
}

void cli_remove_temporaries_on_signals(void)
{
    const char *stop = getenv("CROWDBAKE_TEST_STOP");
    cb_temp_files files = {create_registered, unregister_temp, stop ? stop_here_for_tests : NULL, (void *)stop};
    cb_atomic_set_temp_files(&files);
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);
    sigaction(SIGHUP, &sa, NULL);
}
