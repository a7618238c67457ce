/* record_io.h - the byte records the roster keeps (a type's prep record, roster_cache.c; a type's
 * manifest fragment, roster_fragment.c): numbers in this machine's byte order, strings as a u32
 * length and their bytes. Writing grows a buffer (failed: out of memory); reading never goes past
 * the record's end (failed: truncated or damaged, every later read zero). */
#ifndef CB_RECORD_IO_H
#define CB_RECORD_IO_H

#include <stdbool.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

typedef struct record_writer {
    unsigned char *data; /* the caller frees it */
    size_t size, cap;
    bool failed;
} record_writer;

static inline void rec_put(record_writer *w, const void *p, size_t n)
{
    if (w->failed || n == 0) return;
    if (w->size + n > w->cap) {
        size_t cap = w->cap ? w->cap * 2 : 4096;
        while (cap < w->size + n) cap *= 2;
        unsigned char *grown = realloc(w->data, cap);
        if (!grown) {
            w->failed = true;
            return;
        }
        w->data = grown, w->cap = cap;
    }
    memcpy(w->data + w->size, p, n);
    w->size += n;
}

static inline void rec_put_u32(record_writer *w, uint32_t v) { rec_put(w, &v, sizeof v); }
static inline void rec_put_u64(record_writer *w, uint64_t v) { rec_put(w, &v, sizeof v); }
static inline void rec_put_f32(record_writer *w, float v) { rec_put(w, &v, sizeof v); }
static inline void rec_put_f64(record_writer *w, double v) { rec_put(w, &v, sizeof v); }
static inline void rec_put_str(record_writer *w, const char *s)
{
    uint32_t n = s ? (uint32_t)strlen(s) : 0;
    rec_put_u32(w, n);
    rec_put(w, s, n);
}

typedef struct record_reader {
    const unsigned char *p, *end;
    bool failed;
} record_reader;

static inline void rec_get(record_reader *r, void *out, size_t n)
{
    if (n == 0) return;
    if (r->failed || (size_t)(r->end - r->p) < n) {
        r->failed = true;
        memset(out, 0, n);
        return;
    }
    memcpy(out, r->p, n);
    r->p += n;
}

static inline uint32_t rec_get_u32(record_reader *r) { uint32_t v; rec_get(r, &v, sizeof v); return v; }
static inline uint64_t rec_get_u64(record_reader *r) { uint64_t v; rec_get(r, &v, sizeof v); return v; }
static inline float rec_get_f32(record_reader *r) { float v; rec_get(r, &v, sizeof v); return v; }
static inline double rec_get_f64(record_reader *r) { double v; rec_get(r, &v, sizeof v); return v; }

/* A string into buf (size bytes; too long fails the record); NULL buf: a malloc'ed copy. */
static inline char *rec_get_str(record_reader *r, char *buf, size_t size)
{
    uint32_t n = rec_get_u32(r);
    if (r->failed || (size_t)(r->end - r->p) < n || (buf && n >= size)) {
        r->failed = true;
        if (buf && size) buf[0] = '\0';
        return NULL;
    }
    char *s = buf ? buf : malloc((size_t)n + 1);
    if (!s) {
        r->failed = true;
        return NULL;
    }
    memcpy(s, r->p, n);
    s[n] = '\0';
    r->p += n;
    return s;
}

#endif
