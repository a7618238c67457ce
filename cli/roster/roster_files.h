/* roster_files.h - the roster bake's pieces beside its passes: the content key, and the files
 * beside its palettes (private to libcrowdbake). */
#ifndef CB_ROSTER_FILES_H
#define CB_ROSTER_FILES_H

#include <stdio.h>

#include "crowdbake/bake.h"
#include "roster/roster.h"

/* "CATALOG:LINE:COLUMN" of a place in the catalog, into buf. */
const char *roster_at(const cb_catalog *cat, cb_source_pos pos, char *buf, size_t size);

/* The clips a type bakes, in row order, with their catalog requests, and t->clips allocated
 * (roster_clips.c): the catalog's clips list, else the states' clips and extra_clips (a note
 * names what was left out), else every clip. */
cb_status roster_plan_clips(const cb_catalog *cat, const cb_catalog_animal *an, const cb_model *m, cb_clip_plan **plan,
                            cb_clip_request **requests, cb_roster_type *t, cb_error *err);
/* Fails naming the state whose keywords match none of `names` (the clips it could play). */
cb_status roster_state_matches_none(const cb_catalog *cat, const cb_catalog_animal *an, const cb_catalog_state *st,
                                   const char *const *names, uint32_t count, cb_error *err);
/* Each state's clip (state_clip), by its keywords; fails naming the state that matches none. */
cb_status roster_match_states(const cb_catalog *cat, const cb_catalog_animal *an, cb_roster_type *t, cb_error *err);
/* Which states follow the speed (state_sync, cb_decide_sync) and the speed reference; fails
 * where a state must follow the speed but nothing gives it one (roster_states.c). */
cb_status roster_decide_states(const cb_catalog *cat, const cb_catalog_animal *an, cb_roster_type *t, cb_error *err);
/* A warning per speed-synced clip whose feet slide however it is played (cb_stride). */
void roster_warn_foot_slide(cb_roster_type *t);
/* With plant_feet: a note per clip whose feet were planted, with what it changed (its slide
 * before and after, the largest joint rotation change). */
void roster_note_planted(const cb_bake_job *job, cb_roster_type *t);

/* The content key of a type's rig, planned clips and settings (roster_key.c). */
uint64_t roster_content_key(const cb_model *m, int32_t skin, const cb_clip_plan *plan, uint32_t n, const cb_bake_settings *b);

/* The catalog's models, each loaded once when a type first needs it and shared read-only by
 * every type naming it (roster_models.c). */
#include <threads.h>
struct roster_model;
typedef struct roster_models {
    struct roster_model *items;
    uint32_t count;
    const cb_limits *limits;
} roster_models;
bool roster_models_init(roster_models *ms, const cb_catalog *cat, const cb_limits *limits); /* false: no memory */
/* The model at `path` (one of the catalog's), loading it if no type has; NULL with *err (the
 * load's error, the same for every type) when it cannot be loaded. Thread-safe. */
const cb_model *roster_model_get(roster_models *ms, const char *path, cb_error *err);
void roster_models_free(roster_models *ms);

/* A type's plan worked out once per plan key (roster_plans.c): types whose model bytes, skin,
 * clips and settings are equal plan the same rates and sample the same facts, so the first type
 * to need them works them out and the others copy them. */
typedef struct roster_plan_facts { /* what sampling the planned clips found, for the manifest */
    uint32_t clip_count, rows;
    cb_roster_clip *clips;
    double model_height;
    uint32_t socket_count;
    cb_socket *sockets;
    bool vat_measured;
    double vat_error;
    cb_lod_error lod_error;
} roster_plan_facts;
typedef struct roster_plan roster_plan;
typedef struct roster_plans {
    roster_plan *items;
    uint32_t count, capacity;
    mtx_t lock;
} roster_plans;
bool roster_plans_init(roster_plans *ps, uint32_t capacity); /* false: no memory */
void roster_plans_free(roster_plans *ps);
/* Everything planning reads: the model's source hash (its bytes), the skin, the clips asked for
 * with their catalog requests, and the settings (not out_dir). */
uint64_t roster_plan_key(const cb_model *m, int32_t skin, const cb_clip_plan *plan, const cb_clip_request *requests,
                         uint32_t n, const cb_bake_settings *b);
/* The plan of `key`, locked (the caller holds it while it plans, so a type of the same key
 * waits, then copies); NULL when none can be made (the caller plans alone). */
roster_plan *roster_plan_claim(roster_plans *ps, uint64_t key);
void roster_plan_release(roster_plan *p); /* NULL: nothing */
bool roster_plan_known(const roster_plan *p);
/* Keeps a planned job's plan and its facts (copies) unless the plan is known already. */
void roster_plan_keep(roster_plan *p, const cb_bake_job *job, const roster_plan_facts *facts);
/* Sets the job's plan as planned and *facts (arrays of its own) from a known plan; false (the
 * job untouched) when it is not known or memory ran out. */
bool roster_plan_copy(const roster_plan *p, cb_bake_job *job, roster_plan_facts *facts);

/* Owners of shared palettes (roster_share.c): among types with equal content keys, the first
 * by name owns the palette, the others' owner is set to it and their outcome to shared. */
void roster_assign_owners(cb_roster *r);
/* Shared type i once its owner is settled: its owner's files and geometry, counted as shared;
 * or failed with its owner (false). */
bool roster_settle_shared(cb_roster *r, uint32_t i);
/* The fragment of a roster of one type (roster_fragment.c), written only when its bytes change. */
cb_status roster_write_fragment(const cb_roster *r, const cb_roster_fragment *fragment, cb_error *err);

/* mkdir -p: a directory and any missing parents; or the folder a file goes in. */
cb_status roster_make_directories(const char *dir, cb_error *err);
cb_status roster_make_parent_directories(const char *file, cb_error *err);
/* Writes `data` to path (temporary file + rename) unless the file already holds exactly it. */
cb_status roster_write_if_changed(const char *path, const char *data, size_t size, bool *written, cb_error *err);
/* roster.json (docs/roster.schema.json), rewritten only when its bytes change (r->manifest_written). */
cb_status roster_write_manifest(const cb_catalog *cat, cb_roster *r, const char *path, cb_error *err);
/* opt->depfile: one rule per output, Make and Ninja both read it; or (opt->depfile_manifest_only)
 * one rule, the manifest's, as Ninja wants it for a rule with `depfile` but no `deps = gcc`
 * (CMake's DEPFILE). Each rule names the catalog, the models' files and opt->tool. */
cb_status roster_write_depfile(const cb_catalog *cat, const cb_roster *r, const cb_roster_options *opt, cb_error *err);
/* A type's prep record (roster_cache.h), rewritten only when its bytes change; a failure is
 * ignored (the next run prepares the type again). */
void roster_write_record(const char *path, const unsigned char *data, size_t size);
/* After a failure the manifest and the failed palettes get the epoch (the next build runs
 * again); after a success the manifest is never older than an input, nor than `tool` (the
 * executable the depfile names; NULL: none). */
void roster_settle_times(const cb_roster *r, const char *tool);
/* order[0..type_count): the types, the longest (a guess) first (roster_order.c). */
void roster_order_types(const cb_catalog *cat, const cb_roster *r, bool prepared, uint32_t *order);

/* Format "babylon" (roster_babylon.c): the row clip `clip` starts at in the .bvat.json (its
 * clips' closing rows counted; clip_count: the file's height); "babylon": {from, to, fps} of a
 * clip, as a state in the manifest gives it; the states the file lists (malloc'd, NULL when out
 * of memory); whether the file on disk holds this bake (its input hash and rows). */
struct cb_babylon_state;
uint32_t roster_babylon_from(const cb_roster_type *t, uint32_t clip);
void roster_json_babylon_play(cb_json *j, const cb_roster_type *t, uint32_t clip);
struct cb_babylon_state *roster_babylon_states(const cb_catalog_animal *an, const cb_roster_type *t);
bool roster_babylon_up_to_date(const cb_roster_type *t);
/* True when every output in `formats` exists and records this key; fills the geometry from the
 * first format, in the table's order, that holds the palette (roster_fresh.c). */
bool roster_outputs_up_to_date(cb_roster_type *t, unsigned formats);

/* The roster's log in catalog order (roster_log.c): each type's lines are held until every type
 * before it has printed, so the log reads the same whatever order the threads finish in. The
 * caller serialises the calls. */
typedef struct roster_log {
    FILE *out;
    char **held;     /* per type: its lines once it is settled, until they are printed */
    uint32_t count, next; /* next: the first type not printed yet */
} roster_log;
bool roster_log_init(roster_log *log, FILE *out, uint32_t count); /* false: no memory (lines print as they come) */
/* Type i's lines (malloc'd, taken over; NULL prints nothing): printed now, with the held lines of
 * the types after it, once every type before it has printed. */
void roster_log_put(roster_log *log, uint32_t i, char *text);
void roster_log_free(roster_log *log);

#endif
