/* conformance.h - the runtime conformance cases (runtimes/README.md): one set of palettes, instance
 * states and expected skinned positions, made once by the C runtime, that every runtime's test reads.
 *
 * conformance_make(c, dir) bakes, with the command, the quadruped sample in every layout x precision,
 * the same wrapped into two column blocks, and multitrack's spinning bones (qpos/float); writes each
 * mesh (NAME.positions float32 x3, NAME.joints u16 x4, NAME.weights float32 x4), dir/cases.json, and
 * for every case dir/CASE.expected: the skinned position of every vertex of every instance of every
 * group, float32, in that order, as the C runtime (src/core/runtime.c) gives them.
 *
 * cases.json: {"cases": [{name, pal, mesh: {positions, joints, weights}, groups: [{time, instances:
 * [[16 floats], ...]}], expected, out, transpose, glsl_break: {marker, line}, bone_pass, broken}]}. An
 * instance is 16 floats: [4..7] the clip (first row, frames - negative for a one-shot -, fps x rate,
 * phase), [8..11] the clip it cross-fades from, [12] the fade's start time and [13] its length (0: no
 * fade). A case marked local (local_qpos_u16, local_qpos_float, local_blocks: .pal version 6, the
 * quadruped baked --bone-space local --fps 30) holds local rows: the runtime blends each bone's rows
 * and composes down the skeleton (docs/pal-format.md); a shader runtime runs them once its library
 * knows CB_LOCAL_ROWS. A case marked timed (timed_*, broken-timed-map-ignored: .pal version 7, made from
 * uniform bakes by timed_subset.h) holds timed clips, whose instances are (first row, +-cells, -cell_rate x rate,
 * phase): the runtime reads each cell's rows and weights from the clip's map (docs/pal-format.md "Timed rows");
 * a runtime that does not know them fails these cases. A case marked broken carries the fault a runtime applies to show its test catches it:
 * transpose (each mat4 bone stored transposed), a row offset (in the instances: rows one off), the timed map
 * ignored (in the instances: +-frames and a positive rate, the rows played uniform), or
 * glsl_break (the line of the shipped shader holding `marker` replaced by `line`); its expected
 * positions are the right ones, which the broken runtime must miss by far.
 *
 * Header-only, like testutil.h: a test that includes it compiles it. */
#ifndef CROWDBAKE_TEST_CONFORMANCE_H
#define CROWDBAKE_TEST_CONFORMANCE_H

#include "testutil.h"

#include <limits.h>
#include <math.h>
#include <unistd.h>

#include "crowdbake_pal.h"
#include "crowdbake/pal_view.h"
#include "crowdbake/runtime.h"
#include "runtimes/shader_source.h"
#include "timed_subset.h"

#define CONF_TIMES 2
#define CONF_PER_CLIP 7 /* instances per clip and time */
#define CONF_PALETTES 32
#define CONF_MAX_CASES 40

static const double conf_times[CONF_TIMES] = {0.77, 2.31};
static const char *const conf_layouts[] = {"mat4", "affine", "qpos"};
static const char *const conf_precisions[] = {"float", "half", "u16"};

/* A baked palette opened as the C runtime reads it, and its model. */
typedef struct conf_palette {
    char file[48], mesh[16];
    cb_model *model;
    cbpal_file pal;
    cb_palette view;
} conf_palette;

typedef struct conf_case {
    char name[40];
    int palette;       /* index into conformance.palettes */
    double row_offset; /* broken: the instances' rows shifted */
    bool transpose, broken, local; /* local: local rows (.pal version 6), composed by the runtime */
    bool timed;        /* timed rows (.pal version 7): some clips' rows through their map */
    int right;         /* broken-timed-map-ignored: the palette whose clips are timed (palette: the same file, its
                        * clips read as untimed), which the expected positions come from */
    const char *glsl_marker, *glsl_line, *bone_pass; /* bone_pass: Crowd's bonePass option, as JSON */
} conf_case;

typedef struct conformance {
    const char *dir;
    conf_palette palettes[CONF_PALETTES];
    conf_case cases[CONF_MAX_CASES];
    int palette_count, case_count;
} conformance;

/* A timed clip's instance k (cb_instance_of: first row, +-cells, -cell_rate, phase) at `time`: cells'
 * interiors (0.3, 2.5, 37%), the loop's seam or a one-shot's last cell, a one-shot past its end (a
 * loop: a golden-ratio spread), one cross-fading from the same clip at another phase (a 0.5 fade at
 * `time`), and the last as every clip's (from its first row held). */
static inline void conf_timed_instance(const cb_palette_clip *c, double time, int k, float v[16])
{
    double n = c->cells, rate = c->cell_rate;
    double targets[] = {0.3, 2.5, n * 0.37, n - 0.4, c->loops ? 0.618034 * n : n + 2, 0.236068 * n};
    double phase = k < 6 ? (targets[k] - time * rate) / n : fmod((k - 3) * 0.6180339887, 1.0);
    if (c->loops) phase -= floor(phase);
    v[5] = (float)(c->loops ? n : -n), v[6] = (float)-rate, v[7] = (float)phase;
    if (k == 5) { /* from: the same clip, timed, at another phase */
        double from = c->loops ? 0.7 : (0.55 * n - time * rate) / n; /* a one-shot's: 55% through at `time` */
        v[8] = v[4], v[9] = v[5], v[10] = v[6], v[11] = (float)from;
        v[12] = (float)(time - 0.25), v[13] = 0.5f;
    }
}

/* Instance k of a clip at `time`: phases that land on mid-frames, the loop seam and golden-ratio
 * spreads; the last one cross-fades from the clip's first row held (a 0.5 fade at `time`). A timed
 * clip's: conf_timed_instance. */
static inline void conf_instance(const cb_palette_clip *c, double time, int k, double row_offset, float out[16])
{
    double frames = c->frames, rate = c->fps;
    double targets[] = {0.3, 2.5, frames * 0.37, frames - 0.4 /* the seam */};
    double phase = k < 4 ? (targets[k] - time * rate) / frames : fmod((k - 3) * 0.6180339887, 1.0);
    if (c->loops) phase -= floor(phase);
    double first = c->step ? -(double)c->first_row - 1 : c->first_row; /* held rows: -first - 1 (cb_instance_of) */
    float v[16] = {0, 0, 0, 0, (float)(first + row_offset), (float)(c->loops ? frames : -frames), (float)rate,
                   (float)phase, 0, 0, 0, 0, 0, 0, 1, 0};
    if (c->timed || c->cells) conf_timed_instance(c, time, k, v);
    if (!c->timed && c->cells) { /* conf_map_ignored's: the same clip times, its rows played uniform */
        v[5] = v[9] = (float)(c->loops ? frames : -frames), v[6] = v[10] = (float)rate;
        if (k != 5) v[9] = v[10] = 0;
    }
    if (k == CONF_PER_CLIP - 1) { /* from: the first row, still; fade 0.5 at `time` */
        v[8] = (float)(c->first_row + row_offset), v[9] = 1, v[10] = 0, v[11] = 0;
        v[12] = (float)(time - 0.25), v[13] = 0.5f;
    }
    memcpy(out, v, sizeof v);
}

/* How many positions a case holds: groups x clips x instances x vertices. */
static inline size_t conf_positions(const conformance *c, const conf_case *k)
{
    const conf_palette *p = &c->palettes[k->palette];
    return (size_t)CONF_TIMES * p->view.clip_count * CONF_PER_CLIP * p->model->primitives[0].vertex_count;
}

static inline void conf_write(const char *dir, const char *name, const char *suffix, const void *data, size_t n)
{
    char path[PATH_MAX];
    snprintf(path, sizeof path, "%s/%s%s", dir, name, suffix);
    FILE *f = fopen(path, "wb");
    if (!f || fwrite(data, 1, n, f) != n) fail_msg("cannot write %s", path);
    fclose(f);
}

/* Bakes `model` with the command into dir/FILE and opens it; writes its mesh once per stem. Global rows unless the
 * options name a bone space (the local cases: conf_define_local_cases). */
static inline int conf_bake(conformance *c, const char *model, const char *file, const char *mesh, const char *options)
{
    conf_palette *p = &c->palettes[c->palette_count];
    snprintf(p->file, sizeof p->file, "%s", file);
    snprintf(p->mesh, sizeof p->mesh, "%s", mesh);
    char cmd[3 * PATH_MAX], path[PATH_MAX], err[512];
    snprintf(path, sizeof path, "%s/%s", c->dir, file);
    snprintf(cmd, sizeof cmd, "%s bake %s -o %s --root-motion in-place -q %s%s", crowdbake_exe(), model, path, options,
             strstr(options, "--bone-space") ? "" : " --bone-space global");
    if (system(cmd) != 0) fail_msg("%s failed", cmd);
    p->model = load_or_fail(model);
    if (cbpal_open(path, CBPAL_VERIFY_CHECKSUM, &p->pal, err, sizeof err)) fail_msg("%s", err);
    cb_error e = {0};
    if (cb_palette_view(&p->pal, &p->view, &e)) fail_msg("%s", e.message);
    const cb_primitive *prim = &p->model->primitives[0];
    snprintf(path, sizeof path, "%s/%s.positions", c->dir, mesh);
    if (access(path, F_OK)) {
        conf_write(c->dir, mesh, ".positions", prim->positions, (size_t)prim->vertex_count * 12);
        conf_write(c->dir, mesh, ".joints", prim->joints, (size_t)prim->vertex_count * 8);
        conf_write(c->dir, mesh, ".weights", prim->weights, (size_t)prim->vertex_count * 16);
    }
    return c->palette_count++;
}

static inline conf_case *conf_add(conformance *c, const char *name, int palette)
{
    assert_true(c->case_count < CONF_MAX_CASES);
    conf_case *k = &c->cases[c->case_count++];
    memset(k, 0, sizeof *k);
    snprintf(k->name, sizeof k->name, "%s", name);
    k->palette = palette;
    return k;
}

/* The positions the C runtime gives every instance of a case, float32. Cross-fades as the shaders
 * fade: global rows' skins mixed linearly (the same as mixing the bones); local rows' bones faded
 * before they compose (cb_runtime_matrices_crossfade). */
static inline float *conf_expected(const conformance *c, const conf_case *k)
{
    const conf_palette *p = &c->palettes[k->right ? k->right : k->palette]; /* timed map ignored: the right clips */
    const cb_primitive *prim = &p->model->primitives[0];
    uint32_t verts = prim->vertex_count;
    float *out = malloc(conf_positions(c, k) * 3 * sizeof(float));
    double *mats = malloc(p->view.bone_count * 16 * sizeof(double)), *to = malloc(verts * 3 * sizeof(double)),
           *from = malloc(verts * 3 * sizeof(double));
    size_t at = 0;
    for (int t = 0; t < CONF_TIMES; ++t)
        for (uint32_t cl = 0; cl < p->view.clip_count; ++cl)
            for (int i = 0; i < CONF_PER_CLIP; ++i, at += (size_t)verts * 3) {
                float v[16];
                conf_instance(&p->view.clips[cl], conf_times[t], i, 0, v); /* the right rows, always */
                cb_instance in = {v[4], v[5], v[6], v[7]}, fi = {v[8], v[9], v[10], v[11]};
                double fade = v[13] > 0 ? fmin(fmax((conf_times[t] - v[12]) / v[13], 0), 1) : 1;
                if (k->local) { /* local rows fade before they compose: not a mix of the two skins */
                    assert_true(cb_runtime_matrices_crossfade(&p->view, p->pal.texels, &fi, &in, fade, (float)conf_times[t], mats));
                    cb_skin_positions(prim, mats, to);
                    fade = 1;
                } else {
                    cb_runtime_matrices(&p->view, p->pal.texels, &in, (float)conf_times[t], mats);
                    cb_skin_positions(prim, mats, to);
                }
                if (fade < 1) {
                    cb_runtime_matrices(&p->view, p->pal.texels, &fi, (float)conf_times[t], mats);
                    cb_skin_positions(prim, mats, from);
                }
                for (uint32_t j = 0; j < verts * 3; ++j)
                    out[at + j] = (float)(fade < 1 ? from[j] + (to[j] - from[j]) * fade : to[j]);
            }
    free(mats), free(to), free(from);
    return out;
}

static inline void conf_write_case(FILE *f, const conformance *c, const conf_case *k, bool first)
{
    const conf_palette *p = &c->palettes[k->palette];
    fprintf(f, "%s\n{\"name\": \"%s\", \"pal\": \"%s\", \"expected\": \"%s.expected\", \"out\": \"%s.out\", "
               "\"broken\": %s, \"transpose\": %s,\n", first ? "" : ",", k->name, p->file, k->name, k->name,
            k->broken ? "true" : "false", k->transpose ? "true" : "false");
    if (k->local) fprintf(f, " \"local\": true,\n");
    if (k->timed) fprintf(f, " \"timed\": true,\n");
    fprintf(f, " \"mesh\": {\"positions\": \"%s.positions\", \"joints\": \"%s.joints\", \"weights\": \"%s.weights\"},\n",
            p->mesh, p->mesh, p->mesh);
    if (k->glsl_marker) fprintf(f, " \"glsl_break\": {\"marker\": \"%s\", \"line\": \"%s\"},\n", k->glsl_marker, k->glsl_line);
    if (k->bone_pass) fprintf(f, " \"bone_pass\": %s,\n", k->bone_pass);
    fprintf(f, " \"groups\": [");
    for (int t = 0; t < CONF_TIMES; ++t) {
        fprintf(f, "%s{\"time\": %.9g, \"instances\": [", t ? ", " : "", conf_times[t]);
        for (uint32_t cl = 0; cl < p->view.clip_count; ++cl)
            for (int i = 0; i < CONF_PER_CLIP; ++i) {
                float v[16];
                conf_instance(&p->view.clips[cl], conf_times[t], i, k->row_offset, v);
                fprintf(f, "%s[", cl || i ? "," : "");
                for (int j = 0; j < 16; ++j) fprintf(f, "%s%.9g", j ? "," : "", v[j]);
                fprintf(f, "]");
            }
        fprintf(f, "]}");
    }
    fprintf(f, "]}");
}

/* The cases: every layout x precision, wrapped rows, spinning bones, the bone pass, and the broken
 * variants every runtime's test must catch. */
static inline void conf_define_cases(conformance *c, int all[9], int spin, int wrapped, int held)
{
    for (int i = 0; i < 9; ++i) {
        char name[40];
        snprintf(name, sizeof name, "%s-%s", conf_layouts[i / 3], conf_precisions[i % 3]);
        conf_add(c, name, all[i]);
    }
    conf_add(c, "spin", spin);
    conf_add(c, "wrapped", wrapped);
    conf_add(c, "held", held);
    conf_add(c, "bones-qpos-u16", all[8])->bone_pass = "true";
    conf_add(c, "bones-mat4-half", all[1])->bone_pass = "{\"rows\": 16}";
    conf_case *k = conf_add(c, "broken-transposed", all[0]);
    k->broken = k->transpose = true;
    k = conf_add(c, "broken-row-off-by-one", all[8]);
    k->broken = true, k->row_offset = 1;
    k = conf_add(c, "broken-no-wrap", all[7]);
    k->broken = true, k->glsl_marker = "cb:wrap", k->glsl_line = "        f1 = f0 + 1.0;";
    k = conf_add(c, "broken-no-held", held); /* a STEP-keyed clip's rows blended across its steps */
    k->broken = true, k->glsl_marker = "cb:held", k->glsl_line = "";
    k = conf_add(c, "broken-no-hemisphere-flip", spin);
    k->broken = true, k->glsl_marker = "cb:hemisphere", k->glsl_line = "";
    k = conf_add(c, "broken-bones-transposed", all[8]);
    k->broken = true, k->bone_pass = "true", k->glsl_marker = "cb:bone-columns",
    k->glsl_line = "    mat3 a = transpose(mat3(c0.xyz, c1.xyz, c2.xyz));";
}

/* Local rows (.pal version 6): the quadruped at 30 fps in qpos u16 and float, and u16 wrapped into
 * two column blocks; expected positions from the C runtime, which composes. */
static inline void conf_define_local_cases(conformance *c, const char *quadruped)
{
    static const char *const names[3] = {"local_qpos_u16", "local_qpos_float", "local_blocks"};
    static const char *const options[3] = {
        "--bone-space local --fps 30 --layout qpos --precision u16",
        "--bone-space local --fps 30 --layout qpos --precision float",
        "--bone-space local --fps 30 --layout qpos --precision u16 --max-texture-size 200"};
    for (int i = 0; i < 3; ++i) {
        char file[40];
        snprintf(file, sizeof file, "%s.pal", names[i]);
        int at = conf_bake(c, quadruped, file, "quadruped", options[i]);
        assert_int_equal(c->palettes[at].pal.header.version, 6);
        assert_true(c->palettes[at].view.bone_space == CB_BONE_SPACE_LOCAL);
        if (i == 2) assert_int_equal(c->palettes[at].view.blocks, 2);
        conf_add(c, names[i], at)->local = true;
    }
}

/* Timed rows (.pal version 7) without the bake choosing them (timed_subset.h): `model` baked
 * uniform with `options`, every clip but `untimed` (TIMED_KEEP_ALL: none) kept at intervals of 1, 2
 * and 3 cells with its map, texture wrapped into `blocks` column blocks, written by the library's
 * writer to dir/FILE and opened. */
static inline int conf_timed(conformance *c, const char *model, const char *file, const char *mesh, const char *options,
                             uint32_t untimed, uint32_t blocks)
{
    char uniform[64], path[PATH_MAX], err[512];
    snprintf(uniform, sizeof uniform, "uniform-%s", file);
    int at = conf_bake(c, model, uniform, mesh, options);
    conf_palette *p = &c->palettes[at];
    cb_palette t;
    cb_error e = {0};
    uint32_t rows = 0; /* rows after the subset: for a texture limit that wraps them into `blocks` */
    assert_true(timed_subset_make(&p->pal, &p->view, untimed, 0, &t));
    rows = t.rows;
    if (blocks > 1) {
        timed_subset_free(&t);
        uint32_t max = (rows + blocks - 1) / blocks;
        if (max < blocks * p->view.row_texels) max = blocks * p->view.row_texels;
        assert_true(timed_subset_make(&p->pal, &p->view, untimed, max, &t));
    }
    assert_int_equal(t.blocks, blocks);
    snprintf(path, sizeof path, "%s/%s", c->dir, file);
    if (timed_subset_write(path, &t, &p->pal, p->model, &e)) fail_msg("%s", e.message);
    timed_subset_free(&t);
    cb_palette_view_free(&p->view);
    cbpal_close(&p->pal);
    snprintf(p->file, sizeof p->file, "%s", file);
    if (cbpal_open(path, CBPAL_VERIFY_CHECKSUM, &p->pal, err, sizeof err)) fail_msg("%s", err);
    if (cb_palette_view(&p->pal, &p->view, &e)) fail_msg("%s", e.message);
    assert_int_equal(p->pal.header.version, 7);
    snprintf(path, sizeof path, "%s/%s", c->dir, uniform);
    unlink(path);
    return at;
}

/* The same file as palette `right`, its timed clips read as if untimed: their rows played at a
 * uniform rate (frames / duration), the map ignored: the broken runtime's clips. They keep their
 * cells, which conf_instance reads as this mark: each instance the right one with its second and
 * third numbers made (+-frames, a positive rate), at the same clip time. */
static inline int conf_map_ignored(conformance *c, int right, const char *model)
{
    conf_palette *p = &c->palettes[c->palette_count], *r = &c->palettes[right];
    char path[PATH_MAX], err[512];
    *p = *r;
    snprintf(path, sizeof path, "%s/%s", c->dir, r->file);
    p->model = load_or_fail(model);
    if (cbpal_open(path, CBPAL_VERIFY_CHECKSUM, &p->pal, err, sizeof err)) fail_msg("%s", err);
    cb_error e = {0};
    if (cb_palette_view(&p->pal, &p->view, &e)) fail_msg("%s", e.message);
    for (uint32_t i = 0; i < p->view.clip_count; ++i) {
        cb_palette_clip *k = &p->view.clips[i];
        if (k->timed) k->timed = false, k->fps = (k->frames - !k->loops) / k->duration;
    }
    return c->palette_count++;
}

/* Timed rows (.pal version 7; conf_timed): the quadruped at 48 fps in qpos u16 (walk left untimed),
 * qpos float, affine half, mat4 float (death, a one-shot, left untimed), local rows (u16), qpos
 * half wrapped into two column blocks (the maps too), and the STEP SimpleSkin's held rows timed;
 * and the broken runtime that ignores the maps. */
static inline void conf_define_timed_cases(conformance *c, const char *quadruped, const char *step)
{
    static const struct { const char *name, *options; uint32_t untimed, blocks; } cases[] = {
        {"timed_qpos_u16", "--fps 48 --layout qpos --precision u16", 1, 1},
        {"timed_qpos_float", "--fps 48 --layout qpos --precision float", TIMED_KEEP_ALL, 1},
        {"timed_affine_half", "--fps 48 --layout affine --precision half", TIMED_KEEP_ALL, 1},
        {"timed_mat4_float", "--fps 48 --layout mat4 --precision float", 4, 1},
        {"timed_local", "--fps 48 --bone-space local --layout qpos --precision u16", TIMED_KEEP_ALL, 1},
        {"timed_blocks", "--fps 48 --layout qpos --precision half", TIMED_KEEP_ALL, 2},
        {"timed_held", "--layout qpos --precision u16", TIMED_KEEP_ALL, 1},
    };
    int first = -1;
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
        char file[48];
        bool held = !strcmp(cases[i].name, "timed_held");
        snprintf(file, sizeof file, "%s.pal", cases[i].name);
        int at = conf_timed(c, held ? step : quadruped, file, held ? "step" : "quadruped", cases[i].options,
                            cases[i].untimed, cases[i].blocks);
        if (held) assert_true(c->palettes[at].view.clips[0].step && c->palettes[at].view.clips[0].timed);
        conf_case *k = conf_add(c, cases[i].name, at);
        k->timed = true, k->local = strstr(cases[i].options, "local") != NULL;
        if (first < 0) first = at;
    }
    conf_case *k = conf_add(c, "broken-timed-map-ignored", conf_map_ignored(c, first, quadruped));
    k->broken = k->timed = true, k->right = first;
}

/* Bakes the palettes and writes every file the runtimes' tests read into `dir` (emptied first). */
static inline void conformance_make(conformance *c, const char *dir)
{
    memset(c, 0, sizeof *c);
    c->dir = dir;
    char cmd[PATH_MAX + 32], quadruped[PATH_MAX], multitrack[PATH_MAX], file[32];
    snprintf(cmd, sizeof cmd, "rm -rf %s && mkdir -p %s", dir, dir);
    assert_int_equal(system(cmd), 0);
    sample_path(quadruped, sizeof quadruped, "quadruped");
    shared_path(multitrack, sizeof multitrack, "assets/multitrack-luanti/gltf_multi_track_1.glb");
    int all[9];
    for (int i = 0; i < 9; ++i) {
        char options[64];
        snprintf(file, sizeof file, "%s-%s.pal", conf_layouts[i / 3], conf_precisions[i % 3]);
        snprintf(options, sizeof options, "--layout %s --precision %s", conf_layouts[i / 3], conf_precisions[i % 3]);
        all[i] = conf_bake(c, quadruped, file, "quadruped", options);
    }
    /* multitrack's bones spin a full turn per loop: their last and first rows are -q apart. */
    int spin = conf_bake(c, multitrack, "spin.pal", "spin", "--layout qpos --precision float");
    /* Rows wrapped into two column blocks (a 200-texel limit): addressed as the header says. */
    int wrapped = conf_bake(c, quadruped, "wrapped.pal", "quadruped", "--layout qpos --precision half --max-texture-size 200");
    assert_int_equal(c->palettes[wrapped].view.blocks, 2);
    /* The STEP SimpleSkin: rows at its key times, held (.pal version 4's clip flag bit 2). */
    char step[PATH_MAX];
    shared_path(step, sizeof step, "assets/simpleskin-step-luanti/gltf_simple_skin_step.gltf");
    int held = conf_bake(c, step, "held.pal", "step", "--layout qpos --precision u16");
    assert_true(c->palettes[held].view.clips[0].step);
    conf_define_cases(c, all, spin, wrapped, held);
    conf_define_local_cases(c, quadruped);
    conf_define_timed_cases(c, quadruped, step);
    char path[PATH_MAX];
    snprintf(path, sizeof path, "%s/cases.json", dir);
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fprintf(f, "{\"cases\": [");
    for (int i = 0; i < c->case_count; ++i) {
        conf_write_case(f, c, &c->cases[i], i == 0);
        float *want = conf_expected(c, &c->cases[i]);
        conf_write(dir, c->cases[i].name, ".expected", want, conf_positions(c, &c->cases[i]) * 12);
        free(want);
    }
    fprintf(f, "\n]}\n");
    fclose(f);
}

static inline const conf_case *conformance_case(const conformance *c, const char *name)
{
    for (int i = 0; i < c->case_count; ++i)
        if (!strcmp(c->cases[i].name, name)) return &c->cases[i];
    fail_msg("no conformance case %s", name);
    return NULL;
}

/* The largest |got - expected| over a case, in units of the tolerance (1e-5 of the model's
 * height, at least 1e-5); the worst distance in model units goes to *units. */
static inline double conformance_compare(const conformance *c, const conf_case *k, const float *got, double *units)
{
    char path[PATH_MAX];
    snprintf(path, sizeof path, "%s/%s.expected", c->dir, k->name);
    size_t size = 0, n = conf_positions(c, k) * 3;
    float *want = (float *)read_whole_file(path, &size);
    assert_non_null(want);
    assert_int_equal(size, n * sizeof(float));
    double worst = 0;
    for (size_t i = 0; i < n; ++i) worst = fmax(worst, fabs((double)want[i] - got[i]));
    free(want);
    *units = worst;
    return worst / (1e-5 * fmax(1.0, c->palettes[k->palette].view.model_height));
}

/* conformance_compare for the positions a runtime wrote to `path` (float32 x 3, conf_positions of them). */
static inline double conformance_compare_file(const conformance *c, const conf_case *k, const char *path, double *units)
{
    size_t size = 0;
    float *got = (float *)read_whole_file(path, &size);
    if (!got) fail_msg("%s: %s wrote no result", k->name, path);
    assert_int_equal(size, conf_positions(c, k) * 3 * sizeof(float));
    double ratio = conformance_compare(c, k, got, units);
    free(got);
    return ratio;
}

/* What a shader runtime's GPU skins for a case from `source` (its library, broken where the case
 * says): conf_positions(c, k) positions, 3 floats each, for the caller to free. */
typedef float *(*conf_gpu_case)(const conformance *c, const conf_case *k, const char *source, void *ctx);

/* Every case a shader runtime can express (all but the bone pass's) through `gpu`, from the
 * library `lib` (a broken case's line replaced at its marker, which the GLSL and the HLSL share):
 * each within the tolerance, each broken one off by more than 10 times it; at least 15 run and 4
 * broken ones caught. */
static inline void conformance_check_shader(const conformance *c, const char *lib, conf_gpu_case gpu, void *ctx)
{
    int ran = 0, caught = 0;
    for (int i = 0; i < c->case_count; ++i) {
        const conf_case *k = &c->cases[i];
        if (k->bone_pass || (k->local && !strstr(lib, "CB_LOCAL_ROWS"))) continue; /* local: once the library composes */
        char *broken = k->glsl_marker ? break_shader(lib, k->glsl_marker, k->glsl_line) : NULL;
        float *got = gpu(c, k, broken ? broken : lib, ctx);
        double units, ratio = conformance_compare(c, k, got, &units);
        printf("  %-26s %7zu positions: GPU vs C runtime %.2g (%.2f of the tolerance)\n", k->name, conf_positions(c, k), units,
               ratio);
        if (k->broken) assert_true(ratio > 10), ++caught;
        else assert_true(ratio <= 1);
        ++ran;
        free(got);
        free(broken);
    }
    assert_true(ran >= 15 && caught >= 4);
}

static inline void conformance_free(conformance *c)
{
    for (int i = 0; i < c->palette_count; ++i) {
        cb_palette_view_free(&c->palettes[i].view);
        cbpal_close(&c->palettes[i].pal);
        cb_model_free(c->palettes[i].model);
    }
}

#endif
