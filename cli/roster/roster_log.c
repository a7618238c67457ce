/* roster_log.c - see roster_files.h: the roster's log in catalog order. */
#include "roster_files.h"

#include <stdlib.h>

/* A type whose lines could not be kept (no memory): it prints nothing, and holds nobody up. */
static char nothing[1];

bool roster_log_init(roster_log *log, FILE *out, uint32_t count)
{
    log->out = out, log->count = count, log->next = 0;
    log->held = calloc(count ? count : 1, sizeof *log->held);
    return log->held != NULL;
}

void roster_log_put(roster_log *log, uint32_t i, char *text)
{
    if (!log->held || i >= log->count) { /* no memory for the order: as it comes */
        if (text) fputs(text, log->out);
        free(text);
        return;
    }
    log->held[i] = text ? text : nothing;
    for (; log->next < log->count && log->held[log->next]; ++log->next) {
        char *ready = log->held[log->next];
        fputs(ready, log->out);
        if (ready != nothing) free(ready);
        log->held[log->next] = nothing;
    }
}

void roster_log_free(roster_log *log)
{
    for (uint32_t i = 0; log->held && i < log->count; ++i)
        if (log->held[i] != nothing) free(log->held[i]);
    free(log->held);
    log->held = NULL;
}
