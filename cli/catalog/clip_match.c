/* clip_match.c - the one clip-name matcher (catalog.h's cb_match_clip_name): --clip, verify,
 * inspect and a catalog's clips and extra_clips all find clips by it, so a name that works on
 * the command line works in a catalog. */
#define _DEFAULT_SOURCE /* strncasecmp */
#include <ctype.h>
#include <stdio.h>
#include <string.h>
#include <strings.h>

#include "catalog/catalog.h"

/* The name at index i of an array read with a stride (as cb_closest_name reads it). */
static const char *name_at(const char *const *names, size_t stride, size_t i)
{
    return *(const char *const *)((const char *)names + i * stride);
}

static bool contains_ignoring_case(const char *text, const char *part)
{
    size_t n = strlen(part);
    for (; *text; ++text)
        if (strncasecmp(text, part, n) == 0) return true;
    return false;
}

/* The rules, tried in turn: the exact name; regardless of case; the part after an exporter's
 * "Armature|" regardless of case; a part of the name regardless of case. */
enum { MATCH_RULES = 4 };
static bool matches(int rule, const char *name, const char *typed)
{
    const char *bar = strrchr(name, '|');
    switch (rule) {
    case 0: return strcmp(name, typed) == 0;
    case 1: return strcasecmp(name, typed) == 0;
    case 2: return bar && strcasecmp(bar + 1, typed) == 0;
    default: return contains_ignoring_case(name, typed);
    }
}

/* The name within two edits of `typed`, regardless of case (the closest; the first on a tie). */
static const char *closest_ignoring_case(const char *typed, const char *const *names, size_t count, size_t stride)
{
    char a[256], b[256];
    size_t best = 3;
    const char *guess = NULL;
    snprintf(a, sizeof a, "%s", typed);
    for (char *p = a; *p; ++p) *p = (char)tolower((unsigned char)*p);
    for (size_t i = 0; i < count; ++i) {
        const char *name = name_at(names, stride, i), *bar = strrchr(name, '|');
        snprintf(b, sizeof b, "%s", bar && !strchr(a, '|') ? bar + 1 : name);
        for (char *p = b; *p; ++p) *p = (char)tolower((unsigned char)*p);
        size_t d = cb_edit_distance(a, b);
        if (d < best) best = d, guess = name;
    }
    return guess;
}

int cb_match_clip_name(const char *typed, const char *const *names, size_t count, size_t stride, char *why, size_t size)
{
    for (int rule = 0; rule < MATCH_RULES; ++rule) {
        int found = -1, hits = 0;
        for (size_t i = 0; i < count; ++i)
            if (matches(rule, name_at(names, stride, i), typed) && hits++ == 0) found = (int)i;
        if (hits == 1) return found;
        if (hits > 1) {
            snprintf(why, size, "'%s' matches %d clips:", typed, hits);
            for (size_t i = 0, listed = 0; i < count && listed < 6; ++i)
                if (matches(rule, name_at(names, stride, i), typed))
                    snprintf(why + strlen(why), size - strlen(why), "%s '%s'", listed++ ? "," : "", name_at(names, stride, i));
            snprintf(why + strlen(why), size - strlen(why), "; give more of the name");
            return -1;
        }
    }
    const char *guess = closest_ignoring_case(typed, names, count, stride);
    if (guess) snprintf(why, size, "no clip '%s'; did you mean '%s'?", typed, guess);
    else {
        snprintf(why, size, "no clip '%s'; the clips are:", typed);
        for (size_t i = 0; i < count && strlen(why) + 8 < size; ++i)
            snprintf(why + strlen(why), size - strlen(why), "%s %s", i ? "," : "", name_at(names, stride, i));
    }
    return -1;
}

