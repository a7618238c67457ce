/* test_encode_deferred.c - u16 and half palettes, whose encoding waits for every clip (u16 for
 * the value ranges, half for the position offsets), against a float bake of the same rig
 * encoded again here: the ranges and offsets recomputed from the float texels, every texel
 * quantized by the formulas of docs/pal-format.md and compared byte for byte. The bake stages
 * qpos positions in their texels and stashes the quaternions (palette_stage_qpos), and keeps
 * mat4/affine rows aside; this checks that what comes out is what encoding the values would
 * give, for every layout, on several threads, with wrapped rows and with --fit-rows. */
#include "testutil.h"

#include <math.h>

#include "crowdbake/palette.h"

static float texel_float(const cb_palette *p, uint32_t row, uint32_t bone, int i)
{
    uint32_t x, y;
    cb_palette_texel_xy(p, row, bone, &x, &y);
    const unsigned char *d = (const unsigned char *)p->texels + ((size_t)y * p->width + x) * 16 + (size_t)i * 4;
    uint32_t v = (uint32_t)d[0] | (uint32_t)d[1] << 8 | (uint32_t)d[2] << 16 | (uint32_t)d[3] << 24;
    float f;
    memcpy(&f, &v, 4);
    return f;
}

static uint16_t texel_u16(const cb_palette *p, uint32_t row, uint32_t bone, int i)
{
    uint32_t x, y;
    cb_palette_texel_xy(p, row, bone, &x, &y);
    const unsigned char *d = (const unsigned char *)p->texels + ((size_t)y * p->width + x) * 8 + (size_t)i * 2;
    return (uint16_t)(d[0] | d[1] << 8);
}

/* The joint's position p = A b + t from a bone's float texels (mat4: columns, affine: rows). */
static double position(const cb_palette *f, uint32_t row, uint32_t j, int r)
{
    const float *b = f->bind_positions + (size_t)j * 3;
    bool mat4 = f->layout == CB_LAYOUT_MAT4;
    double v[4];
    for (int k = 0; k < 4; ++k) v[k] = texel_float(f, row, j, mat4 ? k * 4 + r : r * 4 + k);
    return v[0] * b[0] + v[1] * b[1] + v[2] * b[2] + v[3];
}

/* Index of the value that holds translation / position axis k. */
static int position_value(cb_layout l, int k) { return l == CB_LAYOUT_QPOS ? 4 + k : l == CB_LAYOUT_MAT4 ? 12 + k : k * 4 + 3; }

/* u16: x = (v - offset) / range clamped to [lo, 1], times the steps, rounded to nearest even. */
static uint16_t quantize(double v, double offset, double range, bool snorm)
{
    double x = (v - offset) * (range > 0 ? 1 / range : 0);
    x = x < (snorm ? -1 : 0) ? (snorm ? -1 : 0) : x;
    x = x > 1 ? 1 : x;
    return (uint16_t)(int16_t)lrint(x * (snorm ? 32767 : 65535));
}

static uint16_t expected_u16(const cb_palette *p, int i, float v)
{
    cb_layout l = p->layout;
    for (int k = 0; k < 3; ++k)
        if (i == position_value(l, k)) return quantize(v, p->bounds_min[k], (double)p->bounds_max[k] - p->bounds_min[k], false);
    if (l == CB_LAYOUT_QPOS) return i < 4 ? quantize(v, 0, 1, true) : quantize(v, 0, p->linear_range, false);
    if (l == CB_LAYOUT_MAT4 && i % 4 == 3) return v ? 65535 : 0; /* the constant last row */
    return quantize(v, 0, p->linear_range, true);
}

/* The ranges and offsets the deferred bake must have found, from the float texels. */
static void check_ranges(const cb_palette *f, const cb_palette *p, const char *what)
{
    uint32_t values = f->texels_per_bone * 4;
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY}, linear = 0;
    for (uint32_t r = 0; r < f->rows; ++r)
        for (uint32_t j = 0; j < f->bone_count; ++j)
            for (uint32_t i = 0; i < values; ++i) {
                double v = texel_float(f, r, j, (int)i);
                int axis = -1;
                for (int k = 0; k < 3; ++k) axis = (int)i == position_value(f->layout, k) ? k : axis;
                if (axis >= 0) lo[axis] = fmin(lo[axis], v), hi[axis] = fmax(hi[axis], v);
                else if (f->layout == CB_LAYOUT_QPOS ? i == 7 : !(f->layout == CB_LAYOUT_MAT4 && i % 4 == 3))
                    linear = fmax(linear, fabs(v));
            }
    if (p->precision == CB_PRECISION_U16) {
        for (int k = 0; k < 3; ++k) {
            if (p->bounds_min[k] != (float)lo[k] || p->bounds_max[k] != (float)hi[k])
                fail_msg("%s: axis %d range %.9g..%.9g, the float texels span %.9g..%.9g", what, k, p->bounds_min[k],
                         p->bounds_max[k], lo[k], hi[k]);
        }
        if (p->linear_range != (float)linear) fail_msg("%s: linear range %.9g, float texels %.9g", what, p->linear_range, linear);
        return;
    }
    for (uint32_t j = 0; j < f->bone_count; ++j) { /* half: each bone's offset, the centre of its positions' box */
        double plo[3] = {INFINITY, INFINITY, INFINITY}, phi[3] = {-INFINITY, -INFINITY, -INFINITY};
        for (uint32_t r = 0; r < f->rows; ++r)
            for (int k = 0; k < 3; ++k) {
                double x = f->layout == CB_LAYOUT_QPOS ? texel_float(f, r, j, 4 + k) : position(f, r, j, k);
                plo[k] = fmin(plo[k], x), phi[k] = fmax(phi[k], x);
            }
        for (int k = 0; k < 3; ++k)
            if (p->position_offsets[j * 3 + k] != (float)(0.5 * (plo[k] + phi[k])))
                fail_msg("%s: bone %u offset %d is %.9g, the float texels' centre %.9g", what, j, k,
                         p->position_offsets[j * 3 + k], 0.5 * (plo[k] + phi[k]));
    }
}

/* Every texel of p against the float bake f encoded here; the padding past the last row zero. */
static void check_texels(const cb_palette *f, const cb_palette *p, const char *what)
{
    check_ranges(f, p, what);
    uint32_t values = p->texels_per_bone * 4;
    for (uint32_t r = 0; r < p->rows; ++r)
        for (uint32_t j = 0; j < p->bone_count; ++j)
            for (uint32_t i = 0; i < values; ++i) {
                float v = texel_float(f, r, j, (int)i);
                uint16_t want;
                if (p->precision == CB_PRECISION_U16) {
                    want = expected_u16(p, (int)i, v);
                } else {
                    for (int k = 0; k < 3; ++k) /* half: positions less the bone's offset */
                        if ((int)i == position_value(p->layout, k))
                            v = p->layout == CB_LAYOUT_QPOS ? v - p->position_offsets[j * 3 + k]
                                                            : (float)(position(f, r, j, k) - p->position_offsets[j * 3 + k]);
                    want = cb_float_to_half(v);
                }
                uint16_t got = texel_u16(p, r, j, (int)i);
                if (got != want)
                    fail_msg("%s: row %u bone %u value %u is 0x%04x, encoding the float bake's %.9g gives 0x%04x", what, r, j,
                             i, got, texel_float(f, r, j, (int)i), want);
            }
    size_t used = (size_t)p->rows * p->row_texels * 8, zero = 0, total = p->texel_bytes;
    for (size_t b = 0; b < total; ++b) zero += ((const unsigned char *)p->texels)[b] == 0;
    assert_true(total - zero <= used); /* no stray bytes in the padding (every texel above was checked) */
}

static bool bake(cb_sampler *s, cb_layout l, cb_precision pr, uint32_t max_size, bool fit, cb_palette *p)
{
    cb_bake_options o = cb_default_bake_options();
    o.layout = l, o.precision = pr, o.max_texture_size = max_size, o.fit = fit, o.threads = 3;
    cb_error err = {0};
    if (cb_palette_bake(s, &o, NULL, 0, p, &err) == CB_OK) return true;
    if (err.status != CB_ERR_LAYOUT) fail_msg("%s/%s: %s", cb_layout_name(l), cb_precision_name(pr), err.message);
    return false; /* qpos refused a rig with non-uniform scale */
}

/* Returns the number of baked variants whose rows wrapped into several column blocks. */
static int check_model(cb_model *m, const char *name)
{
    int wrapped = 0;
    cb_error err = {0};
    cb_sampler *s = cb_sampler_create(m, 0, &err);
    assert_non_null(s);
    for (int l = 0; l < 3; ++l)
        for (int variant = 0; variant < 3; ++variant) { /* plain, wrapped into blocks, --fit-rows */
            cb_palette f, p;
            uint32_t max_size = 16384;
            if (!bake(s, (cb_layout)l, CB_PRECISION_FLOAT, max_size, false, &f)) continue;
            if (variant == 1) { /* at most a quarter of the rows per block, at least 4 blocks wide */
                max_size = f.row_texels * 4 > (f.rows + 3) / 4 ? f.row_texels * 4 : (f.rows + 3) / 4;
                cb_palette_free(&f);
                assert_true(bake(s, (cb_layout)l, CB_PRECISION_FLOAT, max_size, false, &f));
            } else if (variant == 2) {
                cb_palette_free(&f);
                assert_true(bake(s, (cb_layout)l, CB_PRECISION_FLOAT, max_size, true, &f));
            }
            wrapped += f.blocks > 1;
            for (int pr = CB_PRECISION_HALF; pr <= CB_PRECISION_U16; ++pr) {
                char what[256];
                snprintf(what, sizeof what, "%s %s/%s%s", name, cb_layout_name((cb_layout)l),
                         cb_precision_name((cb_precision)pr), variant == 1 ? " wrapped" : variant == 2 ? " fitted" : "");
                assert_true(bake(s, (cb_layout)l, (cb_precision)pr, max_size, variant == 2, &p));
                assert_int_equal(p.blocks, f.blocks);
                check_texels(&f, &p, what);
                cb_palette_free(&p);
            }
            cb_palette_free(&f);
        }
    cb_sampler_free(s);
    return wrapped;
}

static void test_deferred_encodings_match_the_float_bake_encoded(void **state)
{
    (void)state;
    int wrapped = 0;
    for (size_t i = 0; i < COUNT_OF(shared_models); ++i) {
        cb_model *m = load_shared(shared_models[i]);
        if (m->skin_count) wrapped += check_model(m, shared_models[i]);
        cb_model_free(m);
    }
    for (size_t i = 0; i < COUNT_OF(sample_names); ++i) {
        char path[1024];
        sample_path(path, sizeof path, sample_names[i]);
        cb_model *m = load_or_fail(path);
        wrapped += check_model(m, sample_names[i]);
        cb_model_free(m);
    }
    assert_true(wrapped > 0); /* the wrapped variant did wrap somewhere */
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_deferred_encodings_match_the_float_bake_encoded),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
