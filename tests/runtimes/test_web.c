/* test_web.c - the WebGL2 runtime (runtimes/web/crowdbake_crowd.mjs, whose vertex shader is the shipped
 * runtimes/glsl/crowdbake_palette.glsl) in a real browser: headless Chromium, WebGL2 on
 * SwiftShader, driven by tests/runtimes/browser/skin_check.mjs. For every layout x precision, palettes
 * baked by the command are read by runtimes/web/crowdbake_pal.mjs, uploaded by the runtime and drawn as one
 * instanced draw per time; transform feedback reads every instance's skinned vertices back and
 * they must match the CPU runtime (src/core/runtime.c) within 1e-5 x model height. The broken variants
 * test_gl catches (transposed matrices, rows off by one, no loop wrap, no hemisphere flip) must
 * fail the same comparison here. The fuzzers' hostile palettes are read in the same page (fzstd as
 * the decoder) and every one is refused with a one-line message. CrowdbakeHerd (three.js) is
 * compared with three.js's own skinning of the glTF. */
#define _DEFAULT_SOURCE
#include "testutil.h"

#include <limits.h>
#include <math.h>

#include "crowdbake_pal.h"
#include "crowdbake/pal_view.h"
#include "crowdbake/runtime.h"

#define TMP TEST_TMP "/web"

static const char *layouts[] = {"mat4", "affine", "qpos"};
static const char *precisions[] = {"float", "half", "u16"};

/* A baked palette opened as the CPU runtime reads it, and the model's first primitive. */
typedef struct baked {
    cb_model *model;
    cbpal_file file;
    cb_palette view;
} baked;

static void open_baked(const char *model, const char *pal, baked *b)
{
    char err[512];
    b->model = load_or_fail(model);
    if (cbpal_open(pal, CBPAL_VERIFY_CHECKSUM, &b->file, err, sizeof err)) fail_msg("%s", err);
    cb_error e = {0};
    if (cb_palette_view(&b->file, &b->view, &e)) fail_msg("%s", e.message);
}

static void close_baked(baked *b)
{
    cb_palette_view_free(&b->view);
    cbpal_close(&b->file);
    cb_model_free(b->model);
}

static void write_bytes(const char *path, const void *data, size_t n)
{
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(data, 1, n, f), n);
    fclose(f);
}

/* The mesh as the browser gets it: primitive 0's positions, joints and weights. */
static void write_mesh(const cb_primitive *p, const char *stem)
{
    char path[PATH_MAX];
    snprintf(path, sizeof path, TMP "/%s.positions", stem);
    write_bytes(path, p->positions, (size_t)p->vertex_count * 12);
    snprintf(path, sizeof path, TMP "/%s.joints", stem);
    write_bytes(path, p->joints, (size_t)p->vertex_count * 8);
    snprintf(path, sizeof path, TMP "/%s.weights", stem);
    write_bytes(path, p->weights, (size_t)p->vertex_count * 16);
}

#define TIMES 2
static const double times[TIMES] = {0.77, 2.31};
#define PER_CLIP 7

/* Instance k of a clip at `time`: phases that land on mid-frames, the loop seam and golden-ratio
 * spreads; the last one cross-fades from the clip's first row held (a 0.5 fade at `time`). */
static void instance_of(const cb_palette_clip *c, double time, int k, double row_offset, float out[16])
{
    double frames = c->frames, rate = c->fps;
    double targets[] = {0.3, 2.5, frames * 0.37, frames - 0.4 /* the seam */};
    double phase = k < 4 ? (targets[k] - time * rate) / frames : fmod((k - 3) * 0.6180339887, 1.0);
    if (c->loops) phase -= floor(phase);
    float v[16] = {0, 0, 0, 0, (float)(c->first_row + row_offset), (float)(c->loops ? frames : -frames), (float)rate,
                   (float)phase, 0, 0, 0, 0, 0, 0, 1, 0};
    if (k == PER_CLIP - 1) { /* from: the first row, still; fade 0.5 at `time` */
        v[8] = (float)(c->first_row + row_offset), v[9] = 1, v[10] = 0, v[11] = 0;
        v[12] = (float)(time - 0.25), v[13] = 0.5f;
    }
    memcpy(out, v, sizeof v);
}

static void append_case(FILE *f, bool first, const char *name, const char *pal, const char *mesh, const cb_palette *p,
                        double row_offset, bool transpose, const char *marker, const char *line, const char *bone_pass)
{
    fprintf(f, "%s\n{\"name\": \"%s\", \"pal\": \"%s\", \"out\": \"%s.out\", \"transpose\": %s,\n", first ? "" : ",", name,
            pal, name, transpose ? "true" : "false");
    fprintf(f, " \"mesh\": {\"positions\": \"%s.positions\", \"joints\": \"%s.joints\", \"weights\": \"%s.weights\"},\n", mesh,
            mesh, mesh);
    if (marker) fprintf(f, " \"glsl_break\": {\"marker\": \"%s\", \"line\": \"%s\"},\n", marker, line);
    if (bone_pass) fprintf(f, " \"bone_pass\": %s,\n", bone_pass);
    fprintf(f, " \"groups\": [");
    for (int t = 0; t < TIMES; ++t) {
        fprintf(f, "%s{\"time\": %.9g, \"instances\": [", t ? ", " : "", times[t]);
        for (uint32_t c = 0; c < p->clip_count; ++c)
            for (int k = 0; k < PER_CLIP; ++k) {
                float v[16];
                instance_of(&p->clips[c], times[t], k, row_offset, v);
                fprintf(f, "%s[", c || k ? "," : "");
                for (int i = 0; i < 16; ++i) fprintf(f, "%s%.9g", i ? "," : "", v[i]);
                fprintf(f, "]");
            }
        fprintf(f, "]}");
    }
    fprintf(f, "]}");
}

/* Largest |browser - CPU runtime| over every instance and vertex of a case, in tolerances. */
static double compare(const char *name, const baked *b, double *worst_units)
{
    char path[PATH_MAX];
    snprintf(path, sizeof path, TMP "/%s.out", name);
    size_t size = 0;
    float *gpu = (float *)read_whole_file(path, &size);
    if (!gpu) fail_msg("%s: the browser wrote no result", name);
    const cb_palette *p = &b->view;
    const cb_primitive *prim = &b->model->primitives[0];
    uint32_t verts = prim->vertex_count;
    assert_int_equal(size, (size_t)TIMES * p->clip_count * PER_CLIP * verts * 12);
    double *mats = malloc(p->bone_count * 16 * sizeof(double)), *cpu = malloc(verts * 3 * sizeof(double)),
           *from = malloc(verts * 3 * sizeof(double)), worst = 0;
    size_t at = 0;
    for (int t = 0; t < TIMES; ++t)
        for (uint32_t c = 0; c < p->clip_count; ++c)
            for (int k = 0; k < PER_CLIP; ++k, at += (size_t)verts * 3) {
                float v[16];
                instance_of(&p->clips[c], times[t], k, 0, v); /* the CPU side is never broken */
                cb_instance in = {v[4], v[5], v[6], v[7]}, fi = {v[8], v[9], v[10], v[11]};
                cb_runtime_matrices(p, b->file.texels, &in, (float)times[t], mats);
                cb_skin_positions(prim, mats, cpu);
                double fade = v[13] > 0 ? fmin(fmax((times[t] - v[12]) / v[13], 0), 1) : 1;
                if (fade < 1) {
                    cb_runtime_matrices(p, b->file.texels, &fi, (float)times[t], mats);
                    cb_skin_positions(prim, mats, from);
                }
                for (uint32_t i = 0; i < verts * 3; ++i) {
                    double want = fade < 1 ? from[i] + (cpu[i] - from[i]) * fade : cpu[i];
                    worst = fmax(worst, fabs(want - gpu[at + i]));
                }
            }
    free(mats), free(cpu), free(from), free(gpu);
    *worst_units = worst;
    return worst / (1e-5 * fmax(1.0, p->model_height));
}

static void bake(const char *model, const char *out, const char *layout, const char *precision, const char *more)
{
    char cmd[3 * PATH_MAX];
    snprintf(cmd, sizeof cmd, "%s bake %s -o %s --layout %s --precision %s --root-motion in-place -q %s", crowdbake_exe(),
             model, out, layout, precision, more);
    assert_int_equal(system(cmd), 0);
}

static void test_runtime_in_chromium_matches_the_cpu(void **state)
{
    (void)state;
    assert_int_equal(system("rm -rf " TMP " && mkdir -p " TMP), 0);
    FILE *installed = fopen("tests/runtimes/browser/node_modules/.package-lock.json", "r");
    if (!installed) fail_msg("tests/runtimes/browser: npm packages not installed (make test installs them; or: cd tests/runtimes/browser && npm ci)");
    fclose(installed);
    char quadruped[PATH_MAX], multitrack[PATH_MAX], pal[PATH_MAX], name[64];
    sample_path(quadruped, sizeof quadruped, "quadruped");
    shared_path(multitrack, sizeof multitrack, "assets/multitrack-luanti/gltf_multi_track_1.glb");
    baked all[9], spin, wrapped;
    FILE *jobs = fopen(TMP "/jobs.json", "w");
    assert_non_null(jobs);
    fprintf(jobs, "{\"cases\": [");
    for (int i = 0; i < 9; ++i) {
        snprintf(name, sizeof name, "%s-%s.pal", layouts[i / 3], precisions[i % 3]);
        snprintf(pal, sizeof pal, TMP "/%s", name);
        bake(quadruped, pal, layouts[i / 3], precisions[i % 3], "");
        open_baked(quadruped, pal, &all[i]);
        if (i == 0) write_mesh(&all[0].model->primitives[0], "quadruped");
        char case_name[64];
        snprintf(case_name, sizeof case_name, "%s-%s", layouts[i / 3], precisions[i % 3]);
        append_case(jobs, i == 0, case_name, name, "quadruped", &all[i].view, 0, false, NULL, NULL, NULL);
    }
    /* The broken variants (the C side of the comparison stays right). */
    append_case(jobs, false, "broken-transposed", "mat4-float.pal", "quadruped", &all[0].view, 0, true, NULL, NULL, NULL);
    append_case(jobs, false, "broken-row-off-by-one", "qpos-u16.pal", "quadruped", &all[8].view, 1, false, NULL, NULL, NULL);
    append_case(jobs, false, "broken-no-wrap", "qpos-half.pal", "quadruped", &all[7].view, 0, false, "cb:wrap",
                "        f1 = f0 + 1.0;", NULL);
    bake(multitrack, TMP "/spin.pal", "qpos", "float", "");
    open_baked(multitrack, TMP "/spin.pal", &spin);
    write_mesh(&spin.model->primitives[0], "spin");
    /* multitrack's bones spin a full turn per loop: their last and first rows are -q apart. */
    append_case(jobs, false, "broken-no-hemisphere-flip", "spin.pal", "spin", &spin.view, 0, false, "cb:hemisphere", "", NULL);
    append_case(jobs, false, "spin", "spin.pal", "spin", &spin.view, 0, false, NULL, NULL, NULL);
    /* Rows wrapped into two column blocks (a 200-texel limit): the runtime addresses them as the
     * header says. */
    bake(quadruped, TMP "/wrapped.pal", "qpos", "half", "--max-texture-size 200");
    open_baked(quadruped, TMP "/wrapped.pal", &wrapped);
    assert_int_equal(wrapped.view.blocks, 2);
    append_case(jobs, false, "wrapped", "wrapped.pal", "quadruped", &wrapped.view, 0, false, NULL, NULL, NULL);
    /* The bone pass (bonePass): each instance's bones blended once into float textures, then skinned
     * from; the default qpos/u16 and a half mat4 of positions relative to the bones' offsets, one
     * in column blocks of 16 instances; and broken, its columns read as rows. */
    append_case(jobs, false, "bones-qpos-u16", "qpos-u16.pal", "quadruped", &all[8].view, 0, false, NULL, NULL, "true");
    append_case(jobs, false, "bones-mat4-half", "mat4-half.pal", "quadruped", &all[1].view, 0, false, NULL, NULL,
                "{\"rows\": 16}");
    append_case(jobs, false, "broken-bones-transposed", "qpos-u16.pal", "quadruped", &all[8].view, 0, false,
                "cb:bone-columns", "    return cb_affine(transpose(mat3(c0.xyz, c1.xyz, c2.xyz)), vec3(c0.w, c1.w, c2.w));",
                "true");
    fprintf(jobs, "\n]}\n");
    fclose(jobs);

    static char out[1 << 16];
    int rc = run_command("node tests/runtimes/browser/skin_check.mjs " TMP " 2>&1", out, sizeof out);
    printf("%s", out);
    assert_int_equal(rc, 0);
    /* Every hostile palette of tests/fuzz/regressions/pal refused in the page with a message. */
    char count_cmd[] = "ls tests/fuzz/regressions/pal | wc -l";
    char listed[32];
    assert_int_equal(run_command(count_cmd, listed, sizeof listed), 0);
    int refused = 0;
    for (const char *p = out; (p = strstr(p, "\nrefused ")); ++p) ++refused;
    assert_true(atoi(listed) >= 8);
    assert_int_equal(refused, 2 * atoi(listed)); /* with and without the checksum check */
    assert_null(strstr(out, "ACCEPTED"));
    assert_null(strstr(out, "BAD ERROR"));
    for (int i = 0; i < 9; ++i) {
        double units, ratio;
        snprintf(name, sizeof name, "%s-%s", layouts[i / 3], precisions[i % 3]);
        ratio = compare(name, &all[i], &units);
        printf("  %-12s %u instances x %u vertices: browser vs CPU %.2g (%.2f of the tolerance)\n", name,
               TIMES * all[i].view.clip_count * PER_CLIP, all[i].model->primitives[0].vertex_count, units, ratio);
        assert_true(ratio <= 1);
    }
    double units, spin_ok = compare("spin", &spin, &units), wrapped_ok = compare("wrapped", &wrapped, &units);
    printf("  qpos/half in 2 column blocks: browser vs CPU %.2g (%.2f of the tolerance)\n", units, wrapped_ok);
    assert_true(wrapped_ok <= 1);
    double transposed = compare("broken-transposed", &all[0], &units);
    double off_by_one = compare("broken-row-off-by-one", &all[8], &units);
    double no_wrap = compare("broken-no-wrap", &all[7], &units);
    double no_flip = compare("broken-no-hemisphere-flip", &spin, &units);
    printf("  error / tolerance: transposed %.0f, rows off by one %.0f, no wrap %.0f, no hemisphere flip %.0f "
           "(the same spin palette, shipped shader: %.2f)\n", transposed, off_by_one, no_wrap, no_flip, spin_ok);
    assert_true(spin_ok <= 1);
    assert_true(transposed > 10 && off_by_one > 10 && no_wrap > 10 && no_flip > 10);
    double bones_qpos = compare("bones-qpos-u16", &all[8], &units), bones_mat4 = compare("bones-mat4-half", &all[1], &units);
    double bones_broken = compare("broken-bones-transposed", &all[8], &units);
    printf("  bone pass: browser vs CPU %.2f (qpos/u16), %.2f (mat4/half, 16 instances a column block) of the tolerance; "
           "its columns read as rows: %.0f\n", bones_qpos, bones_mat4, bones_broken);
    assert_true(strstr(out, "ran  bones-qpos-u16: ") && strstr(out, "with the bone pass"));
    assert_true(bones_qpos <= 1 && bones_mat4 <= 1 && bones_broken > 10);
    for (int i = 0; i < 9; ++i) close_baked(&all[i]);
    close_baked(&spin);
    close_baked(&wrapped);
}

/* The share of covered pixels where two silhouettes disagree, at the `index`th time of the
 * three.js check's output, for "herd" or "broken". */
static double disagreement(const char *out, int index, const char *which)
{
    const char *at = strstr(out, "\"results\":[");
    assert_non_null(at);
    for (int i = 0; i <= index; ++i) assert_non_null(at = strstr(at + 1, "{\"time\":"));
    char key[32];
    snprintf(key, sizeof key, "\"%s\":{", which);
    assert_non_null(at = strstr(at, key));
    assert_non_null(at = strstr(at, "\"share\":"));
    return atof(at + 8);
}

/* CrowdbakeHerd (three.js InstancedMesh, the shipped GLSL patched in) against three.js's own
 * SkinnedMesh + AnimationMixer playing the glTF: the Fox walking, silhouettes from one camera. */
static void test_three_herd_matches_three_skinning(void **state)
{
    (void)state;
    char fox[PATH_MAX], cmd[2 * PATH_MAX + 64];
    shared_path(fox, sizeof fox, "assets/fox-bevy/Fox.glb");
    assert_int_equal(system("rm -rf " TMP "/three && mkdir -p " TMP "/three"), 0);
    snprintf(cmd, sizeof cmd, "ln -s \"$(realpath %s)\" " TMP "/three/model.glb", fox);
    assert_int_equal(system(cmd), 0);
    /* Root motion kept: three plays the clip with its travel. */
    snprintf(cmd, sizeof cmd, "%s bake %s -o " TMP "/three/model.pal -q", crowdbake_exe(), fox);
    assert_int_equal(system(cmd), 0);
    static char out[1 << 16];
    int rc = run_command("node tests/runtimes/browser/three_check.mjs " TMP "/three Walk 0.1,0.37,0.6 2>&1", out, sizeof out);
    printf("%s", out);
    assert_int_equal(rc, 0);
    for (int i = 0; i < 3; ++i) {
        double herd = disagreement(out, i, "herd"), broken = disagreement(out, i, "broken");
        printf("  time %d: herd vs three.js skinning %.2f%% of the covered pixels; unpatched herd %.0f%%\n", i, 100 * herd,
               100 * broken);
        assert_true(herd < 0.03);
        assert_true(broken > 0.2);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_runtime_in_chromium_matches_the_cpu),
        cmocka_unit_test(test_three_herd_matches_three_skinning),
    };
    return cmocka_run_group_tests_name("web", tests, NULL, NULL);
}
