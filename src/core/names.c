/* names.c - the closest known name to a mistyped one, for "did you mean" messages. */
#include "crowdbake/core.h"

#include <string.h>

size_t cb_edit_distance(const char *a, const char *b)
{
    /* Levenshtein over one row; names are short, longer ones are cut at 63 bytes. */
    size_t row[64], la = strlen(a), lb = strlen(b);
    if (la > 63) la = 63;
    if (lb > 63) lb = 63;
    for (size_t j = 0; j <= lb; ++j) row[j] = j;
    for (size_t i = 1; i <= la; ++i) {
        size_t prev = row[0];
        row[0] = i;
        for (size_t j = 1; j <= lb; ++j) {
            size_t cur = row[j], best = row[j] + 1;
            if (row[j - 1] + 1 < best) best = row[j - 1] + 1;
            if (prev + (a[i - 1] != b[j - 1]) < best) best = prev + (a[i - 1] != b[j - 1]);
            row[j] = best;
            prev = cur;
        }
    }
    return row[lb];
}

const char *cb_closest_name(const char *name, const char *const *known, size_t count, size_t stride)
{
    const char *best = NULL;
    size_t best_distance = 3; /* two edits at most: further than that is a different word */
    for (size_t i = 0; i < count; ++i) {
        const char *candidate = *(const char *const *)((const char *)known + i * stride);
        size_t d = cb_edit_distance(name, candidate);
        if (d < best_distance) best_distance = d, best = candidate;
    }
    return best;
}
