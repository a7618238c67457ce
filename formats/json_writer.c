/* json_writer.c - see json_writer.h. */
#include "internal/json.h"

#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void cb_json_init(cb_json *j, FILE *out)
{
    j->out = out;
    j->depth = 0;
    j->has_items[0] = false;
    j->compact[0] = false;
}

static void write_escaped(FILE *out, const char *s)
{
    fputc('"', out);
    for (const unsigned char *p = (const unsigned char *)s; *p; ++p) {
        if (*p == '"' || *p == '\\')
            fprintf(out, "\\%c", *p);
        else if (*p == '\n')
            fputs("\\n", out);
        else if (*p < 0x20)
            fprintf(out, "\\u%04x", *p);
        else
            fputc(*p, out);
    }
    fputc('"', out);
}

/* Separator, indentation and key before a value. */
static void prefix(cb_json *j, const char *key)
{
    if (j->depth > 0) {
        bool compact = j->compact[j->depth];
        if (j->has_items[j->depth]) fputc(',', j->out);
        if (compact) {
            if (j->has_items[j->depth]) fputc(' ', j->out);
        } else {
            fputc('\n', j->out);
            for (int i = 0; i < j->depth; ++i) fputs("  ", j->out);
        }
        j->has_items[j->depth] = true;
    }
    if (key) {
        write_escaped(j->out, key);
        fputs(": ", j->out);
    }
}

static void open_container(cb_json *j, const char *key, char bracket, bool compact)
{
    prefix(j, key);
    fputc(bracket, j->out);
    if (j->depth + 1 < CB_JSON_MAX_DEPTH) ++j->depth;
    j->has_items[j->depth] = false;
    j->compact[j->depth] = compact || j->compact[j->depth - 1];
    j->closer[j->depth] = bracket == '{' ? '}' : ']';
}

void cb_json_object(cb_json *j, const char *key) { open_container(j, key, '{', false); }
void cb_json_array(cb_json *j, const char *key) { open_container(j, key, '[', false); }
void cb_json_inline_array(cb_json *j, const char *key) { open_container(j, key, '[', true); }

void cb_json_end(cb_json *j)
{
    if (j->depth == 0) return;
    bool had = j->has_items[j->depth], compact = j->compact[j->depth];
    char closer = j->closer[j->depth];
    --j->depth;
    if (had && !compact) {
        fputc('\n', j->out);
        for (int i = 0; i < j->depth; ++i) fputs("  ", j->out);
    }
    fputc(closer, j->out);
    if (j->depth == 0) fputc('\n', j->out);
}

void cb_json_string(cb_json *j, const char *key, const char *value)
{
    prefix(j, key);
    write_escaped(j->out, value ? value : "");
}

void cb_json_number(cb_json *j, const char *key, double value)
{
    prefix(j, key);
    if (!isfinite(value))
        fputs("null", j->out);
    else if (value == 0)
        fputs("0", j->out); /* no "-0" */
    else
        fprintf(j->out, "%.9g", value);
}

void cb_json_float32(cb_json *j, const char *key, float value)
{
    prefix(j, key);
    if (!isfinite(value) || value == 0) {
        fputs(isfinite(value) ? "0" : "null", j->out);
        return;
    }
    char text[32];
    bool plain = fabsf(value) >= 1e-4f && fabsf(value) < 1e15f; /* written without an exponent: 120, not 1.2e+02 */
    for (int digits = 1; digits <= 9; ++digits) { /* 9 significant digits round-trip any float32 */
        snprintf(text, sizeof text, "%.*g", digits, (double)value);
        if ((float)strtod(text, NULL) == value && (!plain || !strchr(text, 'e'))) break;
    }
    fputs(text, j->out);
}

void cb_json_int(cb_json *j, const char *key, long long value)
{
    prefix(j, key);
    fprintf(j->out, "%lld", value);
}

void cb_json_bool(cb_json *j, const char *key, bool value)
{
    prefix(j, key);
    fputs(value ? "true" : "false", j->out);
}

void cb_json_null(cb_json *j, const char *key)
{
    prefix(j, key);
    fputs("null", j->out);
}
