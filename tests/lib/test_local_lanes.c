/* test_local_lanes.c - local_points4 (src/core/local_lanes.c: four points of local rows measured
 * as lanes) against the scalar operations one point at a time, written out here as local_rate.c
 * had them: each bone's local_qpos_blend, local_qpos_compose and cb_quat_normalize down the
 * skeleton, its matrix (cb_mat4_from_trs, t = p - A b), exact less that, and cb_joint_errors.
 * Bit for bit, on Cow and Husky (matrix rigs, exact matrices as sampled) and Fox (exact global
 * rows made matrices), with the lanes mixed: different rows and fractions in each, a row against
 * itself at 0 (a palette's row), a row held (the same row both sides), rows whose quaternions lie
 * in opposite hemispheres, a zero quaternion (the identity) and a NaN (not finite). */
#include "testutil.h"

#include <math.h>
#include <string.h>

#include "../../src/core/cb_math.h"
#include "../../src/core/local_lanes.h"

/* ---- the scalar operations, one point ---- */

static cb_vec3 bind_at(const float *bind, uint32_t j) { return (cb_vec3){bind[j * 3], bind[j * 3 + 1], bind[j * 3 + 2]}; }

static void row_matrix(const local_qpos *r, cb_vec3 b, double m[16])
{
    cb_mat4_from_trs(m, (cb_vec3){0, 0, 0}, r->q, (cb_vec3){r->s, r->s, r->s});
    cb_vec3 rb = cb_mat4_transform_dir(m, b);
    m[12] = r->p.x - rb.x, m[13] = r->p.y - rb.y, m[14] = r->p.z - rb.z;
}

static bool point_scalar(const local_skeleton *k, const float *bind, const double *reach, const local_qpos *a,
                         const local_qpos *b, double f, const double *mats, const local_qpos *exact, double *diff,
                         cb_joint_error *joints)
{
    local_qpos *out = malloc(k->bones * sizeof *out);
    for (uint32_t i = 0; i < k->bones; ++i) {
        uint32_t j = k->order[i];
        int32_t p = k->parent[j];
        local_qpos l = local_qpos_blend(a[j], b[j], f);
        out[j] = p < 0 ? l : local_qpos_compose(out[p], bind_at(bind, (uint32_t)p), l);
        out[j].q = cb_quat_normalize(out[j].q);
    }
    for (uint32_t j = 0; j < k->bones; ++j) {
        double e[16], m[16];
        memset(diff + 16 * j, 0, 16 * sizeof *diff);
        if (reach[j] < 0) continue;
        if (mats) memcpy(e, mats + 16 * j, sizeof e);
        else row_matrix(&exact[j], bind_at(bind, j), e);
        row_matrix(&out[j], bind_at(bind, j), m);
        for (int n = 0; n < 16; ++n) diff[16 * j + n] = e[n] - m[n];
    }
    free(out);
    return cb_joint_errors(diff, k->bones, bind, joints);
}

/* ---- inputs ---- */

static uint64_t next_random(uint64_t *state)
{
    *state = *state * 6364136223846793005ull + 1442695040888963407ull;
    return *state >> 11;
}

static double uniform(uint64_t *state, double lo, double hi)
{
    return lo + (hi - lo) * (double)next_random(state) / (double)(1ull << 53);
}

/* Local rows near each bone's rest: a turn of up to ~0.6 rad, the position within 0.1 of the
 * bind position, the scale 0.9 .. 1.1; every quaternion on a random side. */
static void random_rows(uint64_t *state, const float *bind, uint32_t bones, local_qpos *out)
{
    for (uint32_t j = 0; j < bones; ++j) {
        cb_quat q = cb_quat_normalize((cb_quat){uniform(state, -.3, .3), uniform(state, -.3, .3), uniform(state, -.3, .3), 1});
        double sign = next_random(state) & 1 ? -1 : 1;
        out[j] = (local_qpos){{q.x * sign, q.y * sign, q.z * sign, q.w * sign},
                              {bind[j * 3] + uniform(state, -.1, .1), bind[j * 3 + 1] + uniform(state, -.1, .1),
                               bind[j * 3 + 2] + uniform(state, -.1, .1)},
                              uniform(state, .9, 1.1)};
    }
}

static bool same_bits(const double *x, const double *y, size_t n) { return memcmp(x, y, n * sizeof *x) == 0; }

/* Every lane's differences (the elements a bound or skinning reads) and terms as the scalar
 * point's. */
static void check_lanes(const local_skeleton *k, const float *bind, const double *reach, const local_qpos *const a[4],
                        const local_qpos *const b[4], const double f[4], const double *const *mats,
                        const local_qpos *const exact[4])
{
    uint32_t n = k->bones;
    double *composed = aligned_alloc(64, (n * 32 * sizeof(double) + 63) / 64 * 64), *diff = malloc(4 * n * 16 * sizeof *diff);
    double *want = malloc(n * 16 * sizeof *want);
    cb_joint_error *joints = malloc(4 * n * sizeof *joints), *want_joints = malloc(n * sizeof *want_joints);
    bool finite[4];
    local_points4(k, bind, bind, reach, a, b, f, mats, exact, composed, diff, joints, finite);
    for (int l = 0; l < 4; ++l) {
        bool want_finite = point_scalar(k, bind, reach, a[l], b[l], f[l], mats ? mats[l] : NULL, exact[l], want, want_joints);
        assert_int_equal(finite[l], want_finite);
        for (uint32_t j = 0; j < n; ++j) {
            const double *got = diff + ((size_t)l * n + j) * 16, *expect = want + (size_t)j * 16;
            for (int c = 0; c < 4; ++c) assert_true(same_bits(got + 4 * c, expect + 4 * c, 3)); /* 3, 7, 11, 15: read by none */
            const cb_joint_error *g = &joints[(size_t)l * n + j], *e = &want_joints[j];
            double gt[4] = {g->at_bind, g->stretch, g->slack_fixed, g->translation};
            double et[4] = {e->at_bind, e->stretch, e->slack_fixed, e->translation};
            if (want_finite) assert_true(same_bits(gt, et, 4));
            assert_ptr_equal(g->diff, got);
        }
    }
    free(composed), free(diff), free(want), free(joints), free(want_joints);
}

static void lanes_equal_scalar(const char *asset, bool as_matrices)
{
    cb_error err = {0};
    cb_model *m = load_shared(asset);
    cb_sampler *s = cb_sampler_create(m, 0, &err);
    palette_skin_facts facts;
    local_skeleton k;
    assert_non_null(s);
    assert_int_equal(palette_skin_facts_build(s, &facts, &err), CB_OK);
    assert_true(local_skeleton_build(m, 0, &k));
    uint32_t n = k.bones;
    local_qpos *rows = malloc(8 * n * sizeof *rows), *exact = malloc(4 * n * sizeof *exact);
    double *mats = malloc(4 * n * 16 * sizeof *mats);
    uint64_t state = 43;
    for (int r = 0; r < 8; ++r) random_rows(&state, facts.bind_positions, n, rows + r * n);
    for (int l = 0; l < 4; ++l) {
        random_rows(&state, facts.bind_positions, n, exact + l * n);
        cb_sample_joint_matrices(s, 0, m->animations[0].t0 + 0.1 * l, mats + (size_t)l * n * 16);
    }
    const double *lane_mats[4] = {mats, mats + n * 16, mats + 2 * n * 16, mats + 3 * n * 16};
    const local_qpos *ex[4] = {exact, exact + n, exact + 2 * n, exact + 3 * n};
    const double *const *use = as_matrices ? lane_mats : NULL;
    { /* quarter points of two intervals, and a row against itself (a palette's row) */
        const local_qpos *a[4] = {rows, rows, rows + n, rows + 2 * n}, *b[4] = {rows + n, rows + n, rows + 2 * n, rows + 2 * n};
        const double f[4] = {0.25, 0.75, 0.5, 0};
        check_lanes(&k, facts.bind_positions, facts.reach, a, b, f, use, ex);
    }
    { /* a held row, other rows, the ends */
        const local_qpos *a[4] = {rows + 3 * n, rows + 4 * n, rows + 5 * n, rows + 6 * n};
        const local_qpos *b[4] = {rows + 3 * n, rows + 7 * n, rows + 4 * n, rows + 5 * n};
        const double f[4] = {0.5, 1, 0.25, 0.125};
        check_lanes(&k, facts.bind_positions, facts.reach, a, b, f, use, ex);
    }
    { /* a zero quaternion (normalised to the identity) and a NaN (no bound holds) in two lanes */
        rows[6 * n + n / 2].q = (cb_quat){0, 0, 0, 0};
        rows[7 * n + n - 1].p.x = NAN;
        const local_qpos *a[4] = {rows + 6 * n, rows + 7 * n, rows, rows + 6 * n};
        const local_qpos *b[4] = {rows + 6 * n, rows, rows + n, rows + 7 * n};
        const double f[4] = {0.75, 0.25, 0.5, 0};
        check_lanes(&k, facts.bind_positions, facts.reach, a, b, f, use, ex);
    }
    free(rows), free(exact), free(mats);
    local_skeleton_free(&k);
    palette_skin_facts_free(&facts);
    cb_sampler_free(s);
    cb_model_free(m);
}

static void cow(void **state)
{
    (void)state;
    lanes_equal_scalar("assets/quaternius-cow/Cow.glb", true);
}

static void husky(void **state)
{
    (void)state;
    lanes_equal_scalar("assets/quaternius-husky/Husky.glb", true);
}

static void fox_exact_rows(void **state)
{
    (void)state;
    lanes_equal_scalar("assets/fox-bevy/Fox.glb", false);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(cow),
        cmocka_unit_test(husky),
        cmocka_unit_test(fox_exact_rows),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
