/* test_palette.c - every layout x precision on every model: decoded matrices against exact
 * sampling within the encoding's own bound, wrapping, quaternion hemispheres, refusals. */
#include "testutil.h"

#include <math.h>

#include "crowdbake/palette.h"

/* Largest error the encoding allows in the 3x3 terms and in the translation of one matrix,
 * from the precision's definition (docs/pal-format.md, "Precision"). */
static void bounds(const cb_palette *p, const double m[16], uint32_t bone, double *lin, double *trans)
{
    double big = 0, tmax = 0;
    *lin = *trans = 0;
    for (int c = 0; c < 3; ++c)
        for (int r = 0; r < 3; ++r) big = fmax(big, fabs(m[c * 4 + r]));
    for (int k = 0; k < 3; ++k) tmax = fmax(tmax, fabs(m[12 + k]));
    double box = 0;
    for (int k = 0; k < 3; ++k) box = fmax(box, (double)p->bounds_max[k] - p->bounds_min[k]);
    const double f32 = 2e-7, h16 = 1.0 / 2048, sn16 = 0.5 / 32767, un16 = 0.5 / 65535;
    if (p->layout != CB_LAYOUT_QPOS) {
        if (p->precision == CB_PRECISION_FLOAT) *lin = f32 * big, *trans = f32 * tmax;
        if (p->precision == CB_PRECISION_HALF) { /* the translation holds p = A b + t less the offset o */
            const float *b = p->bind_positions + (size_t)bone * 3, *o = p->position_offsets + (size_t)bone * 3;
            double rel = 0, blen = fabs(b[0]) + fabs(b[1]) + fabs(b[2]);
            for (int r = 0; r < 3; ++r)
                rel = fmax(rel, fabs(m[r] * b[0] + m[4 + r] * b[1] + m[8 + r] * b[2] + m[12 + r] - o[r]));
            *lin = h16 * big + 1e-7, *trans = h16 * rel + *lin * blen + f32 * (tmax + big * blen) + 1e-7;
        }
        if (p->precision == CB_PRECISION_U16)
            *lin = (sn16 + f32) * p->linear_range + f32 * big, *trans = (un16 + f32) * box + f32 * tmax;
        return;
    }
    /* qpos: each quaternion component off by dq moves a rotation term by at most 4 dq; the
     * translation t = p - A b carries the position's error and |dA| |b|. */
    const float *b = p->bind_positions + (size_t)bone * 3;
    double blen = fabs(b[0]) + fabs(b[1]) + fabs(b[2]), s = big, dq, dp, ds;
    double plen = tmax + big * blen;
    if (p->precision == CB_PRECISION_FLOAT) dq = f32, dp = f32 * plen, ds = f32 * s;
    else if (p->precision == CB_PRECISION_HALF) { /* the position is stored less the bone's offset o */
        const float *o = p->position_offsets + (size_t)bone * 3;
        double rel = 0;
        for (int r = 0; r < 3; ++r)
            rel = fmax(rel, fabs(m[r] * b[0] + m[4 + r] * b[1] + m[8 + r] * b[2] + m[12 + r] - o[r]));
        dq = h16, dp = h16 * rel + f32 * plen, ds = h16 * s;
    }
    else dq = sn16, dp = (un16 + f32) * box + f32 * plen, ds = (un16 + f32) * p->linear_range;
    /* qpos stores a similarity: a rig whose scale is non-uniform by up to the 1e-4 qpos
     * accepts (float noise in exported scales) also loses that much. */
    double l[3], mean = 0, nonuniform = 0;
    for (int c = 0; c < 3; ++c)
        l[c] = sqrt(m[c * 4] * m[c * 4] + m[c * 4 + 1] * m[c * 4 + 1] + m[c * 4 + 2] * m[c * 4 + 2]), mean += l[c] / 3;
    for (int c = 0; c < 3; ++c) nonuniform = fmax(nonuniform, fabs(l[c] - mean));
    *lin = 16 * dq * s + ds + 2 * nonuniform + 1e-9;
    *trans = dp + *lin * blen + 1e-9;
}

/* Bakes `layout`/`precision` and checks every row of every clip. Returns false when the
 * layout refused the rig. */
static bool check_round_trip(cb_model *m, cb_layout layout, cb_precision precision, uint32_t max_size, double *worst_ratio)
{
    cb_error err = {0};
    cb_sampler *s = cb_sampler_create(m, 0, &err);
    assert_non_null(s);
    cb_bake_options o = cb_default_bake_options();
    o.layout = layout, o.precision = precision, o.max_texture_size = max_size;
    cb_palette p;
    if (cb_palette_bake(s, &o, NULL, 0, &p, &err) != CB_OK) {
        cb_sampler_free(s);
        if (layout == CB_LAYOUT_QPOS && strstr(err.message, "qpos layout cannot represent")) return false;
        fail_msg("%s %s/%s: %s", m->source, cb_layout_name(layout), cb_precision_name(precision), err.message);
    }
    assert_true(p.width <= max_size && p.height <= max_size);
    uint32_t joints = m->skins[0].joint_count;
    double *exact = malloc(joints * 16 * sizeof(double)), dec[16];
    for (uint32_t c = 0; c < p.clip_count; ++c) {
        cb_clip_info info;
        assert_int_equal(cb_clip_analyze(s, (int32_t)c, o.fps, p.clips[c].loops, NULL, &info, &err), CB_OK);
        assert_int_equal(info.frames, p.clips[c].frames);
        for (uint32_t f = 0; f < info.frames; ++f) {
            cb_clip_frame_matrices(s, &info, f, o.root_motion, exact);
            for (uint32_t j = 0; j < joints; ++j) {
                const double *e = exact + (size_t)j * 16;
                cb_palette_decode(&p, p.texels, p.clips[c].first_row + f, j, dec);
                double lin, trans;
                bounds(&p, e, j, &lin, &trans);
                for (int k = 0; k < 16; ++k) {
                    if (k % 4 == 3) continue; /* the constant last row */
                    double d = fabs(dec[k] - e[k]), tol = k >= 12 ? trans : lin;
                    if (tol > 0) *worst_ratio = fmax(*worst_ratio, d / tol);
                    if (d > tol)
                        fail_msg("%s %s/%s clip %u frame %u joint %u m%d: decoded %.9g, exact %.9g, bound %.3g", m->source,
                                 cb_layout_name(layout), cb_precision_name(precision), c, f, j, k, dec[k], e[k], tol);
                }
            }
        }
    }
    free(exact);
    cb_palette_free(&p);
    cb_sampler_free(s);
    return true;
}

static void round_trip_all(cb_model *m, const char *name, bool expect_qpos)
{
    for (int l = 0; l < 3; ++l)
        for (int pr = 0; pr < 3; ++pr) {
            double ratio = 0;
            bool ok = check_round_trip(m, (cb_layout)l, (cb_precision)pr, 16384, &ratio);
            if (!ok) {
                if (expect_qpos) fail_msg("%s: qpos refused unexpectedly", name);
                continue;
            }
            if (l == CB_LAYOUT_QPOS && !expect_qpos) fail_msg("%s: qpos accepted a rig with non-uniform scale", name);
            printf("  %-44s %-6s %-5s worst error %.2f of its bound\n", name, cb_layout_name((cb_layout)l),
                   cb_precision_name((cb_precision)pr), ratio);
        }
}

static void test_round_trip_shared_assets(void **state)
{
    (void)state;
    for (size_t i = 0; i < COUNT_OF(shared_models); ++i) {
        cb_model *m = load_shared(shared_models[i]);
        if (m->skin_count) round_trip_all(m, shared_models[i], strstr(shared_models[i], "spider") == NULL);
        cb_model_free(m);
    }
}

static void test_round_trip_samples(void **state)
{
    (void)state;
    for (size_t i = 0; i < COUNT_OF(sample_names); ++i) {
        char path[1024];
        sample_path(path, sizeof path, sample_names[i]);
        cb_model *m = load_or_fail(path);
        round_trip_all(m, sample_names[i], true);
        cb_model_free(m);
    }
}

static void test_wrapping_keeps_every_texel_addressable(void **state)
{
    (void)state;
    cb_model *m = load_shared("assets/robot-quaternius-raylib/robot.glb");
    cb_error err = {0};
    cb_sampler *s = cb_sampler_create(m, 0, &err);
    cb_bake_options o = cb_default_bake_options();
    o.layout = CB_LAYOUT_MAT4, o.precision = CB_PRECISION_FLOAT;
    cb_palette flat, wrapped;
    assert_int_equal(cb_palette_bake(s, &o, NULL, 0, &flat, &err), CB_OK);
    assert_int_equal(flat.blocks, 1);
    o.max_texture_size = 512; /* 43 bones x 4 texels = 172 per row: 2 blocks fit in 512 */
    double ratio = 0;
    assert_true(check_round_trip(m, o.layout, o.precision, 512, &ratio));
    assert_int_equal(cb_palette_bake(s, &o, NULL, 0, &wrapped, &err), CB_OK);
    printf("  robot: %u rows -> %ux%u in %u blocks of %u rows\n", flat.rows, wrapped.width, wrapped.height,
           wrapped.blocks, wrapped.height);
    assert_true(wrapped.blocks == 2 && wrapped.width <= 512 && wrapped.height <= 512);
    assert_true(wrapped.height * wrapped.blocks >= wrapped.rows && (wrapped.blocks - 1) * wrapped.height < wrapped.rows);
    for (uint32_t r = 0; r < flat.rows; ++r)
        for (uint32_t j = 0; j < flat.bone_count; ++j) {
            double a[16], b[16];
            cb_palette_decode(&flat, flat.texels, r, j, a);
            cb_palette_decode(&wrapped, wrapped.texels, r, j, b);
            assert_memory_equal(a, b, sizeof a);
        }
    o.max_texture_size = 128; /* narrower than one row */
    cb_palette none;
    assert_int_equal(cb_palette_bake(s, &o, NULL, 0, &none, &err), CB_ERR_INPUT);
    assert_non_null(strstr(err.message, "wider than the texture size limit 128"));
    assert_int_equal(err.setting, CB_SETTING_MAX_TEXTURE_SIZE); /* the front end names its flag */
    cb_palette_free(&flat);
    cb_palette_free(&wrapped);
    cb_sampler_free(s);
    cb_model_free(m);
}

static void test_qpos_refuses_non_uniform_scale_naming_joint_and_frame(void **state)
{
    (void)state;
    cb_model *m = load_shared("assets/spider-animated-luanti/gltf_spider_animated.gltf");
    cb_error err = {0};
    cb_sampler *s = cb_sampler_create(m, 0, &err);
    cb_bake_options o = cb_default_bake_options();
    cb_palette p;
    assert_int_equal(cb_palette_bake(s, &o, NULL, 0, &p, &err), CB_ERR_LAYOUT);
    assert_non_null(strstr(err.message, "joint '"));
    assert_non_null(strstr(err.message, "at frame "));
    assert_non_null(strstr(err.message, "use the affine or the mat4 layout"));
    assert_int_equal(err.setting, CB_SETTING_LAYOUT);
    cb_sampler_free(s);
    cb_model_free(m);
}

static void test_qpos_rows_stay_in_one_hemisphere(void **state)
{
    (void)state;
    const char *models[] = {"assets/fox-bevy/Fox.glb", "assets/robot-quaternius-raylib/robot.glb",
                            "assets/multitrack-luanti/gltf_multi_track_1.glb"};
    for (int i = 0; i < 3; ++i) {
        cb_model *m = load_shared(models[i]);
        cb_error err = {0};
        cb_sampler *s = cb_sampler_create(m, 0, &err);
        cb_bake_options o = cb_default_bake_options();
        o.precision = CB_PRECISION_FLOAT;
        cb_palette p;
        assert_int_equal(cb_palette_bake(s, &o, NULL, 0, &p, &err), CB_OK);
        uint32_t wrap_breaks = 0;
        for (uint32_t c = 0; c < p.clip_count; ++c)
            for (uint32_t f = 0; f < p.clips[c].frames; ++f) {
                bool wrap = f + 1 == p.clips[c].frames;
                if (wrap && !p.clips[c].loops) continue;
                uint32_t next = p.clips[c].first_row + (wrap ? 0 : f + 1), row = p.clips[c].first_row + f;
                for (uint32_t j = 0; j < p.bone_count; ++j) {
                    uint32_t x0, y0, x1, y1;
                    cb_palette_texel_xy(&p, row, j, &x0, &y0);
                    cb_palette_texel_xy(&p, next, j, &x1, &y1);
                    const float *a = (const float *)p.texels + ((size_t)y0 * p.width + x0) * 4;
                    const float *b = (const float *)p.texels + ((size_t)y1 * p.width + x1) * 4;
                    double dot = a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3];
                    if (dot < 0 && !wrap) fail_msg("%s clip %u rows %u->%u bone %u flip hemisphere", models[i], c, f, f + 1, j);
                    if (dot < 0) ++wrap_breaks;
                }
            }
        /* Only a bone that turns a full circle over a loop may break at the wrap, and the bake
         * reports it (the multitrack file spins its bones 360 degrees; the robot's Dance, a loop by
         * its name and poses, turns one bone a full circle). */
        printf("  %s: %u wrap break(s), reported %u\n", models[i], wrap_breaks, p.quat_hemisphere_breaks);
        assert_int_equal(wrap_breaks, p.quat_hemisphere_breaks);
        if (i == 0) assert_int_equal(wrap_breaks, 0);
        if (i == 1) assert_int_equal(wrap_breaks, 1);
        cb_palette_free(&p);
        cb_sampler_free(s);
        cb_model_free(m);
    }
}

static void test_half_conversion(void **state)
{
    (void)state;
    /* Known binary16 encodings. */
    assert_int_equal(cb_float_to_half(1.0f), 0x3c00);
    assert_int_equal(cb_float_to_half(-2.0f), 0xc000);
    assert_int_equal(cb_float_to_half(65504.0f), 0x7bff);
    assert_int_equal(cb_float_to_half(1e6f), 0x7c00);
    assert_int_equal(cb_float_to_half(5.9604645e-8f), 0x0001); /* smallest subnormal */
    assert_int_equal(cb_float_to_half(1.0f + 1.0f / 2048), 0x3c00); /* a tie rounds to even */
    assert_int_equal(cb_float_to_half(1.0f + 3.0f / 2048), 0x3c02);
    for (uint32_t h = 0; h < 0x7c00; ++h) assert_int_equal(cb_float_to_half(cb_half_to_float((uint16_t)h)), h);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_half_conversion),
        cmocka_unit_test(test_round_trip_shared_assets),
        cmocka_unit_test(test_round_trip_samples),
        cmocka_unit_test(test_wrapping_keeps_every_texel_addressable),
        cmocka_unit_test(test_qpos_refuses_non_uniform_scale_naming_joint_and_frame),
        cmocka_unit_test(test_qpos_rows_stay_in_one_hemisphere),
    };
    return cmocka_run_group_tests_name("palette", tests, NULL, NULL);
}
