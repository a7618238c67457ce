/* catalog.h - an animal catalog (a roster of animal types to bake) as plain structs, and the
 * roster logic that needs no file: state keywords, ground speed, LOD joint remapping.
 * formats/catalog_toml.cpp fills a cb_catalog from TOML; pipeline/roster.c bakes it. */
#ifndef CB_CATALOG_H
#define CB_CATALOG_H

#include "crowdbake/bake.h"
#include "crowdbake/locomotion.h"
#include "crowdbake/stride.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct cb_source_pos {
    uint32_t line, column; /* 1-based; 0 when unknown */
} cb_source_pos;

typedef struct cb_catalog_clip {
    const char *source; /* the clip's name in the model */
    const char *name;   /* its name in the palette */
    int loop;           /* -1 from the poses, 0, 1 */
    double fps;         /* 0: the animal's fps */
    int fps_auto;       /* -1: as the animal; 0: fixed fps; 1: fps = "auto" */
    double max_error_mm; /* 0: the animal's */
    cb_source_pos pos;
} cb_catalog_clip;

/* A state's playback: decided by crowdbake (cb_decide_sync), or the catalog's sync = "speed" |
 * "time". */
typedef enum cb_sync_mode { CB_SYNC_AUTO, CB_SYNC_SPEED, CB_SYNC_TIME } cb_sync_mode;

typedef struct cb_catalog_state {
    const char *name;
    const char **keywords;
    uint32_t keyword_count;
    cb_sync_mode sync;
    bool sync_from_command_line; /* sync was given by --sync (cb_catalog_override_states) */
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
    cb_catalog_clip *clips; /* NULL: the clips the states play and extra_clips (every clip without states) */
    uint32_t clip_count;
    cb_catalog_clip *extra_clips; /* baked beside the states' clips though no state plays them */
    uint32_t extra_clip_count;
    cb_catalog_state *states;
    uint32_t state_count;
    const char *default_state;
    const char *default_state_from; /* why: "the catalog's default_state", "decided by name ..." (cb_pick_default_state), the command line */
    double speed_reference; /* model units/s; with speed_auto, measured */
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
 * with those of `values`, recording CB_FROM_COMMAND_LINE: options given for one run win over
 * what [bake] and [animal] say. A clip's own fps and max_error still apply (clip_settings.h's
 * precedence). CB_BAKE_MAX_ERROR also makes max_error given (a fixed fps is checked). Fails, naming the animal, when an animal would write u16 texels to
 * EXR (which holds half or float only). */
cb_status cb_catalog_override_bake(cb_catalog *catalog, const cb_bake_settings *values, unsigned fields, cb_error *err);

/* The formats (CB_FORMAT_*) a catalog can write: those of the table of formats (outputs.h) that
 * are in_catalogs, at least one of which holds the palette (the manifest's palette and its
 * up-to-date facts are its): pal, exr and ktx2, and babylon (.bvat.json) beside any of them. */
bool cb_catalog_formats_valid(unsigned formats);

/* The command line's word on states, over the catalog's for this run: `syncs` is a comma-separated
 * list of STATE=speed|time|auto (NULL: none), `default_state` a state's name (NULL: none); each
 * applies to every animal with that state, and is an error when no animal has it. Counts in
 * what is up to date (the animals' canonical entries record it). */
cb_status cb_catalog_override_states(cb_catalog *catalog, const char *syncs, const char *default_state, cb_error *err);

/* The state a herd spawns in when the catalog names none (its index), decided by name and never
 * by the order the states are written in: the state whose name, else whose keywords, say it
 * rests (idle, stand, rest, breathe, graze, eat, sit, sleep, in that preference); else one whose
 * words say it is not an action done once; among equals the first by name (alphabetically).
 * Why, with "default_state or --default-state overrides", in `why`. */
uint32_t cb_pick_default_state(const cb_catalog_animal *animal, char *why, size_t size);

/* The one clip-name matcher, for the command line's --clip and a catalog's clips alike: the name
 * exactly, else regardless of case, else the part after an exporter's "Armature|" regardless of
 * case, else the one clip whose name holds it (`walk` for "AnimalArmature|Walk"). names[i] lies
 * `stride` bytes after names[i-1] (as cb_closest_name reads them). The index, or -1 with `why`
 * saying so: "no clip 'X'; did you mean 'Y'?", or the clips an ambiguous name fits. */
int cb_match_clip_name(const char *typed, const char *const *names, size_t count, size_t stride, char *why,
                       size_t size);

/* Index of the first clip whose name contains a keyword, trying keywords in order
 * (case-insensitive), or -1. */
int cb_match_state(const char *const *clip_names, uint32_t clip_count, const char *const *keywords,
                   uint32_t keyword_count);

/* Ground speed (cb_ground_speed, cb_measure_ground_speed) and the clip-alone locomotion decision: the
 * library's locomotion.h. */

/* Whether a state's clip follows the instance's speed (foot-sync: its rate is speed times
 * rate_per_speed) or plays at its own rate, and why in one line. Decided from, in order: the
 * catalog's sync for the state; a one-shot never follows speed; the words of the state's name,
 * then of its keywords, then of the clip's name (gaits such as walk, run, gallop, swim, fly
 * name locomotion; idle, eat, attack, hit, death and the like name actions in place); and
 * where no word decides, the clip's stride. Locomotion needs a ground speed (a stride or root
 * travel) unless the animal gives speed_reference. `state` may be NULL (a clip alone, as
 * `info` shows it). */
typedef struct cb_sync_decision {
    bool speed;         /* follows the instance's speed */
    char reason[512];
} cb_sync_decision;
void cb_decide_sync(const cb_catalog_state *state, const char *clip_name, bool loops, const cb_ground_speed *speed,
                    bool speed_given, cb_sync_decision *out);

/* For a LOD skin: remap[i] = the main skin's joint with the LOD joint i's name. Fails, naming
 * the first mismatch, when a name is missing or its bind pose (inverse bind matrix) differs. */
cb_status cb_lod_remap(const cb_model *main, int32_t main_skin, const cb_model *lod, int32_t lod_skin, uint32_t *remap,
                       cb_error *err);

#ifdef __cplusplus
}
#endif

#endif
