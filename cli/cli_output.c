/* cli_output.c - -q/--quiet and -v/--verbose, which every command takes (see cli.h). */
#include "cli.h"

#include <stdarg.h>
#include <stdio.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

const char cli_output_usage[] =
    "\noutput (every command):\n"
    "  -q, --quiet     no notes, progress or summary lines (a bake's warnings still show)\n"
    "  -v, --verbose   more on stderr: each file read and written, timings, the decisions taken\n";

int cli_take_output(int *argc, char **argv, cli_output *out)
{
    memset(out, 0, sizeof *out);
    int kept = 1, i = 1;
    for (; i < *argc && strcmp(argv[i], "--") != 0; ++i) { /* after "--", a file may be named -v */
        if (strcmp(argv[i], "-q") == 0 || strcmp(argv[i], "--quiet") == 0) out->quiet = true;
        else if (strcmp(argv[i], "-v") == 0 || strcmp(argv[i], "--verbose") == 0) out->verbose = true;
        else argv[kept++] = argv[i];
    }
    while (i < *argc) argv[kept++] = argv[i++];
    *argc = kept;
    argv[kept] = NULL;
    if (out->quiet) out->verbose = false; /* -q wins: a script's -q stays quiet whatever else it passes */
    return 0;
}

void cli_verbose(const cli_output *out, const char *fmt, ...)
{
    if (!out->verbose || out->quiet) return;
    va_list ap;
    va_start(ap, fmt);
    fputs("crowdbake: ", stderr);
    vfprintf(stderr, fmt, ap);
    fputc('\n', stderr);
    va_end(ap);
}

bool cli_progress(const cli_output *out) { return !out->quiet && (out->verbose || isatty(STDERR_FILENO)); }

double cli_seconds(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + t.tv_nsec * 1e-9;
}
