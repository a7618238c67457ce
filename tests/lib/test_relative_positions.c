/* test_relative_positions.c - qpos/half palettes store joint positions relative to each bone's
 * offset (.pal version 3): their precision on real models, and older versions still read. Split
 * from test_motion.c, which is about how clips move. */
#define _DEFAULT_SOURCE
#include "testutil.h"

#include <limits.h>
#include <math.h>

#include "crowdbake_pal.h"
#include "crowdbake/pal_view.h"
#include "crowdbake/runtime.h"

#define TMP TEST_TMP "/relative-positions"
#define COW "assets/quaternius-cow/Cow.glb"

static int setup(void **state)
{
    (void)state;
    return system("rm -rf " TMP " && mkdir -p " TMP);
}

/* qpos/half stores each joint's position less its bone's offset, the centre of the bone's
 * positions over the palette, which stays small (and precise in half floats) on a model far from
 * the origin or a body that falls or travels: version 3 files with an offset table. Every
 * qpos/half bake of Cow and the samples stays under 0.5 mm per metre of height (bind positions
 * as offsets, version 2: Cow 0.60, the quadruped with its travel 0.74). A version 2 file
 * (relative to the bind positions) and a version 1 file (absolute) still read back the same
 * matrices; a newer version is refused. */
static double half_error_mm(const char *model, const char *layout, const char *root_motion, const char *out)
{
    char cmd[4096];
    static char text[65536];
    /* --row-travel off: version 3 exactly (a striding loop's travel offsets would make it version 5) */
    snprintf(cmd, sizeof cmd, "%s bake %s --fps 30 -o %s --layout %s --precision half --root-motion %s --row-travel off --json",
             crowdbake_exe(), model, out, layout, root_motion);
    assert_int_equal(run_command(cmd, text, sizeof text), 0);
    const char *e = strstr(text, "\"max_error_mm_per_m\": ");
    assert_non_null(e);
    return atof(e + strlen("\"max_error_mm_per_m\": "));
}

/* file bytes rewritten as an older version: position texels relative to `offset(bone)`. */
static unsigned char *rewrite_positions(const cbpal_file *f, const unsigned char *d, size_t size, uint32_t version,
                                        bool relative_to_bind)
{
    unsigned char *v = malloc(size);
    memcpy(v, d, size);
    const cbpal_header *h = &f->header;
    for (uint32_t r = 0; r < h->rows; ++r)
        for (uint32_t j = 0; j < h->bone_count; ++j) {
            cbpal_bone bone;
            cbpal_get_bone(f, j, &bone);
            uint32_t x, y;
            cbpal_texel_xy(h, r, j, &x, &y);
            unsigned char *t = v + h->payload_offset + ((size_t)y * h->width + x + 1) * 8; /* texel 1: position */
            for (int k = 0; k < 3; ++k) {
                uint16_t half;
                memcpy(&half, t + 2 * k, 2);
                float p = cb_half_to_float(half) + bone.position_offset[k];
                half = cb_float_to_half(relative_to_bind ? p - bone.bind_position[k] : p);
                memcpy(t + 2 * k, &half, 2);
            }
        }
    uint32_t flags = relative_to_bind ? h->flags : h->flags & ~(uint32_t)CBPAL_FLAG_POSITIONS_RELATIVE;
    memcpy(v + 8, &version, 4);
    memcpy(v + 12, &flags, 4);
    memset(v + 184, 0, 8); /* no offset table before version 3 */
    memset(v + CBPAL_CHECKSUM_OFFSET, 0, 8);
    uint64_t sum = cbpal_xxh64(v, h->payload_offset + h->payload_size);
    memcpy(v + CBPAL_CHECKSUM_OFFSET, &sum, 8);
    return v;
}

static void test_half_positions_relative_to_offsets(void **state)
{
    (void)state;
    char fox[1024], cow[1024], quadruped[600];
    shared_path(fox, sizeof fox, "assets/fox-bevy/Fox.glb");
    shared_path(cow, sizeof cow, COW);
    sample_path(quadruped, sizeof quadruped, "quadruped");
    /* Before: qpos relative to the bind positions, mat4 and affine absolute. */
    struct { const char *model, *layout, *root_motion; double before; } cases[] = {
        {cow, "qpos", "keep", 0.603},       {cow, "qpos", "in-place", 0.615}, {quadruped, "qpos", "keep", 0.742},
        {quadruped, "qpos", "in-place", 0.404}, {cow, "mat4", "in-place", 0.77}, {cow, "affine", "keep", 0.678},
        {quadruped, "mat4", "keep", 0.841}, {fox, "affine", "keep", 0.433},   {fox, "qpos", "keep", 0.206}};
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
        double mm = half_error_mm(cases[i].model, cases[i].layout, cases[i].root_motion, TMP "/half.pal");
        printf("  %s %s %s/half: encoding error %.3f mm/m (before: %.3f)\n", strrchr(cases[i].model, '/') + 1,
               cases[i].root_motion, cases[i].layout, mm, cases[i].before);
        assert_true(mm < 0.5);
    }

    size_t size;
    unsigned char *d = (unsigned char *)read_whole_file(TMP "/half.pal", &size); /* Fox */
    assert_non_null(d);
    cbpal_file f;
    char msg[256];
    assert_int_equal(cbpal_open_memory(d, size, CBPAL_VERIFY_CHECKSUM, &f, msg, sizeof msg), 0);
    assert_int_equal(f.header.version, 3);
    assert_true(f.header.flags & CBPAL_FLAG_POSITIONS_RELATIVE);
    const cbpal_header *h = &f.header;
    unsigned char *v2 = rewrite_positions(&f, d, size, 2, true), *v1 = rewrite_positions(&f, d, size, 1, false);
    cbpal_file g2, g1;
    assert_int_equal(cbpal_open_memory(v2, size, CBPAL_VERIFY_CHECKSUM, &g2, msg, sizeof msg), 0);
    assert_int_equal(cbpal_open_memory(v1, size, CBPAL_VERIFY_CHECKSUM, &g1, msg, sizeof msg), 0);
    cb_palette a, b2, b1;
    cb_error err = {0};
    assert_int_equal(cb_palette_view(&f, &a, &err), CB_OK);
    assert_int_equal(cb_palette_view(&g2, &b2, &err), CB_OK);
    assert_int_equal(cb_palette_view(&g1, &b1, &err), CB_OK);
    assert_true(a.positions_relative && b2.positions_relative && !b1.positions_relative);
    double worst = 0, moved = 0;
    for (uint32_t j = 0; j < h->bone_count; ++j)
        for (int k = 0; k < 3; ++k) moved = fmax(moved, fabs(a.position_offsets[j * 3 + k] - b2.position_offsets[j * 3 + k]));
    for (uint32_t r = 0; r < h->rows; r += 7)
        for (uint32_t j = 0; j < h->bone_count; ++j) {
            double ma[16], m2[16], m1[16];
            cb_palette_decode(&a, f.texels, r, j, ma);
            cb_palette_decode(&b2, g2.texels, r, j, m2);
            cb_palette_decode(&b1, g1.texels, r, j, m1);
            for (int k = 12; k < 15; ++k) worst = fmax(worst, fmax(fabs(ma[k] - m2[k]), fabs(ma[k] - m1[k])));
        }
    printf("  versions 3, 2 and 1 decode within %.3g units (offsets up to %.3g from the bind positions)\n", worst, moved);
    assert_true(moved > 1); /* version 2's offsets (the bind positions) are not version 3's */
    assert_true(worst < 0.1);
    cb_palette_view_free(&a), cb_palette_view_free(&b2), cb_palette_view_free(&b1);
    cbpal_close(&g2), cbpal_close(&g1);
    /* A newer version is refused with the fix. */
    uint32_t eight = 8;
    memcpy(v1 + 8, &eight, 4);
    assert_int_not_equal(cbpal_open_memory(v1, size, 0, &g1, msg, sizeof msg), 0);
    assert_non_null(strstr(msg, "version 8 is newer than this reader (version 7); update the reader"));
    cbpal_close(&f);
    free(v1), free(v2), free(d);
}


int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_half_positions_relative_to_offsets),
    };
    return cmocka_run_group_tests_name("relative_positions", tests, setup, NULL);
}
