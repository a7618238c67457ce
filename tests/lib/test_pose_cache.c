/* test_pose_cache.c - the exact poses a --fps auto search keeps by clip time (src/core/pose_cache.h):
 * a time finds what was stored for it and nothing else finds it (times one ulp apart, 0 and
 * -0 are different keys); pointers stay put as the cache grows past a block; a full cache
 * refuses more and still finds what it holds; a cleared one finds nothing and is filled again;
 * a pose's extra doubles (qpos's derivation, for the search) stay with it, NaN until written.
 * And times coincide as the search counts on: row f at `steps` is row 2f at 2 x steps, the
 * same double. A block attached beside the poses (a probe's fitted rows) is found until another
 * replaces it (the one before freed: ASan's leak check holds it to that) or the cache is
 * cleared, and goes with the cache. A probe's worst point is found by its rows' count and parts,
 * replaced by the next for the same, the oldest forgotten past 16, all of them by a clear. And
 * times that are short binary fractions of a second (all their low bits zero: they once shared
 * one table entry) each find their own pose. Caches drawing on one arena (a run's kept caches,
 * sharing huge pages) fill alternately past several chunks and pages, and each finds its own
 * poses, none written over by the other's; a pose bigger than half a page gets a block of its
 * own; the caches freed (in either order) before the arena leave nothing behind. A cache that
 * releases its poses keeps its attachments and worst points, and its blocks serve the next. */
#include "testutil.h"

#include <math.h>

#include "../../src/core/pose_cache.h"
#include "crowdbake/core.h"

enum { BONES = 3 };

/* A pose whose every value says which time it is for. */
static void fill(double *pose, double t)
{
    for (int k = 0; k < BONES * 16; ++k) pose[k] = t * 1000 + k;
}

static void expect_pose(const double *pose, double t)
{
    assert_non_null(pose);
    for (int k = 0; k < BONES * 16; ++k) assert_true(pose[k] == t * 1000 + k);
}

static void test_times_find_their_poses(void **state)
{
    (void)state;
    pose_cache *c = pose_cache_create(BONES, 0, (size_t)1 << 20);
    assert_non_null(c);
    double t = 0.1, next = nextafter(0.1, 1);
    fill(pose_cache_add(c, t), t);
    assert_null(pose_cache_find(c, next)); /* one ulp away: another time */
    fill(pose_cache_add(c, next), next);
    fill(pose_cache_add(c, 0.0), 0.0);
    assert_null(pose_cache_find(c, -0.0)); /* the bits differ; a clip's times are never -0 */
    expect_pose(pose_cache_find(c, t), t);
    expect_pose(pose_cache_find(c, next), next);
    expect_pose(pose_cache_find(c, 0.0), 0.0);
    assert_int_equal(pose_cache_count(c), 3);
    pose_cache_free(c);
}

static void test_pointers_stay_as_it_grows(void **state)
{
    (void)state;
    /* 3 bones: 384 bytes a pose, 5,462 poses a 2 MB block: 12,000 span three blocks and many
     * table growths. */
    enum { N = 12000 };
    pose_cache *c = pose_cache_create(BONES, 0, (size_t)64 << 20);
    assert_non_null(c);
    const double *first = NULL;
    for (uint32_t i = 0; i < N; ++i) {
        double t = i / 30.0, *pose = pose_cache_add(c, t);
        fill(pose, t);
        if (i == 0) first = pose;
    }
    assert_int_equal(pose_cache_count(c), N);
    assert_ptr_equal(pose_cache_find(c, 0.0), first);
    for (uint32_t i = 0; i < N; i += 7) expect_pose(pose_cache_find(c, i / 30.0), i / 30.0);
    assert_null(pose_cache_find(c, N / 30.0));
    pose_cache_free(c);
}

static void test_full_and_cleared(void **state)
{
    (void)state;
    pose_cache *c = pose_cache_create(BONES, 0, 10 * BONES * 16 * sizeof(double)); /* room for 10 poses */
    assert_non_null(c);
    for (uint32_t i = 0; i < 10; ++i) fill(pose_cache_add(c, i * 0.25), i * 0.25);
    assert_null(pose_cache_add(c, 2.5)); /* full: the caller samples without it */
    assert_null(pose_cache_find(c, 2.5));
    expect_pose(pose_cache_find(c, 2.25), 2.25);
    pose_cache_clear(c);
    assert_int_equal(pose_cache_count(c), 0);
    assert_null(pose_cache_find(c, 0.25));
    fill(pose_cache_add(c, 7.0), 7.0);
    expect_pose(pose_cache_find(c, 7.0), 7.0);
    assert_null(pose_cache_find(c, 2.25));
    pose_cache_free(c);
}

/* Each pose's extra doubles follow its matrices, the first NaN until the user writes it, and
 * stay with the pose. */
static void test_extra_doubles_follow_the_pose(void **state)
{
    (void)state;
    pose_cache *c = pose_cache_create(BONES, 1 + 5 * BONES, (size_t)1 << 20);
    assert_non_null(c);
    double *a = pose_cache_add(c, 0.5), *b = pose_cache_add(c, 0.75);
    fill(a, 0.5), fill(b, 0.75);
    assert_true(isnan(a[BONES * 16]) && isnan(b[BONES * 16]));
    a[BONES * 16] = 1, a[BONES * 16 + 5 * BONES] = 42;
    const double *found = pose_cache_find(c, 0.5);
    expect_pose(found, 0.5);
    assert_true(found[BONES * 16] == 1 && found[BONES * 16 + 5 * BONES] == 42);
    assert_true(isnan(pose_cache_find(c, 0.75)[BONES * 16]));
    expect_pose(pose_cache_find(c, 0.75), 0.75); /* a's extra did not run into b */
    pose_cache_free(c);
}

/* A probe's rows are rows of the probe at twice its steps, the same doubles (t0 + f x D / s and
 * t0 + 2f x D / 2s: doubling is exact), so the poses kept for one answer the other; likewise a
 * blend halfway, which measuring frames as row 2f + 1 at twice the steps. Eating's 6 s (144
 * steps at 24 fps) and open loops' durations whose quotients are inexact. */
static void test_rows_of_twice_the_steps_are_the_same_times(void **state)
{
    (void)state;
    const double durations[] = {6.0, 1.2083333333333333, 0.7916666865348816};
    const uint32_t steps[] = {144, 29, 19};
    for (int d = 0; d < 3; ++d) {
        cb_clip_info once = {0}, twice = {0};
        once.t0 = twice.t0 = 0.0416666679084301;
        once.duration = twice.duration = durations[d];
        once.steps = steps[d], twice.steps = 2 * steps[d];
        for (uint32_t f = 0; f <= steps[d]; ++f) assert_true(cb_clip_frame_time(&once, f) == cb_clip_frame_time(&twice, 2 * f));
    }
}

static void test_an_attached_block_goes_with_the_poses(void **state)
{
    (void)state;
    pose_cache *c = pose_cache_create(BONES, 0, (size_t)1 << 20);
    assert_non_null(c);
    assert_null(pose_cache_attached(c, 0));
    assert_null(pose_cache_attached(c, 1));
    int *first = malloc(sizeof *first), *second = malloc(sizeof *second), *other = malloc(sizeof *other);
    assert_non_null(first), assert_non_null(second), assert_non_null(other);
    *first = 1, *second = 2, *other = 3;
    pose_cache_attach(c, 1, first);
    assert_ptr_equal(pose_cache_attached(c, 1), first);
    assert_null(pose_cache_attached(c, 0)); /* each slot its own (a probe's sampled and fitted rows) */
    pose_cache_attach(c, 0, other);
    pose_cache_attach(c, 1, second); /* frees the first, leaves the other slot's */
    assert_int_equal(*(int *)pose_cache_attached(c, 1), 2);
    assert_int_equal(*(int *)pose_cache_attached(c, 0), 3);
    pose_cache_clear(c); /* another clip's: frees both */
    assert_null(pose_cache_attached(c, 0));
    assert_null(pose_cache_attached(c, 1));
    int *third = malloc(sizeof *third), *fourth = malloc(sizeof *fourth);
    assert_non_null(third), assert_non_null(fourth);
    pose_cache_attach(c, 0, third);
    pose_cache_attach(c, 1, fourth);
    pose_cache_free(c); /* frees the third and the fourth */
}

static void test_worst_points_by_rows_and_parts(void **state)
{
    (void)state;
    pose_cache *c = pose_cache_create(BONES, 0, (size_t)1 << 20);
    assert_non_null(c);
    pose_worst at;
    assert_false(pose_cache_worst(c, 73, 2, &at));
    pose_cache_note_worst(c, (pose_worst){73, 2, 40, 1});
    pose_cache_note_worst(c, (pose_worst){73, 4, 12, 3}); /* fitted rows at the same rate: another key */
    assert_true(pose_cache_worst(c, 73, 2, &at) && at.frame == 40 && at.sub == 1);
    assert_true(pose_cache_worst(c, 73, 4, &at) && at.frame == 12 && at.sub == 3);
    assert_false(pose_cache_worst(c, 37, 2, &at));
    pose_cache_note_worst(c, (pose_worst){73, 2, 41, 1}); /* the same rows measured again: replaced */
    assert_true(pose_cache_worst(c, 73, 2, &at) && at.frame == 41);
    for (uint32_t f = 100; f < 115; ++f) pose_cache_note_worst(c, (pose_worst){f, 2, f / 2, 1}); /* 17 in all */
    assert_false(pose_cache_worst(c, 73, 2, &at)); /* the oldest, forgotten */
    assert_true(pose_cache_worst(c, 73, 4, &at) && at.frame == 12);
    assert_true(pose_cache_worst(c, 114, 2, &at) && at.frame == 57);
    pose_cache_clear(c); /* another clip's */
    assert_false(pose_cache_worst(c, 73, 4, &at) || pose_cache_worst(c, 114, 2, &at));
    pose_cache_free(c);
}

static void test_binary_fractions_find_their_poses(void **state)
{
    (void)state;
    pose_cache *c = pose_cache_create(BONES, 0, (size_t)4 << 20);
    assert_non_null(c);
    for (int k = 0; k < 512; ++k) fill(pose_cache_add(c, k / 64.0), k / 64.0); /* 1/64 s apart: exact */
    for (int k = 0; k < 512; ++k) expect_pose(pose_cache_find(c, k / 64.0), k / 64.0);
    assert_null(pose_cache_find(c, 1.0 / 128));
    pose_cache_free(c);
}

/* A pose of `bones` joints whose every value says which time and cache it is for. */
static void fill_wide(double *pose, uint32_t bones, double t, int cache)
{
    for (size_t k = 0; k < (size_t)bones * 16; ++k) pose[k] = t * 1e6 + cache * 1e5 + (double)k;
}

static bool is_wide(const double *pose, uint32_t bones, double t, int cache)
{
    for (size_t k = 0; pose && k < (size_t)bones * 16; ++k)
        if (pose[k] != t * 1e6 + cache * 1e5 + (double)k) return false;
    return pose != NULL;
}

static void test_caches_share_an_arena(void **state)
{
    (void)state;
    /* 3 bones: 384 bytes a pose, 682 a 256 KB chunk: 3,000 a cache span five chunks each, and
     * the two together more than one 2 MB page. */
    enum { N = 3000 };
    pose_arena *arena = pose_arena_create();
    assert_non_null(arena);
    pose_cache *c[2] = {pose_cache_create_in(arena, BONES, 0, (size_t)64 << 20),
                        pose_cache_create_in(arena, BONES, 0, (size_t)64 << 20)};
    assert_non_null(c[0]), assert_non_null(c[1]);
    for (uint32_t i = 0; i < N; ++i)
        for (int k = 0; k < 2; ++k) fill_wide(pose_cache_add(c[k], i / 30.0), BONES, i / 30.0, k);
    for (uint32_t i = 0; i < N; ++i)
        for (int k = 0; k < 2; ++k) assert_true(is_wide(pose_cache_find(c[k], i / 30.0), BONES, i / 30.0, k));
    /* 9,000 joints: 1.15 MB a pose, over half a page: a block of its own each */
    enum { WIDE = 9000 };
    pose_cache *wide = pose_cache_create_in(arena, WIDE, 0, (size_t)8 << 20);
    assert_non_null(wide);
    for (int i = 0; i < 3; ++i) fill_wide(pose_cache_add(wide, i), WIDE, i, 2);
    for (int i = 0; i < 3; ++i) assert_true(is_wide(pose_cache_find(wide, i), WIDE, i, 2));
    assert_true(is_wide(pose_cache_find(c[0], (N - 1) / 30.0), BONES, (N - 1) / 30.0, 0));
    pose_cache_free(c[1]), pose_cache_free(wide), pose_cache_free(c[0]);
    pose_arena_free(arena);
}

/* A cache that releases its poses (a clip's, once its search is done) keeps what is attached and
 * its worst points, finds none of its poses, and its blocks go to the next cache of the arena
 * that needs one: the same memory, no fresh page (written over by that cache, not by the first,
 * which takes fresh blocks for its own next poses). */
static void test_released_poses_go_to_the_next_cache(void **state)
{
    (void)state;
    enum { N = 1500 }; /* three 256 KB chunks of 3-bone poses */
    pose_arena *arena = pose_arena_create();
    assert_non_null(arena);
    pose_cache *first = pose_cache_create_in(arena, BONES, 0, (size_t)64 << 20);
    assert_non_null(first);
    double *chunk_start = NULL;
    for (uint32_t i = 0; i < N; ++i) {
        double *pose = pose_cache_add(first, i / 30.0);
        fill_wide(pose, BONES, i / 30.0, 0);
        if (i == 0) chunk_start = pose;
    }
    int *rows = malloc(sizeof *rows);
    assert_non_null(rows);
    pose_cache_attach(first, 0, rows);
    pose_cache_note_worst(first, (pose_worst){30, 2, 7, 1});
    pose_cache_release_poses(first);
    assert_int_equal(pose_cache_count(first), 0);
    for (uint32_t i = 0; i < N; ++i) assert_null(pose_cache_find(first, i / 30.0));
    assert_ptr_equal(pose_cache_attached(first, 0), rows);
    pose_worst at;
    assert_true(pose_cache_worst(first, 30, 2, &at));
    assert_int_equal(at.frame, 7);
    pose_cache *next = pose_cache_create_in(arena, BONES, 0, (size_t)64 << 20);
    assert_non_null(next);
    bool reused = false;
    for (uint32_t i = 0; i < N; ++i) {
        double *pose = pose_cache_add(next, i / 60.0);
        reused = reused || pose == chunk_start;
        fill_wide(pose, BONES, i / 60.0, 1);
    }
    assert_true(reused);
    for (uint32_t i = 0; i < 10; ++i) fill_wide(pose_cache_add(first, i / 30.0), BONES, i / 30.0, 0);
    for (uint32_t i = 0; i < N; ++i) assert_true(is_wide(pose_cache_find(next, i / 60.0), BONES, i / 60.0, 1));
    for (uint32_t i = 0; i < 10; ++i) assert_true(is_wide(pose_cache_find(first, i / 30.0), BONES, i / 30.0, 0));
    pose_cache_free(first), pose_cache_free(next);
    pose_arena_free(arena);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_times_find_their_poses),
        cmocka_unit_test(test_pointers_stay_as_it_grows),
        cmocka_unit_test(test_full_and_cleared),
        cmocka_unit_test(test_extra_doubles_follow_the_pose),
        cmocka_unit_test(test_rows_of_twice_the_steps_are_the_same_times),
        cmocka_unit_test(test_an_attached_block_goes_with_the_poses),
        cmocka_unit_test(test_worst_points_by_rows_and_parts),
        cmocka_unit_test(test_binary_fractions_find_their_poses),
        cmocka_unit_test(test_caches_share_an_arena),
        cmocka_unit_test(test_released_poses_go_to_the_next_cache),
    };
    return cmocka_run_group_tests_name("pose_cache", tests, NULL, NULL);
}
