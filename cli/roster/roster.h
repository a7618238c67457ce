/* roster.h - bakes a whole catalog: one palette per animal type (shared between types whose
 * rigs and clips are identical), a roster manifest, a depfile; incremental and parallel. */
#ifndef CB_ROSTER_H
#define CB_ROSTER_H

#include <stdio.h>

#include "catalog/catalog.h"
#include "internal/json.h"
#include "crowdbake/mesh.h"
#include "crowdbake/socket.h"
#include "crowdbake/plant_feet.h"

#ifdef __cplusplus
extern "C" {
#endif

/* `bake CATALOG --type NAME`: a manifest fragment in place of the manifest (roster_fragment.c).
 * It records what the manifest says of the type and the run's state options, which the merge
 * applies to the catalog again. */
typedef struct cb_roster_fragment {
    const char *path;
    const char *syncs, *default_state; /* --sync and --default-state as given, or NULL */
} cb_roster_fragment;

typedef struct cb_roster_options {
    uint32_t jobs;          /* types baked at once */
    bool force;             /* re-bake what is up to date */
    FILE *log;              /* one line per type, or NULL */
    bool tty;               /* log is a terminal: show progress */
    FILE *progress;         /* a line per type as each is done, in the order they finish ("crowdbake: [2/4] goat:
                             * baked 247 rows in 10 ms"), or NULL */
    const char *manifest;   /* roster.json path; NULL: OUT_DIR/roster.json */
    const char *depfile;    /* Make/Ninja depfile, or NULL */
    bool depfile_manifest_only; /* the depfile's one rule is the manifest's (Ninja's `depfile` without `deps = gcc`) */
    const char *tool;       /* the crowdbake executable, or NULL: an input of every output in the depfile, so that a
                             * new build of the tool re-runs the bake (which decides per type what it changes) */
    const cb_roster_fragment *fragment; /* write this fragment instead of the manifest, or NULL */
    const cb_limits *limits; /* for loading and baking; NULL: the defaults */
    bool measure_vat;       /* also measure each type's VAT error (half-float positions) for the report */
    /* How the front end names a setting (cb_error.setting) in a failed type's line, or NULL. */
    const char *(*setting_name)(cb_setting setting);
} cb_roster_options;

typedef enum cb_type_outcome { CB_TYPE_BAKED, CB_TYPE_UP_TO_DATE, CB_TYPE_SHARED, CB_TYPE_FAILED } cb_type_outcome;

typedef struct cb_roster_clip {
    char name[128];
    uint32_t first_row, frames;
    double fps, duration;
    bool loops;
    bool step;             /* its rows held, not blended (cb_clip_plan.step): the instance's first row is -first - 1 */
    char loop_reason[384]; /* why it loops or plays once (cb_loop_reason_text) */
    double visible_error_mm; /* the worst error a player sees in it, mm per metre of model height (the bake's
                              * cb_clip_budget.error_mm, kept in the type's record); -1 where no bake measured it
                              * (a record lost beside an up-to-date palette: the files record only the type's) */
    char rate_reason[320];   /* why its rate and rows (cb_bake_clip_reason, as `crowdbake bake` says it) */
    bool in_place;         /* its root travel taken out (the job's root motion, cb_root_motion_in_place) */
    cb_ground_speed speed; /* speed.speed is the clip's ground speed */
    cb_plant_clip plant;   /* with plant_feet, what planting its feet changed (plant.planted: it did) */
    cb_row_travel travel;  /* its per-row travel offset, as the bake decides it (cb_bake_job_row_travel) */
    uint32_t cells, map_rows; /* timed rows (cells > 0; docs/pal-format.md "Timed rows"): its map's cells and rows,
                               * the map just before first_row; frames counts its rows */
    double cell_rate;
} cb_roster_clip;

typedef struct cb_roster_lod {
    const char *path;
    uint32_t joint_count;
    uint32_t *remap;          /* joint_count entries */
    uint64_t vertices, indices;
} cb_roster_lod;

typedef struct cb_roster_type {
    const cb_catalog_animal *animal;
    cb_type_outcome outcome;
    cb_error error;
    uint32_t owner;           /* the type whose palette file this type uses */
    uint64_t key;             /* content hash of rig, clips and settings: equal keys share */
    uint64_t input_hash;      /* key + model and LOD bytes + the resolved entry: recorded in the files */
    char paths[CB_OUTPUT_MAX][1024]; /* per row of the table of formats (outputs.h): OUT_DIR/NAME.EXT */
    uint32_t bones, rows, width, height, blocks;
    cb_layout layout;
    cb_precision precision;
    uint64_t vertices, indices, palette_bytes; /* palette_bytes: the texture as uploaded */
    uint64_t mesh_bytes;      /* vertex and index buffers in the model's own vertex format */
    uint64_t file_bytes;      /* the palette file the log names (roster_palette_path) */
    float max_error, visible_error; /* see cb_palette; float32 as the files record them, so an up-to-date run reports the same */
    double model_height, speed_reference, seconds;
    char speed_reference_from[512]; /* which rule picked speed_reference, in words */
    double vat_error;         /* with measure_vat */
    bool vat_measured;        /* vat_error holds a measure (this run's, or its record's: a report reuses it) */
    uint32_t clip_count;
    cb_roster_clip *clips;
    int *state_clip;          /* per catalog state: index into clips */
    cb_sync_decision *state_sync; /* per catalog state: follows the speed or not, and why */
    uint32_t lod_count;
    cb_roster_lod *lods;
    uint32_t socket_count;
    cb_socket *sockets;       /* where props attach (socket.h) */
    cb_lod_error lod_error;   /* what skinning with fewer influences costs (mesh.h), for the runtimes' animation LOD */
    uint32_t input_count;
    char **inputs;            /* every file read for it: model, LODs, their external buffers */
    cb_warnings warnings;     /* clips skipped at load, the layout's fallback, ... */
    bool prepared_from_record; /* its record (roster_cache.h) matched its files: nothing was loaded or sampled */
    uint32_t error_rows_measured; /* baked this run: the rows its errors were measured at (cb_palette's), else 0 */
} cb_roster_type;

typedef struct cb_roster {
    const cb_catalog *catalog;
    uint32_t type_count;
    cb_roster_type *types;
    uint32_t baked, up_to_date, shared, failed;
    char manifest_path[1024];
    bool manifest_written;
} cb_roster;

/* Bakes every type; failures are recorded per type and the others still bake. Returns the
 * status of the first failure (by name), or CB_OK. */
cb_status cb_roster_bake(const cb_catalog *catalog, const cb_roster_options *options, cb_roster *out, cb_error *err);
void cb_roster_free(cb_roster *roster);

/* `crowdbake roster merge`: reads the fragments `bake CATALOG --type NAME` wrote, one per type
 * of their catalog (which it loads, as `catalog`, applying the state options they record), and
 * writes the manifest at `manifest`, byte-identical to the one `bake CATALOG` writes: types
 * whose content keys are equal share the palette of the first by name. Fails naming a missing,
 * repeated or damaged fragment; a type that failed is listed as failed and fails the merge. */
cb_status cb_roster_merge(char *const *fragments, uint32_t count, const char *manifest, cb_catalog *catalog,
                          cb_roster *out, cb_error *err);

/* A clip's stride as the manifest and `info --json` give it: "stride", "stride_reason" and, for
 * a stride, "foot_slide": how much each planted foot slides at the clip's ground speed
 * (fractions of that speed, mean and worst over the foot's stance). */
void cb_roster_json_stride(cb_json *j, const cb_stride *stride);
/* What planting a clip's feet changed (crowdbake/plant_feet.h), into an open object: the manifest's
 * plant_feet, bake and info --json's. */
void cb_roster_json_plant(cb_json *j, const cb_plant_clip *plant);
/* A clip's per-row travel (row_travel.h) as the manifest and `info --json` give it: "row_travel"
 * with "applied", "reason" and, where measured, the slide without and with the offsets. */
void cb_roster_json_row_travel(cb_json *j, const cb_row_travel *travel);
/* "sockets": [{name, bone, bind_transform}], as the manifest and `info --json` give them. */
void cb_roster_json_sockets(cb_json *j, const cb_socket *sockets, uint32_t count);

/* A type's file of `format` (a CB_FORMAT_* bit; "" for a format it does not write), and the file
 * that stands for its palette: the first of its formats, in the table's order, that holds one
 * (roster_fresh.c). */
const char *roster_output_path(const cb_roster_type *t, unsigned format);
const char *roster_palette_path(const cb_roster_type *t);
/* Its .pal holds local rows: bone_space "local" on a qpos palette (a rig qpos cannot hold is baked global). */
bool roster_local_rows(const cb_roster_type *t);

#ifdef __cplusplus
}
#endif

#endif
