/* catalog.h - an animal catalog (a roster of animal types to bake) as plain structs, and the
 * roster logic that needs no file: state keywords, ground speed, LOD joint remapping.
 * formats/catalog_toml.cpp fills a cb_catalog from TOML; formats/roster.c bakes it. */
#ifndef CB_CATALOG_H
#define CB_CATALOG_H

#include "palette.h"

#ifdef __cplusplus
extern "C" {
#endif

enum { CB_FORMAT_PAL = 1u, CB_FORMAT_EXR = 2u };

typedef struct cb_source_pos {
    uint32_t line, column; /* 1-based; 0 when unknown */
} cb_source_pos;

typedef struct cb_bake_settings {
    double fps;
    bool fps_auto;               /* fps = "auto": per clip, the lowest rate within max_error_mm */
    double max_error_mm;         /* visible error goal of fps = "auto", mm per metre of model height (default 1) */
    double max_fps;              /* fps = "auto" goes no higher (default 60) */
    cb_layout layout;
    cb_precision precision;
    unsigned formats;            /* CB_FORMAT_* */
    const char *out_dir;         /* resolved against the catalog's directory */
    uint32_t max_texture_size;
    cb_root_motion root_motion;
    bool layout_set, precision_set; /* chosen explicitly (else: defaults, with fallbacks) */
    bool zstd;                   /* compress the .pal payload */
    int exr_compression;         /* formats/exr_io.h's lossless codes; 0: none */
    bool fit_rows;               /* fit_rows = true: rows fitted to the linear blend (cb_bake_options.fit) */
} cb_bake_settings;

/* Which settings an override carries (the command line's bake options over a catalog). */
enum {
    CB_BAKE_FPS = 1u << 0, CB_BAKE_LAYOUT = 1u << 1, CB_BAKE_PRECISION = 1u << 2, CB_BAKE_FORMATS = 1u << 3,
    CB_BAKE_MAX_TEXTURE_SIZE = 1u << 4, CB_BAKE_ROOT_MOTION = 1u << 5, CB_BAKE_ZSTD = 1u << 6,
    CB_BAKE_EXR_COMPRESSION = 1u << 7, CB_BAKE_FIT_ROWS = 1u << 8
};

typedef struct cb_catalog_clip {
    const char *source; /* the clip's name in the model */
    const char *name;   /* its name in the palette */
    int loop;           /* -1 from the poses, 0, 1 */
    double fps;         /* 0: the animal's fps */
    int fps_auto;       /* -1: as the animal; 0: fixed fps; 1: fps = "auto" */
    double max_error_mm; /* 0: the animal's */
    cb_source_pos pos;
} cb_catalog_clip;

typedef struct cb_catalog_state {
    const char *name;
    const char **keywords;
    uint32_t keyword_count;
    cb_source_pos pos;
} cb_catalog_state;

typedef struct cb_catalog_animal {
    const char *name;
    cb_source_pos pos;
    const char *model; /* resolved path */
    cb_source_pos model_pos;
    const char **lods;
    cb_source_pos *lod_pos;
    uint32_t lod_count;
    uint32_t *lod_max_influences; /* lod_count entries (1, 2 or 4) for `crowdbake mesh --lod N`, or NULL */
    cb_catalog_clip *clips; /* NULL: every clip of the model */
    uint32_t clip_count;
    cb_catalog_state *states;
    uint32_t state_count;
    const char *default_state;
    double speed_reference; /* m/s (model units/s); with speed_auto, measured */
    bool speed_auto;
    const char *speed_state; /* speed_reference = "STATE": measure it on that state's clip (unless the default state's is locomotion) */
    cb_source_pos speed_pos;
    cb_bake_settings bake;
    const char *canonical;  /* the resolved entry as text: part of the input hash */
} cb_catalog_animal;

typedef struct cb_budget {
    bool set;
    const char *target;        /* a built-in profile or one defined in the catalog */
    uint64_t vram_bytes;
    double crowd_share;        /* the share of vram crowds may use, 0..1 */
    uint32_t max_texture_size; /* the target's limit */
    uint32_t max_bones;        /* the runtime shader's limit */
    cb_source_pos pos;
} cb_budget;

typedef struct cb_catalog {
    cb_arena *arena;
    const char *path, *dir;
    cb_bake_settings defaults;
    cb_budget budget;
    cb_catalog_animal *animals; /* sorted by name */
    uint32_t animal_count;
} cb_catalog;

void cb_catalog_free(cb_catalog *catalog);

/* Replaces the `fields` (CB_BAKE_*) of the catalog's defaults and of every animal's settings
 * with those of `values`: options given for one run win over what the catalog says. A clip's
 * own fps still applies. Fails, naming the animal, when an animal would write u16 texels to
 * EXR (which holds half or float only). */
cb_status cb_catalog_override_bake(cb_catalog *catalog, const cb_bake_settings *values, unsigned fields, cb_error *err);

/* Index of the first clip whose name contains a keyword, trying keywords in order
 * (case-insensitive), or -1. */
int cb_match_state(const char *const *clip_names, uint32_t clip_count, const char *const *keywords,
                   uint32_t keyword_count);

/* Ground speed of a clip in model units per second, from two pieces of evidence: the root's
 * horizontal travel, and the speed at which planted feet slide back relative to the root (a
 * foot on the ground is still in the world). Root travel when the two agree or no foot steps;
 * the feet when the root moves far less than they do (the clip walks in place and its root
 * only drifts). 0 when neither moves. */
typedef struct cb_ground_speed {
    double speed;       /* the ground speed: what foot-sync uses */
    double root, feet;  /* both measurements; feet 0 when no foot steps */
    const char *method; /* "root motion", "planted feet", "planted feet (the root only drifts)" or "none" */
} cb_ground_speed;
void cb_measure_ground_speed(cb_sampler *sampler, const cb_clip_info *clip, cb_ground_speed *out);

/* For a LOD skin: remap[i] = the main skin's joint with the LOD joint i's name. Fails, naming
 * the first mismatch, when a name is missing or its bind pose (inverse bind matrix) differs. */
cb_status cb_lod_remap(const cb_model *main, int32_t main_skin, const cb_model *lod, int32_t lod_skin, uint32_t *remap,
                       cb_error *err);

#ifdef __cplusplus
}
#endif

#endif
