/* outputs.h - the table of output formats: one descriptor per file format a bake writes (.pal,
 * .exr, .ktx2, .bvat.json). The command line's --format and extensions, a catalog's format, the
 * roster's up-to-date check, the completions and the man page all read this table; a new format
 * is one row (src/bake/outputs.c) and its writer.
 *
 *     for (uint32_t i = 0; i < cb_output_format_count(); ++i) puts(cb_output_format_at(i)->name);
 *     const cb_output_format *f = cb_output_format_for_path("fox.ktx2"); // f->format == CB_FORMAT_KTX2
 */
#ifndef CB_OUTPUTS_H
#define CB_OUTPUTS_H

#include "export.h"
#include "palette.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Each format's bit (cb_output_format.format, cb_bake_settings.formats). */
enum { CB_FORMAT_PAL = 1u, CB_FORMAT_EXR = 2u, CB_FORMAT_KTX2 = 4u, CB_FORMAT_BABYLON = 8u };
/* At most this many formats, so a bake writes at most this many files (cb_bake_result.outputs). */
#define CB_OUTPUT_MAX 8

typedef struct cb_output_format {
    unsigned format;         /* its CB_FORMAT_* bit */
    const char *name;        /* --format's word and a catalog's: "pal" */
    const char *extension;   /* ".pal", ".bvat.json" */
    const char *summary;     /* one line, for usage texts and the man page */
    const char *manifest_key;/* a catalog manifest's member naming the file: "palette", "palette_exr" */
    unsigned layouts;        /* 1u << cb_layout, each layout it holds */
    unsigned precisions;     /* 1u << cb_precision, each precision it holds */
    bool zstd;               /* --zstd compresses it */
    bool in_catalogs;        /* a catalog can write it */
    bool holds_palette;      /* its texels are the palette's rows (a .bvat.json holds Babylon's own) */
} cb_output_format;

/* The formats, in the order a bake writes them (the first one a job writes chooses its rates). */
CROWDBAKE_API uint32_t cb_output_format_count(void);
CROWDBAKE_API const cb_output_format *cb_output_format_at(uint32_t index);
/* By bit, by name (length bytes of it: a word of a comma-separated list), by a path's extension
 * (".bvat.json" before ".json"); NULL when none. */
CROWDBAKE_API const cb_output_format *cb_output_format_of(unsigned format);
CROWDBAKE_API const cb_output_format *cb_output_format_named(const char *name, size_t length);
CROWDBAKE_API const cb_output_format *cb_output_format_for_path(const char *path);

/* What an output file on disk records of its bake: what an up-to-date check compares. The
 * geometry (width .. texel_bytes) is the palette's only for a format that holds_palette. */
typedef struct cb_output_facts {
    uint64_t input_hash;     /* cb_bake_input_hash of the bake that wrote it */
    uint32_t rows, width, height, blocks;
    cb_layout layout;
    cb_precision precision;
    float max_error, visible_error; /* model units, as cb_palette */
    uint64_t texel_bytes;    /* the texture as uploaded */
} cb_output_facts;

/* Reads the facts `format`'s file at `path` records, verifying what its reader verifies (a .pal's
 * checksum): a torn or foreign file fails. */
CROWDBAKE_API cb_status cb_output_read_facts(unsigned format, const char *path, cb_output_facts *out, cb_error *err);

#ifdef __cplusplus
}
#endif

#endif
