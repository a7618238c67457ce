/* test_bone_matrix.c - cbpal_bone_matrix, the reader's socket matrix: at the baked rows it equals
 * `crowdbake sample` (the exact joint matrices) within the encoding, for every layout and
 * precision and for fitted rows; between rows it is the blend the shipped GLSL computes (the CPU
 * runtime, which test_gl holds equal to the GLSL on Mesa); bad clips, bones and times fail. */
#define _DEFAULT_SOURCE
#include "testutil.h"

#include <math.h>

#include "crowdbake_pal.h"
#include "crowdbake/pal_view.h"
#include "crowdbake/runtime.h"
#include "runtimes/conformance.h"

#define TMP TEST_TMP "/bone_matrix"

/* crowdbake sample's matrices for Fox at 30 fps: [clip][frame][joint][16]. */
typedef struct sampled {
    uint32_t clips, frames[3], joints;
    double *m[3];
} sampled;

static sampled fox_sampled;
static char fox[1024];

static int setup(void **state)
{
    (void)state;
    char cmd[4096], log[4096];
    shared_path(fox, sizeof fox, "assets/fox-bevy/Fox.glb");
    /* Flattened by Python to "clip frame joint m0..m15" lines the test reads with scanf. */
    snprintf(cmd, sizeof cmd,
             "mkdir -p %s && %s sample %s --fps 30 --json > %s/sample.json && python3 -c \"import json\n"
             "d = json.load(open('%s/sample.json'))\n"
             "for c, clip in enumerate(d['clips']):\n"
             "  for s in clip['samples']:\n"
             "    for j, m in enumerate(s['joints']): print(c, s['frame'], j, *m)\" > %s/sample.txt",
             TMP, crowdbake_exe(), fox, TMP, TMP, TMP);
    if (run_command(cmd, log, sizeof log) != 0) return fprintf(stderr, "%s: %s\n", cmd, log), -1;
    FILE *f = fopen(TMP "/sample.txt", "r");
    if (!f) return -1;
    sampled *s = &fox_sampled;
    memset(s, 0, sizeof *s);
    uint32_t c, fr, j;
    size_t cap[3] = {0};
    while (fscanf(f, "%u %u %u", &c, &fr, &j) == 3 && c < 3) {
        size_t at = ((size_t)fr * 64 + j) * 16; /* Fox has 24 joints: 64 is room */
        if (at + 16 > cap[c]) s->m[c] = realloc(s->m[c], (cap[c] = (at + 16) * 2) * sizeof(double));
        for (int e = 0; e < 16; ++e)
            if (fscanf(f, "%lf", &s->m[c][at + e]) != 1) return fclose(f), -1;
        if (fr + 1 > s->frames[c]) s->frames[c] = fr + 1;
        if (c + 1 > s->clips) s->clips = c + 1;
        if (j + 1 > s->joints) s->joints = j + 1;
    }
    fclose(f);
    return s->clips == 3 && s->joints == 24 ? 0 : -1;
}

static int teardown(void **state)
{
    (void)state;
    for (int c = 0; c < 3; ++c) free(fox_sampled.m[c]);
    return 0;
}

static void open_bake(const char *options, const char *name, cbpal_file *f)
{
    char cmd[4096], log[4096], path[512], err[256];
    snprintf(path, sizeof path, TMP "/%s.pal", name);
    snprintf(cmd, sizeof cmd, "%s bake %s -o %s -q --max-error 1000 %s 2>&1", crowdbake_exe(), fox, path, options);
    if (run_command(cmd, log, sizeof log) != 0) fail_msg("%s failed: %s", cmd, log);
    if (cbpal_open(path, CBPAL_VERIFY_CHECKSUM, f, err, sizeof err)) fail_msg("%s", err);
}

/* The farthest two matrices move a point near the bone: its bind position and points a tenth of
 * the model's height away along each axis. */
static double point_distance(const float *a, const double *b, const float bind[3], double reach)
{
    double worst = 0;
    for (int i = 0; i < 7; ++i) {
        double p[3] = {bind[0], bind[1], bind[2]};
        if (i) p[(i - 1) / 2] += (i % 2 ? reach : -reach);
        double d2 = 0;
        for (int k = 0; k < 3; ++k) {
            double x = a[12 + k] + a[k] * p[0] + a[4 + k] * p[1] + a[8 + k] * p[2];
            double y = b[12 + k] + b[k] * p[0] + b[4 + k] * p[1] + b[8 + k] * p[2];
            d2 += (x - y) * (x - y);
        }
        worst = fmax(worst, sqrt(d2));
    }
    return worst;
}

/* The worst distance, over every clip, row and bone, between the palette's matrix at the row's
 * time and the sampled one. */
static double worst_at_rows(const cbpal_file *f)
{
    double worst = 0, reach = 0.1 * f->header.model_height;
    for (uint32_t c = 0; c < f->header.clip_count; ++c) {
        cbpal_clip clip;
        assert_int_equal(cbpal_get_clip(f, c, &clip), 0);
        assert_int_equal(clip.frames, fox_sampled.frames[c]);
        for (uint32_t r = 0; r < clip.frames; ++r)
            for (uint32_t j = 0; j < f->header.bone_count; ++j) {
                float m[16];
                cbpal_bone b;
                cbpal_get_bone(f, j, &b);
                assert_int_equal(cbpal_bone_matrix(f, c, r / (double)clip.fps, j, m), 0);
                worst = fmax(worst, point_distance(m, fox_sampled.m[c] + ((size_t)r * 64 + j) * 16, b.bind_position, reach));
            }
    }
    return worst;
}

static void test_rows_equal_sample_for_every_layout_and_precision(void **state)
{
    (void)state;
    static const char *layouts[] = {"mat4", "affine", "qpos"}, *precisions[] = {"float", "half", "u16"};
    for (int l = 0; l < 3; ++l)
        for (int p = 0; p < 3; ++p) {
            char options[128];
            cbpal_file f;
            snprintf(options, sizeof options, "--fps 30 --layout %s --precision %s", layouts[l], precisions[p]);
            open_bake(options, "rows", &f);
            double worst = worst_at_rows(&f), h = f.header.model_height;
            /* The encoding's own bound: float32 rounding, half's 2^-11, u16's steps (the bake's max_error, measured on
             * the skinned vertices, with room for points a tenth of the height off them). */
            double bound = p == 0 ? 1e-5 * h : 2 * f.header.max_error + 1e-4 * h;
            printf("  %-6s %-5s worst %.3g (%.3g mm/m), bound %.3g\n", layouts[l], precisions[p], worst, 1000 * worst / h,
                   bound);
            assert_true(worst <= bound);
            assert_true(worst > 0 || p == 0);
            cbpal_close(&f);
        }
}

static void test_fitted_rows_stay_within_their_encoding(void **state)
{
    (void)state;
    cbpal_file f;
    open_bake("--fps 30 --fit-rows", "fitted", &f);
    cbpal_clip clip;
    cbpal_get_clip(&f, 0, &clip);
    assert_true(clip.flags & CBPAL_CLIP_FITTED);
    /* Fitted rows leave the exact poses by about half the chord a bone cuts between rows: the bake's own
     * max_error at the rows says how far. */
    double worst = worst_at_rows(&f), h = f.header.model_height;
    printf("  fitted worst %.3g (%.3g mm/m), max_error %.3g\n", worst, 1000 * worst / h, f.header.max_error);
    assert_true(worst <= 2 * f.header.max_error + 1e-4 * h);
    cbpal_close(&f);
}

/* Between rows, the matrix is what the runtime blends: a time a quarter and half into each row,
 * wrapping past a loop's end, and clamped before and after a one-shot. */
static void test_between_rows_is_the_shaders_blend(void **state)
{
    (void)state;
    static const char *variants[] = {"--fps 30 --layout mat4 --precision half", "--fps 30 --layout affine --precision u16",
                                     "--fps 30 --layout qpos --precision u16", "--fps 30 --layout qpos --precision half",
                                     "--fps 30 --one-shot Walk --layout qpos --precision float",
                                     /* local rows (.pal version 6): the header composes in float, the runtime in double */
                                     "--fps 30 --bone-space local --layout qpos --precision u16",
                                     "--fps 30 --bone-space local --one-shot Walk --layout qpos --precision float"};
    for (size_t v = 0; v < COUNT_OF(variants); ++v) {
        cbpal_file f;
        cb_palette view;
        cb_error err = {0};
        open_bake(variants[v], "blend", &f);
        assert_int_equal(cb_palette_view(&f, &view, &err), CB_OK);
        double worst = 0, *mats = malloc(sizeof(double) * 16 * f.header.bone_count);
        for (uint32_t c = 0; c < f.header.clip_count; ++c) {
            cbpal_clip clip;
            cbpal_get_clip(&f, c, &clip);
            bool loops = clip.flags & CBPAL_CLIP_LOOPS;
            cb_instance in = {clip.first_row, loops ? clip.frames : -(double)clip.frames, clip.fps, 0};
            for (double r = -2.5; r < clip.frames + 3; r += 0.25) {
                double t = r / clip.fps;
                cb_runtime_matrices(&view, f.texels, &in, t, mats);
                for (uint32_t j = 0; j < f.header.bone_count; ++j) {
                    float m[16];
                    assert_int_equal(cbpal_bone_matrix(&f, c, t, j, m), 0);
                    cbpal_bone b;
                    cbpal_get_bone(&f, j, &b);
                    worst = fmax(worst, point_distance(m, mats + (size_t)j * 16, b.bind_position, 0.1 * view.model_height));
                }
            }
        }
        printf("  %s: worst %.3g against the runtime's blend\n", variants[v], worst);
        assert_true(worst < 1e-5 * view.model_height); /* float against double arithmetic */
        free(mats);
        cb_palette_view_free(&view);
        cbpal_close(&f);
    }
}

static void test_bad_clip_bone_or_time_fails(void **state)
{
    (void)state;
    cbpal_file f;
    float m[16];
    open_bake("--fps 30", "bad", &f);
    assert_int_equal(cbpal_bone_matrix(&f, 0, 0.1, 0, m), 0);
    assert_int_not_equal(cbpal_bone_matrix(&f, f.header.clip_count, 0.1, 0, m), 0);
    assert_int_not_equal(cbpal_bone_matrix(&f, 0, 0.1, f.header.bone_count, m), 0);
    assert_int_not_equal(cbpal_bone_matrix(&f, 0, NAN, 0, m), 0);
    assert_int_not_equal(cbpal_bone_matrix(&f, 0, INFINITY, 0, m), 0);
    cbpal_close(&f);
}

/* The conformance cases' timed rows (.pal version 7): the reader's matrices at each instance's clip
 * time skin the quadruped (and the held SimpleSkin) where the C runtime does, every precision,
 * local rows and wrapped maps; the cross-fading instances are the runtimes' to check. The broken
 * case (the maps ignored, rows played uniform) misses the right positions by far. */
static void test_timed_conformance_cases(void **state)
{
    (void)state;
    conformance conf;
    conformance_make(&conf, TMP "/conformance");
    int timed = 0;
    for (int i = 0; i < conf.case_count; ++i) {
        const conf_case *k = &conf.cases[i];
        if (!k->timed) continue;
        const conf_palette *p = &conf.palettes[k->palette];
        const cb_primitive *prim = &p->model->primitives[0];
        size_t verts = prim->vertex_count, n = conf_positions(&conf, k), at = 0;
        float *got = calloc(n * 3, sizeof(float)), *want = calloc(n * 3, sizeof(float));
        double *mats = malloc(sizeof(double) * 16 * p->view.bone_count), *pos = malloc(sizeof(double) * 3 * verts);
        char path[PATH_MAX];
        size_t size = 0;
        snprintf(path, sizeof path, "%s/%s.expected", conf.dir, k->name);
        float *expected = (float *)read_whole_file(path, &size);
        uint32_t compared = 0;
        for (int t = 0; t < CONF_TIMES; ++t)
            for (uint32_t cl = 0; cl < p->view.clip_count; ++cl)
                for (int j = 0; j < CONF_PER_CLIP; ++j, at += verts * 3) {
                    float v[16];
                    conf_instance(&p->view.clips[cl], conf_times[t], j, k->row_offset, v);
                    if (v[13] > 0 && !k->broken) continue; /* a cross-fade */
                    cb_instance in = {v[4], v[5], v[6], v[7]};
                    if (k->broken) { /* what the broken runtime draws: its instances through the C runtime */
                        cb_runtime_matrices(&p->view, p->pal.texels, &in, (float)conf_times[t], mats);
                    } else { /* the reader at the instance's clip time */
                        double clip_time = (float)conf_times[t] + v[7] * fabs(v[5]) / fabs(v[6]);
                        for (uint32_t b = 0; b < p->view.bone_count; ++b) {
                            float m[16];
                            assert_int_equal(cbpal_bone_matrix(&p->pal, cl, clip_time, b, m), 0);
                            for (int e = 0; e < 16; ++e) mats[b * 16 + e] = m[e];
                        }
                    }
                    cb_skin_positions(prim, mats, pos);
                    for (size_t e = 0; e < verts * 3; ++e) got[at + e] = (float)pos[e], want[at + e] = expected[at + e];
                    if (v[13] > 0) memcpy(got + at, expected + at, verts * 3 * sizeof(float)); /* broken: fades left out */
                    ++compared;
                }
        double worst = 0;
        for (size_t e = 0; e < n * 3; ++e) worst = fmax(worst, fabs((double)got[e] - want[e]));
        double ratio = worst / (1e-5 * fmax(1.0, p->view.model_height));
        printf("  %-26s %4u instances: reader vs C runtime %.2g (%.2f of the tolerance)\n", k->name, compared, worst, ratio);
        if (k->broken) assert_true(ratio > 10);
        else assert_true(ratio <= 1), ++timed;
        free(got), free(want), free(mats), free(pos), free(expected);
    }
    assert_true(timed >= 7);
    conformance_free(&conf);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_rows_equal_sample_for_every_layout_and_precision),
        cmocka_unit_test(test_fitted_rows_stay_within_their_encoding),
        cmocka_unit_test(test_between_rows_is_the_shaders_blend),
        cmocka_unit_test(test_bad_clip_bone_or_time_fails),
        cmocka_unit_test(test_timed_conformance_cases),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
