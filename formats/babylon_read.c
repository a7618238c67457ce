/* babylon_read.c - the facts of a .bvat.json an up-to-date check needs (include/crowdbake/babylon.h),
 * read from its tail: the file is {"vertexData": "BASE64", "width": W, "height": H, "crowdbake": {...}}
 * as babylon_write.c writes it, and only the base64 is large. */
#define _FILE_OFFSET_BITS 64
#include "crowdbake/babylon.h"

#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define TAIL_BYTES (1u << 20) /* the crowdbake object: clips and states, far below this */

/* The bytes before the base64 data: `{"vertexData": "` (only its length is read). */
#define HEAD_BYTES (sizeof "{\"vertexData\": \"" - 1)
static const char AFTER_DATA[] = "\",\n\"width\": ";

/* Reads the last TAIL_BYTES of the file (all of a smaller one) into a string; *start: where it
 * begins in the file. */
static char *read_tail(FILE *f, long long *start)
{
    if (fseeko(f, 0, SEEK_END) != 0) return NULL;
    long long size = ftello(f);
    *start = size > TAIL_BYTES ? size - TAIL_BYTES : 0;
    char *text = size >= 0 ? malloc((size_t)(size - *start) + 1) : NULL;
    if (!text || fseeko(f, *start, SEEK_SET) != 0 || fread(text, 1, (size_t)(size - *start), f) != (size_t)(size - *start))
        return free(text), NULL;
    text[size - *start] = '\0';
    return text;
}

/* Whether the tail holds whole facts: the base64 ends where width x height texels of four
 * Float32 values end, the input hash is there, and the object is closed. */
static bool parse_tail(const char *text, long long start, cb_babylon_facts *out)
{
    const char *data_end = strstr(text, AFTER_DATA), *hash = strstr(text, "\"input_hash\": \"");
    size_t n = strlen(text);
    if (!data_end || !hash || n < 2 || strcmp(text + n - 2, "}\n") != 0) return false;
    if (sscanf(data_end + sizeof AFTER_DATA - 1, "%" SCNu32 ",\n\"height\": %" SCNu32, &out->width, &out->height) != 2)
        return false;
    if (sscanf(hash + 15, "%16" SCNx64, &out->input_hash) != 1) return false;
    unsigned long long bytes = (unsigned long long)out->width * out->height * 16;
    unsigned long long base64 = (bytes + 2) / 3 * 4;
    return (unsigned long long)(start + (data_end - text)) == HEAD_BYTES + base64;
}

cb_status cb_babylon_read_facts(const char *path, cb_babylon_facts *out, cb_error *err)
{
    memset(out, 0, sizeof *out);
    FILE *f = fopen(path, "rb");
    if (!f) return cb_fail(err, CB_ERR_IO, "%s: cannot open", path);
    long long start = 0;
    char *text = read_tail(f, &start);
    fclose(f);
    bool whole = text && parse_tail(text, start, out);
    free(text);
    return whole ? CB_OK
                 : cb_fail(err, CB_ERR_INPUT, "%s: not a whole .bvat.json as crowdbake writes it (bake it again)", path);
}
