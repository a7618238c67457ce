/* toml_guard.c - see toml_guard.h. The strings are TOML's four kinds; a multi-line one ends at
 * the last of a run of 3 to 5 quotes. */
#include "toml_guard.h"

enum scan_state { CODE, COMMENT, BASIC, LITERAL, MULTI_BASIC, MULTI_LITERAL };

static bool starts_character(unsigned char ch) { return (ch & 0xC0) != 0x80; }

static size_t run_of(const char *t, size_t size, size_t i, char quote)
{
    size_t n = 0;
    while (i + n < size && t[i + n] == quote) ++n;
    return n;
}

bool toml_non_ascii_outside_strings(const char *t, size_t size, unsigned *line, unsigned *column)
{
    enum scan_state state = CODE;
    unsigned l = 1, c = 0;
    for (size_t i = 0; i < size; ++i) {
        unsigned char ch = (unsigned char)t[i];
        c += starts_character(ch);
        if (ch == '\n') {
            l++, c = 0;
            if (state == COMMENT || state == BASIC || state == LITERAL) state = CODE; /* ended, or unterminated */
            continue;
        }
        bool basic = state == BASIC || state == MULTI_BASIC;
        if (basic && ch == '\\' && i + 1 < size && t[i + 1] != '\n') { /* an escaped character */
            c += starts_character((unsigned char)t[++i]);
            continue;
        }
        char quote = basic ? '"' : '\'';
        size_t run = state == CODE && (ch == '"' || ch == '\'') ? run_of(t, size, i, (char)ch) : 0;
        switch (state) {
        case CODE:
            if (ch >= 0x80) {
                *line = l, *column = c;
                return true;
            }
            if (ch == '#') state = COMMENT;
            else if (run >= 3) state = ch == '"' ? MULTI_BASIC : MULTI_LITERAL, i += 2, c += 2;
            else if (run) state = ch == '"' ? BASIC : LITERAL;
            break;
        case BASIC:
        case LITERAL:
            if (ch == (unsigned char)quote) state = CODE;
            break;
        case MULTI_BASIC:
        case MULTI_LITERAL:
            if (ch == (unsigned char)quote) {
                size_t n = run_of(t, size, i, quote);
                i += n - 1, c += (unsigned)n - 1;
                if (n >= 3) state = CODE;
            }
            break;
        case COMMENT:
            break;
        }
    }
    return false;
}
