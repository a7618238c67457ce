/* warnings.c - see crowdbake.h: a list of warnings and notes, and the model's. */
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>

#include "crowdbake/core.h"

void cb_warn(cb_warnings *list, const char *kind, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(NULL, 0, fmt, ap);
    va_end(ap);
    cb_warning *grown = n >= 0 ? realloc(list->items, (list->count + 1) * sizeof *grown) : NULL;
    char *text = grown ? malloc((size_t)n + 1) : NULL;
    if (grown) list->items = grown;
    if (!text) return;
    va_start(ap, fmt);
    vsnprintf(text, (size_t)n + 1, fmt, ap);
    va_end(ap);
    list->items[list->count++] = (cb_warning){kind, text};
}

void cb_warnings_free(cb_warnings *list)
{
    for (uint32_t i = 0; i < list->count; ++i) free(list->items[i].message);
    free(list->items);
    list->count = 0;
    list->items = NULL;
}

void cb_model_warnings(const cb_model *m, bool skipped_clips, cb_warnings *out)
{
    for (uint32_t i = 0; skipped_clips && i < m->skipped_clip_count; ++i)
        cb_warn(out, "warning", "%s; the clip is skipped, the others are baked",
                m->skipped_clips[i].reason);
    if (m->ignored_morph_channels)
        cb_warn(out, "note", "%s: %u morph-weight channel(s) ignored: palettes carry joints only", m->source,
                m->ignored_morph_channels);
}
