/* test_verify.c - verification thresholds and the preview sheets (global and local rows). */
#define _DEFAULT_SOURCE
#include "testutil.h"

#include <math.h>
#include <png.h>
#include <sys/stat.h>

#include "report/preview.h"
#include "crowdbake/runtime.h"

#define TMP TEST_TMP "/verify"
#define PREVIEWS BUILD_DIR "/previews"

/* Bakes `path` and verifies every clip in process. */
static void verify_model(const char *path, cb_layout l, cb_precision pr, double fps, double *quant, double *interp,
                         double *bake_error, double *height, bool transpose)
{
    cb_model *m = load_or_fail(path);
    cb_error err = {0};
    cb_sampler *s = cb_sampler_create(m, 0, &err);
    cb_bake_options o = cb_default_bake_options();
    o.layout = l, o.precision = pr, o.fps = fps, o.root_motion = CB_ROOT_MOTION_IN_PLACE;
    cb_palette p;
    assert_int_equal(cb_palette_bake(s, &o, NULL, 0, &p, &err), CB_OK);
    if (transpose) /* the reference runtime's shipped bug, in a float mat4 palette */
        for (size_t b = 0; b + 16 <= p.texel_bytes / 4; b += 16)
            for (int r = 0; r < 4; ++r)
                for (int c = r + 1; c < 4; ++c) {
                    float *t = (float *)p.texels, x = t[b + r * 4 + c];
                    t[b + r * 4 + c] = t[b + c * 4 + r], t[b + c * 4 + r] = x;
                }
    *quant = *interp = 0;
    for (uint32_t c = 0; c < p.clip_count; ++c) {
        cb_clip_error e;
        assert_int_equal(cb_verify_clip(s, &p, p.texels, c, (int32_t)c, 32, &e, &err), CB_OK);
        *quant = fmax(*quant, e.quant_max);
        *interp = fmax(*interp, e.interp_max);
    }
    *bake_error = p.max_error;
    *height = p.model_height;
    cb_palette_free(&p);
    cb_sampler_free(s);
    cb_model_free(m);
}

static void test_verify_agrees_with_the_bake_and_converges(void **state)
{
    (void)state;
    char paths[4][1024];
    snprintf(paths[0], sizeof paths[0], "%s/quadruped.glb", samples_dir());
    snprintf(paths[1], sizeof paths[1], "%s/fish.glb", samples_dir());
    snprintf(paths[2], sizeof paths[2], "%s/bird.glb", samples_dir());
    shared_path(paths[3], sizeof paths[3], "assets/fox-bevy/Fox.glb");
    for (int i = 0; i < 4; ++i)
        for (int l = 0; l < 3; ++l)
            for (int pr = 0; pr < 3; ++pr) {
                double q, in30, in120, bake, h, q2, b2;
                verify_model(paths[i], (cb_layout)l, (cb_precision)pr, 30, &q, &in30, &bake, &h, false);
                verify_model(paths[i], (cb_layout)l, (cb_precision)pr, 120, &q2, &in120, &b2, &h, false);
                /* At the baked rows the runtime reads exactly what the bake measured. */
                if (fabs(q - bake) > 1e-6 * fmax(1, h)) fail_msg("%s: verify %g, bake %g", paths[i], q, bake);
                /* Between rows, a finer bake interpolates better. */
                assert_true(in120 < in30);
                if (pr == CB_PRECISION_FLOAT)
                    printf("  %-40s %-6s: at frames %.4f mm/m; between them %.2f mm/m at 30 fps, %.2f at 120 fps\n",
                           strrchr(paths[i], '/') + 1, cb_layout_name((cb_layout)l), q / h * 1000, in30 / h * 1000,
                           in120 / h * 1000);
            }
}

static void test_verify_catches_a_transposed_palette(void **state)
{
    (void)state;
    char path[1024];
    snprintf(path, sizeof path, "%s/quadruped.glb", samples_dir());
    double q, in, bake, h;
    verify_model(path, CB_LAYOUT_MAT4, CB_PRECISION_FLOAT, 30, &q, &in, &bake, &h, true);
    printf("  transposed mat4: %.0f mm/m at the baked frames\n", q / h * 1000);
    assert_true(q / h * 1000 > 100); /* the crumpled herd */
}

static void test_verify_exit_code(void **state)
{
    (void)state;
    char cmd[4096], out[8192], fox[1024];
    shared_path(fox, sizeof fox, "assets/fox-bevy/Fox.glb");
    snprintf(cmd, sizeof cmd, "mkdir -p " TMP " && %s bake %s --fps 30 -o " TMP "/v.pal -q && %s verify %s " TMP "/v.pal "
             "--max-error 0.01 2>&1", crowdbake_exe(), fox, crowdbake_exe(), fox);
    assert_int_equal(run_command(cmd, out, sizeof out), EXIT_VERIFY);
    assert_non_null(strstr(out, "over --max-error"));
    snprintf(cmd, sizeof cmd, "%s verify %s " TMP "/v.pal --max-error 100 --json 2>&1", crowdbake_exe(), fox);
    assert_int_equal(run_command(cmd, out, sizeof out), 0);
    assert_non_null(strstr(out, "\"between_max_mm_per_m\""));
    char q[1024];
    snprintf(q, sizeof q, "%s/quadruped.glb", samples_dir());
    snprintf(cmd, sizeof cmd, "%s verify %s " TMP "/v.pal 2>&1", crowdbake_exe(), q);
    assert_int_equal(run_command(cmd, out, sizeof out), EXIT_INPUT); /* not its palette */
}

static bool ink(const unsigned char *p, const unsigned char bg[3], int threshold)
{
    return abs(p[0] - bg[0]) + abs(p[1] - bg[1]) + abs(p[2] - bg[2]) > threshold;
}

/* A sheet's pixels, RGBA, for the caller to free. */
static unsigned char *read_sheet(const char *png, uint32_t *w, uint32_t *h)
{
    png_image img;
    memset(&img, 0, sizeof img);
    img.version = PNG_IMAGE_VERSION;
    assert_true(png_image_begin_read_from_file(&img, png));
    img.format = PNG_FORMAT_RGBA;
    unsigned char *px = malloc(PNG_IMAGE_SIZE(img));
    assert_true(png_image_finish_read(&img, NULL, px, 0, NULL));
    *w = img.width, *h = img.height;
    return px;
}

/* A sheet as preview.h lays it out: every cell shows the animal, and the labels are there, where
 * they should be: the header's text, each clip's band from its left edge across its name and
 * numbers, and each cell's time in its top-left corner. */
static void check_sheet(const char *png, uint32_t rows, uint32_t cols, uint32_t cell)
{
    static const unsigned char sheet_bg[3] = {237, 237, 230}, band_bg[3] = {214, 216, 208}, header_bg[3] = {52, 58, 64};
    struct { uint32_t width, height; } img;
    unsigned char *px = read_sheet(png, &img.width, &img.height);
    assert_int_equal(img.width, cols * cell);
    assert_int_equal(img.height, CB_PREVIEW_HEADER + rows * (CB_PREVIEW_BAND + cell));
#define PX(x, y) (px + ((size_t)(y) * img.width + (x)) * 4)
    uint32_t header_ink = 0, header_fill = 0;
    for (uint32_t y = 0; y < CB_PREVIEW_HEADER; ++y)
        for (uint32_t x = 0; x < img.width; ++x) header_ink += ink(PX(x, y), header_bg, 120), header_fill += !ink(PX(x, y), header_bg, 10);
    if (header_fill < img.width * CB_PREVIEW_HEADER / 2 || header_ink < 300)
        fail_msg("%s: the header has %u background and %u text pixels", png, header_fill, header_ink);
    for (uint32_t r = 0; r < rows; ++r) {
        uint32_t top = CB_PREVIEW_HEADER + r * (CB_PREVIEW_BAND + cell) + CB_PREVIEW_BAND, left = img.width, right = 0;
        for (uint32_t y = top - CB_PREVIEW_BAND; y < top; ++y)
            for (uint32_t x = 0; x < img.width; ++x)
                if (ink(PX(x, y), band_bg, 120)) left = x < left ? x : left, right = x > right ? x : right;
        /* name, loop, rows, fps, length and the errors: most of the band's width */
        if (left > 12 || right < img.width / 2) fail_msg("%s: clip %u's label spans x %u..%u", png, r, left, right);
        for (uint32_t c = 0; c < cols; ++c) {
            uint32_t drawn = 0, time_ink = 0;
            for (uint32_t y = top; y < top + cell; ++y)
                for (uint32_t x = c * cell; x < (c + 1) * cell; ++x) {
                    bool label = y < top + 16 && x < c * cell + 44;
                    if (label) time_ink += ink(PX(x, y), sheet_bg, 120);
                    else drawn += ink(PX(x, y), sheet_bg, 30);
                }
            if (drawn < cell * cell / 200) fail_msg("%s: cell %u,%u is empty", png, r, c);
            if (time_ink < 20) fail_msg("%s: cell %u,%u has no time label", png, r, c);
        }
    }
#undef PX
    free(px);
}

static void test_preview_sheets_of_the_samples(void **state)
{
    (void)state;
    const char *names[] = {"quadruped", "fish", "bird"};
    const uint32_t clips[] = {5, 1, 2};
    mkdir(PREVIEWS, 0777); /* CI keeps these as artifacts */
    for (int i = 0; i < 3; ++i) {
        char cmd[4096], out[2048];
        snprintf(cmd, sizeof cmd, "%s bake %s/%s.glb --fps 30 -o " PREVIEWS "/%s.pal -q && %s preview %s/%s.glb " PREVIEWS
                 "/%s.pal -o " PREVIEWS "/%s.png --columns 6 --cell 96 2>&1",
                 crowdbake_exe(), samples_dir(), names[i], names[i], crowdbake_exe(), samples_dir(), names[i], names[i],
                 names[i]);
        assert_int_equal(run_command(cmd, out, sizeof out), 0);
        char png[256];
        snprintf(png, sizeof png, PREVIEWS "/%s.png", names[i]);
        check_sheet(png, clips[i], 6, 96);
        printf("  %s", out);
    }
}

/* A palette of local rows (.pal version 6; its auto rates put Gallop's rows on its keys, version 7) drawn by the
 * preview as the runtimes draw it: the shaders' CB_LOCAL_ROWS and the bind texture's parents and ranges (without
 * them every cell was empty). Husky's loops, cell by cell, are the global bake's sheet: the same poses within
 * 1 mm/m, so the animal covers the same pixels but for a few on its outline. */
static void test_preview_of_local_rows(void **state)
{
    (void)state;
    char model[1024], cmd[4096], out[2048];
    shared_path(model, sizeof model, "assets/quaternius-husky/Husky.glb");
    const char *clips = "'AnimalArmature|Gallop,AnimalArmature|Walk'", *space[2] = {"local", "global"};
    unsigned char *px[2];
    uint32_t w = 0, h = 0;
    for (int i = 0; i < 2; ++i) {
        snprintf(cmd, sizeof cmd, "%s bake %s --clip %s --bone-space %s -o " PREVIEWS "/husky_%s.pal -q && %s preview %s "
                 PREVIEWS "/husky_%s.pal -o " PREVIEWS "/husky_%s.png --columns 6 --cell 96 2>&1", crowdbake_exe(), model,
                 clips, space[i], space[i], crowdbake_exe(), model, space[i], space[i]);
        assert_int_equal(run_command(cmd, out, sizeof out), 0);
        char png[256];
        snprintf(png, sizeof png, PREVIEWS "/husky_%s.png", space[i]);
        check_sheet(png, 2, 6, 96);
        px[i] = read_sheet(png, &w, &h);
    }
    uint32_t cells = 0, differ = 0;
    for (uint32_t r = 0; r < 2; ++r) {
        uint32_t top = CB_PREVIEW_HEADER + r * (CB_PREVIEW_BAND + 96) + CB_PREVIEW_BAND;
        for (uint32_t y = top + 16; y < top + 96; ++y) /* below the time labels */
            for (uint32_t x = 0; x < w; ++x, ++cells) {
                const unsigned char *a = px[0] + ((size_t)y * w + x) * 4, *b = px[1] + ((size_t)y * w + x) * 4;
                differ += abs(a[0] - b[0]) + abs(a[1] - b[1]) + abs(a[2] - b[2]) > 60;
            }
    }
    printf("  Husky, local rows against global: %u of %u cell pixels differ\n", differ, cells);
    assert_true(differ * 200 < cells); /* under 0.5% */
    free(px[0]), free(px[1]);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_verify_agrees_with_the_bake_and_converges),
        cmocka_unit_test(test_verify_catches_a_transposed_palette),
        cmocka_unit_test(test_verify_exit_code),
        cmocka_unit_test(test_preview_sheets_of_the_samples),
        cmocka_unit_test(test_preview_of_local_rows),
    };
    return cmocka_run_group_tests_name("verify", tests, NULL, NULL);
}
