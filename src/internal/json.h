/* json.h (internal: the tool's plumbing, linked from libcrowdbake.a, not exported) - a small streaming JSON writer for machine-readable output.
 * Keys are passed with each value; pass NULL inside arrays. Output is deterministic. */
#ifndef CB_JSON_WRITER_H
#define CB_JSON_WRITER_H


#include <stdbool.h>
#include <stdio.h>

#ifdef __cplusplus
extern "C" {
#endif

#define CB_JSON_MAX_DEPTH 32

typedef struct cb_json {
    FILE *out;
    int depth;
    bool has_items[CB_JSON_MAX_DEPTH];
    bool compact[CB_JSON_MAX_DEPTH]; /* arrays of numbers stay on one line */
    char closer[CB_JSON_MAX_DEPTH];  /* '}' or ']' */
} cb_json;

void cb_json_init(cb_json *j, FILE *out);
void cb_json_object(cb_json *j, const char *key);
void cb_json_array(cb_json *j, const char *key);
/* An array printed on one line: for short vectors such as a 4x4 matrix. */
void cb_json_inline_array(cb_json *j, const char *key);
void cb_json_end(cb_json *j); /* closes the innermost object or array; a newline after the last */
void cb_json_string(cb_json *j, const char *key, const char *value);
void cb_json_number(cb_json *j, const char *key, double value); /* NaN and infinities become null */
/* The shortest decimal that reads back as the same float32 (24, not 24.0000006): for a value
 * the files record as float32. */
void cb_json_float32(cb_json *j, const char *key, float value);
void cb_json_int(cb_json *j, const char *key, long long value);
void cb_json_bool(cb_json *j, const char *key, bool value);
void cb_json_null(cb_json *j, const char *key);

#ifdef __cplusplus
}
#endif

#endif
