/* core.h - the core library: a skinned, animated model as plain C structs, glTF 2.0
 * animation sampling, clip framing and root motion.
 *
 * The core never reads or writes a file. formats/ fills a cb_model (gltf_load.h), the core
 * samples it, and formats/ writes the result. Every cb_model allocation lives in the model's
 * arena and is released by cb_model_free().
 */
#ifndef CROWDBAKE_H
#define CROWDBAKE_H

#include "export.h"

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#define CROWDBAKE_VERSION "0.1.0"
/* The library's API version: MAJOR changes break callers, MINOR ones add to the API. */
#define CROWDBAKE_API_VERSION_MAJOR 3
#define CROWDBAKE_API_VERSION_MINOR 2
#define CROWDBAKE_API_VERSION (CROWDBAKE_API_VERSION_MAJOR * 100 + CROWDBAKE_API_VERSION_MINOR)

#ifdef __cplusplus
extern "C" {
#endif

/* ---- errors --------------------------------------------------------------------------- */

/* What a library call reports. The command line maps each to its own exit codes
 * (cli/cli.h); the values are kept apart from them on purpose, so a new status never leaks
 * out as an exit code by accident. */
typedef enum cb_status {
    CB_OK = 0,
    CB_ERR_INTERNAL = 1, /* a bug or an allocation failure */
    CB_ERR_SETTINGS = 2, /* a setting out of range, or two that contradict each other */
    CB_ERR_BUDGET = 3,   /* the roster exceeds its VRAM budget (report) */
    CB_ERR_INPUT = 4,    /* an input file is invalid or unsupported */
    CB_ERR_IO = 5,       /* a file could not be read or written */
    CB_ERR_VERIFY = 6,   /* a verification threshold was exceeded, or a bake's error budget (max_error) */
    CB_ERR_LAYOUT = 7    /* the rig needs another layout: qpos cannot hold non-uniform scale or shear */
} cb_status;

/* The setting whose change would fix an error. The library words its messages without any
 * front end's vocabulary; a front end names the setting its own way (the command line as a
 * flag, see cli/cli.c), so the fix a message suggests is always one its user can type. */
typedef enum cb_setting {
    CB_SETTING_NONE = 0,
    CB_SETTING_MAX_FRAMES,         /* cb_limits.max_frames */
    CB_SETTING_MAX_JOINTS,         /* cb_limits.max_joints */
    CB_SETTING_MAX_PALETTE_BYTES,  /* cb_limits.max_palette_bytes */
    CB_SETTING_MAX_FILE_BYTES,     /* cb_limits.max_file_bytes */
    CB_SETTING_MAX_ACCESSOR_COUNT, /* cb_limits.max_accessor_count */
    CB_SETTING_MAX_TEXTURE_SIZE,   /* cb_bake_options.max_texture_size */
    CB_SETTING_LAYOUT,             /* cb_bake_options.layout */
    CB_SETTING_PRECISION,          /* cb_bake_options.precision */
    CB_SETTING_BATCH,              /* cb_mesh_options.batch */
    CB_SETTING_SYNC,               /* a catalog state's sync (cb_catalog_override_states) */
    CB_SETTING_DEFAULT_STATE,      /* a catalog animal's default_state */
    CB_SETTING_ROOT_MOTION,        /* cb_bake_settings.root_motion */
    CB_SETTING_FPS,                /* cb_bake_settings.fps (fixed) */
    CB_SETTING_MAX_FPS,            /* cb_bake_settings.max_fps */
    CB_SETTING_MAX_ERROR,          /* cb_bake_settings.max_error_mm */
    CB_SETTING_ALLOW_OVER_BUDGET,  /* cb_bake_settings.allow_over_budget */
    CB_SETTING_BONE_SPACE          /* cb_bake_settings.bone_space */
} cb_setting;

typedef struct cb_error {
    cb_status status;
    char message[512];
    cb_setting setting; /* CB_SETTING_NONE, or what would fix it */
} cb_error;

/* An error in model units as mm per metre of model height, the unit every error is reported
 * in so that models of any size compare (0 for a model without height). */
static inline double cb_mm_per_m(double error, double height) { return height > 0 ? error / height * 1000 : 0; }

/* Records the first error only; later ones are dropped so the root cause is reported. */
CROWDBAKE_API cb_status cb_fail(cb_error *err, cb_status status, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;
/* cb_fail for an error that changing `setting` would fix. */
CROWDBAKE_API cb_status cb_fail_setting(cb_error *err, cb_status status, cb_setting setting, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;

/* ---- limits --------------------------------------------------------------------------- */

/* The highest frame rate anything is baked or sampled at. */
#define CB_FPS_LIMIT 1000.0

typedef struct cb_limits {
    uint32_t max_joints;         /* joints in one skin */
    uint32_t max_frames;         /* frames in one clip at the chosen fps */
    uint64_t max_accessor_count; /* elements in one accessor */
    uint64_t max_file_bytes;     /* one input file (model, external buffer) */
    uint64_t max_palette_bytes;  /* one palette's texture */
} cb_limits;

CROWDBAKE_API cb_limits cb_default_limits(void);

/* ---- arenas: one owner for many small allocations ------------------------------------- */

typedef struct cb_arena cb_arena;

/* ---- the model ------------------------------------------------------------------------ */

typedef struct cb_node {
    const char *name;   /* never NULL; "node_N" when the file has none */
    int32_t parent;     /* -1 for a root */
    double translation[3];
    double rotation[4]; /* x, y, z, w; normalized */
    double scale[3];
    double matrix[16];  /* valid when has_matrix; then TRS above is its decomposition */
    bool has_matrix;
} cb_node;

typedef struct cb_skin {
    const char *name;
    uint32_t joint_count;
    int32_t *joints;       /* node indices */
    double *inverse_bind;  /* 16 per joint, column-major; identity when the file has none */
    int32_t skeleton;      /* node index or -1 */
} cb_skin;

/* What a primitive looks like, kept from the file so `crowdbake mesh` writes it back (API 3.0).
 * Only the base colour and what decides how it blends are kept: the runtimes draw an unlit or
 * simply lit base colour. */
typedef enum cb_alpha_mode { CB_ALPHA_OPAQUE, CB_ALPHA_MASK, CB_ALPHA_BLEND } cb_alpha_mode;

typedef struct cb_image {
    const char *mime_type;      /* "image/png", "image/jpeg", ...; "" when the file gives none */
    const unsigned char *bytes; /* the encoded image as stored (never decoded); owned by the model; NULL: see path */
    uint64_t size;
    /* An image in a file of its own (a uri beside the model): its path, read by `mesh` when it
     * writes it (a bake never draws it, so loading never reads it); NULL otherwise. */
    const char *path;
} cb_image;

typedef struct cb_texture {
    const cb_image *image;      /* NULL when the file's image is missing or broken (then the colour factor alone is kept) */
    int32_t mag_filter, min_filter, wrap_s, wrap_t; /* glTF sampler values; 0 for the filters when unset */
} cb_texture;

typedef struct cb_material {
    const char *name;                       /* never NULL; "" when the file has none */
    float base_color[4];                    /* pbrMetallicRoughness.baseColorFactor, linear RGBA */
    float metallic, roughness;              /* pbrMetallicRoughness factors */
    const cb_texture *base_color_texture;   /* NULL: none */
    uint32_t base_color_texcoord;           /* the TEXCOORD_n it reads (only TEXCOORD_0 is kept) */
    cb_alpha_mode alpha_mode;
    float alpha_cutoff;                     /* CB_ALPHA_MASK; 0.5 by default */
    bool double_sided;
} cb_material;

typedef struct cb_primitive {
    int32_t node;          /* the mesh node that uses it */
    int32_t skin;          /* index into cb_model.skins */
    uint32_t vertex_count;
    float *positions;      /* 3 per vertex, dequantized */
    float *normals;        /* 3 per vertex or NULL */
    float *texcoords;      /* TEXCOORD_0: 2 per vertex or NULL (carried into `crowdbake mesh` output) */
    uint16_t *joints;      /* 4 per vertex: indices into the skin's joints */
    float *weights;        /* 4 per vertex, as stored (not renormalized) */
    uint32_t index_count;
    uint32_t *indices;     /* index_count, or NULL for non-indexed */
    /* What a runtime uploads for it: one vertex of every attribute the file gives the
     * primitive, each as the file types it (after Draco/meshopt decoding) and padded to 4 bytes
     * as vertex attributes must be; an index as stored (8-bit indices widen to 16). */
    uint32_t vertex_bytes, index_bytes;
    const cb_material *material; /* NULL: glTF's default material (API 3.0) */
    float *colors;               /* COLOR_0 as linear RGBA (alpha 1 for RGB), 4 per vertex, or NULL (API 3.0) */
} cb_primitive;

typedef enum cb_path { CB_PATH_TRANSLATION, CB_PATH_ROTATION, CB_PATH_SCALE } cb_path;
typedef enum cb_interp { CB_INTERP_LINEAR, CB_INTERP_STEP, CB_INTERP_CUBICSPLINE } cb_interp;

typedef struct cb_channel {
    int32_t node;
    cb_path path;
    cb_interp interp;
    uint32_t key_count;
    float *times;   /* key_count, strictly increasing */
    float *values;  /* key_count * components, times 3 for CUBICSPLINE (in-tangent, value, out-tangent) */
} cb_channel;

typedef struct cb_animation {
    const char *name;   /* never NULL; "animation_N" when the file has none */
    uint32_t channel_count;
    cb_channel *channels;
    double t0, t1;      /* first and last key over all channels */
} cb_animation;

/* Bytes of model data, for cb_model.release. */
typedef struct cb_byte_range {
    const void *ptr;
    size_t bytes;
} cb_byte_range;

typedef struct cb_model {
    cb_arena *arena;
    const char *source;   /* the file it came from, for messages */
    uint32_t node_count;
    cb_node *nodes;
    uint32_t skin_count;
    cb_skin *skins;
    uint32_t primitive_count;
    cb_primitive *primitives;
    uint32_t animation_count;
    cb_animation *animations;
    uint32_t ignored_morph_channels; /* weights channels dropped at load */
    /* Clips left out at load because they cannot be sampled (no channels, a channel without
     * keys, NaN keys, ...), so one broken clip does not block a model's others. */
    uint32_t skipped_clip_count;
    struct cb_skipped_clip {
        const char *name;
        const char *reason; /* the whole one-line message: "FILE: clip 'x' has no channels" */
    } *skipped_clips;
    uint64_t source_hash; /* set by the loader: a hash of every byte it read (file and external buffers) */
    uint32_t external_file_count;
    const char **external_files; /* what the file referenced and the loader read (buffers, images) */
    /* Optional, set by a loader whose model data lies in memory it can drop and read again
     * unchanged (a read-only file mapping): release(release_ctx, ranges, count) is a hint that
     * those bytes will not be read for a while, so their memory may go; reading them later
     * gives the same bytes. NULL: nothing to release. See cb_model_release_clip. */
    void (*release)(void *release_ctx, const cb_byte_range *ranges, size_t count);
    void *release_ctx;
    /* The file's materials, textures and images, for the primitives' `material` (API 3.0). */
    uint32_t material_count;
    cb_material *materials;
    uint32_t texture_count;
    cb_texture *textures;
    uint32_t image_count;
    cb_image *images;
} cb_model;

/* Warnings and notes a command shows the user: on stderr, or in its --json output. */
typedef struct cb_warning {
    const char *kind; /* "warning" (something was left out or may be wrong) or "note" (worth knowing) */
    char *message;    /* one line, no "crowdbake:" prefix */
} cb_warning;

typedef struct cb_warnings {
    uint32_t count;
    cb_warning *items; /* owned; cb_warnings_free */
} cb_warnings;

/* Appends one; when out of memory it is dropped (a warning is never worth failing a bake). */
CROWDBAKE_API void cb_warn(cb_warnings *list, const char *kind, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;
CROWDBAKE_API void cb_warnings_free(cb_warnings *list);

/* An empty model with its own arena; NULL when out of memory. */
CROWDBAKE_API cb_model *cb_model_create(const char *source);
CROWDBAKE_API void cb_model_free(cb_model *model);
/* Zeroed memory owned by the model; NULL when out of memory. */
CROWDBAKE_API void *cb_model_alloc(cb_model *model, size_t count, size_t size);
CROWDBAKE_API const char *cb_model_strdup(cb_model *model, const char *s);

/* Checks what the core relies on: parents form a forest without cycles, joint and node
 * indices are in range, key times strictly increase, no value is NaN or infinite, skins
 * have joints, clips have channels. Rotation keys are normalized here. A clip that breaks a
 * rule is moved to skipped_clips with the reason, unless every clip does (then the first
 * reason is the error: nothing in the file could be baked). */
CROWDBAKE_API cb_status cb_model_validate(cb_model *model, const cb_limits *limits, cb_error *err);

/* Index of the skin named or numbered `name`, or -1. */
CROWDBAKE_API int32_t cb_model_find_skin(const cb_model *model, const char *name);
CROWDBAKE_API int32_t cb_model_find_animation(const cb_model *model, const char *name);
/* What loading left out: skipped clips (when skipped_clips: a command given its clips by name
 * does not care about others), ignored morph-weight channels. */
CROWDBAKE_API void cb_model_warnings(const cb_model *model, bool skipped_clips, cb_warnings *out);
/* The skipped clip named `name`, or NULL. */
CROWDBAKE_API const struct cb_skipped_clip *cb_model_find_skipped_clip(const cb_model *model, const char *name);
/* Tells the model's loader (cb_model.release) that the key times and values of `animation`
 * will not be read for a while: a big rig's keys are most of its file, and a bake reads one
 * clip's keys only while it samples or measures that clip. A hint: reading them later is
 * always allowed. Safe from several threads; does nothing without a release hook. */
CROWDBAKE_API void cb_model_release_clip(const cb_model *model, int32_t animation);
/* Vertices of the primitives that use `skin`. */
CROWDBAKE_API uint64_t cb_model_skin_vertex_count(const cb_model *model, int32_t skin);
/* Bytes of the vertex and index buffers of the primitives that use `skin`, in their own
 * vertex formats (cb_primitive.vertex_bytes, index_bytes). */
CROWDBAKE_API uint64_t cb_model_skin_mesh_bytes(const cb_model *model, int32_t skin);

/* ---- sampling ------------------------------------------------------------------------- */

/* Per-skin sampling state: evaluation order and scratch space. Not thread-safe; make one
 * per thread. */
typedef struct cb_sampler cb_sampler;

CROWDBAKE_API cb_sampler *cb_sampler_create(const cb_model *model, int32_t skin, cb_error *err);
CROWDBAKE_API void cb_sampler_free(cb_sampler *sampler);
CROWDBAKE_API const cb_model *cb_sampler_model(const cb_sampler *sampler);
CROWDBAKE_API int32_t cb_sampler_skin(const cb_sampler *sampler);

/* A loop without a closing key (cb_clip_analyze): from time `from` (its last key) to `to` (its
 * start plus its period) every channel returns to its first key. from = to = 0: none. */
typedef struct cb_wrap {
    double from, to;
} cb_wrap;

/* Sets the period of `animation` as a loop: when longer than its key span (a loop whose
 * exporter left out the closing key), times past the last key interpolate back to the first
 * key over the rest of the period instead of clamping. 0 (the default): times clamp.
 * cb_clip_analyze sets it on its sampler; another sampler of the same clips needs it set too. */
CROWDBAKE_API void cb_sampler_set_period(cb_sampler *sampler, int32_t animation, double period);

/* Joint matrices (16 doubles each, column-major, skin joint order) of `animation` at time t.
 * animation < 0 gives the rest pose. Times outside the clip clamp to its ends (or wrap, see
 * cb_sampler_set_period). */
CROWDBAKE_API void cb_sample_joint_matrices(cb_sampler *sampler, int32_t animation, double t, double *out);
/* Global (scene-space) matrices of every node at time t; out holds 16 * node_count. */
CROWDBAKE_API const double *cb_sample_globals(cb_sampler *sampler, int32_t animation, double t);

/* A joint matrix that is a similarity: x -> translation + scale * rotate(rotation, x). */
typedef struct cb_similarity {
    double rotation[4]; /* x, y, z, w; unit */
    double translation[3];
    double scale;       /* uniform, positive */
} cb_similarity;

/* Whether every transform from the skin's joints up to the scene root, every inverse bind
 * matrix and every scale key is a similarity (rotation, uniform positive scale, translation;
 * within 1e-6 relative). Then cb_sample_joint_similarities gives the joint matrices without
 * building, multiplying and decomposing 4x4 matrices: what the qpos layout stores, and the
 * qpos bake's sampling takes half the time. */
CROWDBAKE_API bool cb_sampler_is_similarity(const cb_sampler *sampler);
/* The joint matrices of cb_sample_joint_matrices as similarities (equal within the 1e-6
 * tolerance). Only for samplers where cb_sampler_is_similarity is true. */
CROWDBAKE_API void cb_sample_joint_similarities(cb_sampler *sampler, int32_t animation, double t, cb_similarity *out);
/* The same at `count` increasing times at once, bit for bit: out[i * joints + j] is joint j at
 * times[i]. The sampler runs each step over CB_SAMPLE_BATCH times at a time, which vectorizes:
 * several times the throughput of one time per call. */
#define CB_SAMPLE_BATCH 16
CROWDBAKE_API void cb_sample_joint_similarities_batch(cb_sampler *sampler, int32_t animation, const double *times,
                                                      uint32_t count, cb_similarity *out);

/* Evaluates one channel at time t into out (3 or 4 components). Exposed for tests. */
CROWDBAKE_API void cb_channel_eval(const cb_channel *channel, double t, double out[4]);

/* ---- clip framing --------------------------------------------------------------------- */

/* How a clip's root travel is baked: kept in the rows; taken out (in place, its average velocity
 * recorded for the game to move the instance); or taken out of the loops only, the one-shots
 * keeping theirs (a death fall lands where it lands; a travelling loop would be pulled back at
 * its wrap). */
typedef enum cb_root_motion { CB_ROOT_MOTION_KEEP, CB_ROOT_MOTION_IN_PLACE, CB_ROOT_MOTION_LOOPS_IN_PLACE } cb_root_motion;
/* "keep", "in-place" or "loops-in-place" (its parser: the internal plumbing.h). */
CROWDBAKE_API const char *cb_root_motion_name(cb_root_motion root_motion);

/* Why a clip was judged a loop or a one-shot (cb_clip_info.loop_reason). */
typedef enum cb_loop_reason {
    CB_LOOP_SET,          /* the caller said (a catalog's loop = true/false) */
    CB_LOOP_CLOSED,       /* the last pose is the first: a loop over the key span */
    CB_LOOP_OPEN,         /* no closing key: the first pose comes round one key step after the last */
    CB_LOOP_ENDS_ELSEWHERE, /* the wrap from the last pose to the first is a jump: a one-shot */
    CB_LOOP_CLOSED_CORRECTED /* the last key is the closing key slightly off (a wrap well under its neighbour
                              * steps): a loop over the key span, its mismatch spread over the cycle
                              * (cb_sampler_set_loop) */
} cb_loop_reason;

typedef struct cb_clip_info {
    int32_t animation;
    double t0, t1;           /* first and last key */
    double duration;         /* playback length: t1 - t0, plus one key interval for a loop without a closing key */
    bool loops;
    cb_loop_reason loop_reason;
    double key_interval;     /* the clip's key step (the shortest interval between keys), 0 if none */
    double wrap_jump, largest_step; /* pose distances (cb_pose_distance) of the wrap and of the bigger of its
                                     * neighbour key steps (the first and the last) */
    /* The loop decision's evidence, each + for a loop and - for a one-shot; the clip loops when
     * their sum is above 0 (cb_loop_reason_text says it in words). loop_set: the caller decided
     * (loop_override), and none of them was weighed. */
    bool loop_set;
    double loop_name;        /* its name's words: +2 a cycle (walk, gallop, idle, eat), -3 an action done once
                              * (attack, hit, death, punch), -1 a jump; a once word outweighs a cycle word */
    char loop_word[48];      /* the words that decided loop_name, "" when none */
    double loop_pose;        /* its poses: +2 last = first; log2(neighbour step / wrap) clamped to +-2 */
    double loop_feet;        /* its feet: +1 when they stride played as a loop, else 0; measured only where it can
                              * turn the sum (loop_feet_weighed) */
    bool loop_feet_weighed;
    uint32_t loop_striding_feet;
    uint32_t steps;          /* N = max(1, round(duration * fps)) */
    uint32_t frames;         /* rows baked: N for loops, N + 1 for one-shots */
    double effective_fps;    /* N / duration; the requested fps for a zero-length clip */
    double root_displacement[3]; /* root joint travel from t0 to t1, scene units */
    double root_velocity[3];     /* average velocity (displacement / duration); y is kept */
    double ground_speed;         /* |velocity.xz| */
    /* CB_LOOP_CLOSED_CORRECTED: the largest distance of any vertex from where the source puts it
     * that the loop-closing correction makes (at the clip's ends, where it is half the mismatch),
     * in mm per metre of the mesh's rest height; 0 for any other clip. Appended in API 3.0. */
    double loop_correction_mm_per_m;
    /* The biggest pose step between keys over the whole clip (cb_pose_distance), measured where
     * the wrap is no bigger than its neighbour steps (CB_LOOP_OPEN or CB_LOOP_CLOSED_CORRECTED),
     * else 0: a wrap under CB_LOOP_CORRECTABLE of it is a closing key slightly off. Appended in
     * API 3.0. */
    double largest_key_step;
} cb_clip_info;

/* Whether a clip is baked in place under a root motion mode. */
CROWDBAKE_API bool cb_root_motion_in_place(cb_root_motion root_motion, const cb_clip_info *clip);

/* In-place bakes take the root's average horizontal travel, velocity * tau, off every joint at
 * clip time t (from the clip's start). tau = t over the keys (span); a loop without a closing
 * key returns to its first pose over its last interval, from span to duration, and so does
 * the travel taken off (tau falls back to 0): the in-place loop ends where it starts. */
CROWDBAKE_API double cb_root_travel_time(double t, double span, double duration, bool loops);

/* The shortest interval between keys of any channel of the clip (exporters that bake keys
 * sample every channel at one rate), ignoring intervals under 0.1 ms; 0 when none. */
CROWDBAKE_API double cb_animation_key_interval(const cb_animation *animation);

/* Frame count rule: N = max(1, round(D * fps)); loops bake N rows, one-shots N + 1. */
CROWDBAKE_API uint32_t cb_clip_step_count(double duration, double fps);
/* Time of row i: t0 + i * D / N. */
CROWDBAKE_API double cb_clip_frame_time(const cb_clip_info *clip, uint32_t frame);

/* Measures a clip: duration, loop test, root motion and framing at `fps`. loop_override is
 * -1 (decide from the poses), 0 or 1. */
CROWDBAKE_API cb_status cb_clip_analyze(cb_sampler *sampler, int32_t animation, double fps, int loop_override,
                                        const cb_limits *limits, cb_clip_info *out, cb_error *err);
/* Sets the sampler up to play an analyzed clip as cb_clip_analyze framed it: its period
 * (cb_sampler_set_period: the clip's duration for a loop, 0 for a one-shot) and, for a loop whose
 * last key is its closing key slightly off (CB_LOOP_CLOSED_CORRECTED), the loop-closing
 * correction: each channel's mismatch between its last and first key spread linearly over the
 * key span, half at each end (rotations by the delta's slerp), the root's horizontal travel
 * kept. Every sampler that samples the clip (bake, verify, a writer's own) needs it set. False
 * when out of memory (the clip then plays uncorrected). */
CROWDBAKE_API bool cb_sampler_set_loop(cb_sampler *sampler, const cb_clip_info *clip);
/* The same for a clip as a bake wrote it (a .pal's loops, start and duration, its model's
 * animation): a loop over exactly its key span is judged again, and closed when the bake
 * closed it. verify and writers that sample a baked palette's clips use it. */
CROWDBAKE_API bool cb_sampler_set_baked_loop(cb_sampler *sampler, int32_t animation, bool loops, double start,
                                             double duration);
/* An analyzed clip framed at another fps (steps, frames, effective_fps), as cb_clip_analyze at
 * that fps frames it, without analyzing it again: a clip baked at many rates (--fps auto's
 * search) is analyzed once. */
CROWDBAKE_API cb_status cb_clip_frame_at(const cb_model *model, double fps, const cb_limits *limits,
                                         cb_clip_info *clip, cb_error *err);

/* Joint matrices of a framed clip's row, with root motion removed when asked: in-place
 * subtracts the root's average horizontal travel, velocity.xz * (t - t0), from every joint. */
CROWDBAKE_API void cb_clip_frame_matrices(cb_sampler *sampler, const cb_clip_info *clip, uint32_t frame,
                                          cb_root_motion root_motion, double *out);
/* The same as similarities, for samplers where cb_sampler_is_similarity is true, at `count`
 * increasing frames: out[i * joints + j] is joint j at frames[i]. */
CROWDBAKE_API void cb_clip_frame_similarities(cb_sampler *sampler, const cb_clip_info *clip, const uint32_t *frames,
                                              uint32_t count, cb_root_motion root_motion, cb_similarity *out);
/* A similarity as a 4x4 matrix. */
CROWDBAKE_API void cb_similarity_matrix(const cb_similarity *s, double out[16]);

/* The skin's root joint (the top-most joint), as an index into its joints. */
CROWDBAKE_API uint32_t cb_skin_root_joint(const cb_model *model, int32_t skin);

/* ---- skinning ------------------------------------------------------------------------- */

/* Linear blend skinning in double precision: out[3 * v] = sum_i w_i * M_{j_i} * p_v, with
 * the weights as stored (glTF requires them to sum to 1). joint_mats: 16 per skin joint. */
CROWDBAKE_API void cb_skin_positions(const cb_primitive *prim, const double *joint_mats, double *out);

/* Axis-aligned bounds of the skin's meshes in the rest pose (skinned with the rest-pose joint
 * matrices): min[3], max[3]. Returns the height (max.y - min.y). */
CROWDBAKE_API double cb_skin_rest_bounds(cb_sampler *sampler, double min[3], double max[3]);

#ifdef __cplusplus
}
#endif

#endif
