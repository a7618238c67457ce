/* report_runtime.h - the report's runtime section: what runtime-ready meshes, batches and a
 * runtime cross-fade save or cost per animal type (`crowdbake mesh`, CB_BATCH, the shaders'
 * cross-fade). report.c calls it; it has its own file to keep each file one job. */
#ifndef CB_REPORT_RUNTIME_H
#define CB_REPORT_RUNTIME_H

#include <stdio.h>

#include "internal/json.h"
#include "catalog/catalog.h"

#ifdef __cplusplus
extern "C" {
#endif

#define CB_REPORT_STR_(x) #x
#define CB_REPORT_STR(x) CB_REPORT_STR_(x)

/* mm per metre that u8 weights may add before the mesh takes u16 ones (`mesh`'s default). */
#define CB_REPORT_MAX_QUANTIZATION_ERROR 0.1

/* Copies in the batch the report prices (the Unity vehicle crowd drew 100 per batch). */
#define CB_REPORT_BATCH 100
/* Length of one pre-baked transition clip the report prices against a runtime cross-fade. */
#define CB_REPORT_TRANSITION_SECONDS 0.5

/* One runtime mesh: the model (lod 0) or a catalog LOD at some influences, quantized. */
typedef struct cb_report_mesh {
    uint32_t lod, influences;
    uint64_t vertices, vertex_bytes, index_bytes; /* as `crowdbake mesh --quantize` writes it */
    uint64_t source_bytes;                        /* the same mesh's buffers in its file's own format */
    double error, height;                         /* extra vertex error vs 4 influences (model units), rest height */
    uint32_t fetches;                             /* palette texel fetches per vertex: influences x texels x 2 rows */
    uint32_t weight_bits;                         /* 8, or 16 where u8 weights cost over CB_REPORT_MAX_QUANTIZATION_ERROR */
} cb_report_mesh;

typedef struct cb_report_runtime {
    uint32_t mesh_count;
    cb_report_mesh *meshes;        /* the model at 4, 2, 1 influences, then each LOD at its lod_max_influences */
    uint64_t batch_bytes;          /* CB_REPORT_BATCH copies of the model's mesh in one batch (vertices + indices) */
    uint64_t instanced_bytes;      /* one mesh + 16 bytes of instance data per copy */
    uint32_t loops;                /* looping clips */
    uint64_t transition_bytes;     /* a pre-baked transition between every ordered pair of loops */
    bool measured;                 /* false when the model could not be read again (the section is left out) */
    bool half_rate_measured;       /* the palette baked again at half every clip's rate (report_half.c) */
    bool half_rate_within;         /* ... and every clip stayed within its max_error */
    double half_rate_error_mm;     /* the worst clip's visible error there, mm per metre */
} cb_report_runtime;

struct cb_roster_type;
/* The types measured so far, by what their meshes depend on (report_runtime.c's meshes_key):
 * a type whose model and LODs hold the bytes of one measured before copies its meshes. */
typedef struct report_mesh_memo_item {
    uint64_t key;
    const cb_report_runtime *runtime; /* the measured type's (it outlives the memo) */
} report_mesh_memo_item;
typedef struct report_mesh_memo {
    uint32_t count;
    report_mesh_memo_item *items; /* room for every type */
} report_mesh_memo;
/* Measures a type: reloads its model and LODs, builds their quantized runtime meshes and measures
 * them against the palette model's clips at 30 fps (or copies them from `memo`, which may be
 * NULL, and adds them to it). */
cb_status cb_report_runtime_measure(const struct cb_roster_type *type, const struct cb_roster_type *owner,
                                    report_mesh_memo *memo, cb_report_runtime *out, cb_error *err);
void cb_report_runtime_free(cb_report_runtime *rt);
/* Bakes the owner's clips at half their rates, in its encoding, and records in `out` whether
 * every clip stays within its budget (report_half.c). */
void report_measure_half_rate(cb_sampler *s, const struct cb_roster_type *owner, cb_report_runtime *out);

typedef struct cb_report cb_report;
void cb_report_runtime_text(FILE *f, const cb_report *r);
void cb_report_runtime_markdown(FILE *f, const cb_report *r);
void cb_report_runtime_json(cb_json *j, const cb_report_runtime *rt);
void cb_report_runtime_html(FILE *f, const cb_report *r);

#ifdef __cplusplus
}
#endif

#endif
