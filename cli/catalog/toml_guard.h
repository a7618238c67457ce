/* toml_guard.h - what the catalog adapter checks before toml++ parses a file (private to
 * libcrowdbake). */
#ifndef CB_TOML_GUARD_H
#define CB_TOML_GUARD_H

#include <stdbool.h>
#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Where TOML text meets a character outside ASCII that is neither in a string nor in a comment
 * (1-based line, and column in characters), or false. TOML allows none there, and toml++ 3.3
 * reaches a __builtin_unreachable on some of them (U+00A1 where a key or value starts; found by
 * fuzzing it under UBSan): such a file is refused before it is parsed. */
bool toml_non_ascii_outside_strings(const char *text, size_t size, unsigned *line, unsigned *column);

#ifdef __cplusplus
}
#endif

#endif
