/* name_words.c - words of a clip's or state's name (name_words.h). */
#include "internal/name_words.h"

#include <ctype.h>
#include <stdbool.h>
#include <stdio.h>
#include <string.h>

static bool word_matches(const char *word, size_t n, const char *stem)
{
    static const char *const endings[] = {"", "s", "es", "ed", "d", "er", "ing", "ion"};
    size_t k = strlen(stem);
    if (n < k || strncmp(word, stem, k) != 0) return false;
    const char *rest = word + k;
    size_t r = n - k;
    if (r > 0 && rest[0] == stem[k - 1] && r > 1) ++rest, --r; /* a doubled consonant: running, trotted */
    for (size_t e = 0; e < sizeof endings / sizeof *endings; ++e)
        if (strlen(endings[e]) == r && strncmp(rest, endings[e], r) == 0) return true;
    return false;
}

int cb_name_find_word(const char *text, const char *const *stems, size_t count, char *out, size_t size)
{
    char word[64];
    for (const char *p = text ? text : ""; *p;) {
        size_t n = 0;
        while (*p && !isalpha((unsigned char)*p)) ++p;
        while (isalpha((unsigned char)*p)) {
            if (n < sizeof word - 1) word[n++] = (char)tolower((unsigned char)*p);
            ++p;
            if (islower((unsigned char)p[-1]) && isupper((unsigned char)*p)) break;
        }
        for (size_t i = 0; n && i < count; ++i)
            if (word_matches(word, n, stems[i])) {
                if (size) snprintf(out, size, "%.*s", (int)n, word);
                return (int)i;
            }
    }
    return -1;
}
