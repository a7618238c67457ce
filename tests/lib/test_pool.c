/* test_pool.c - the threads a bake's passes run on (src/core/pool.h): every share of every run runs
 * exactly once and has finished when cb_pool_dispatch returns, whether the pool's threads were
 * still checking for work or had gone to sleep between runs; shares beyond the pool's threads,
 * and every share without a pool, run on the caller; a run's shares see what the caller wrote
 * before it, and the caller sees what they wrote; cb_pool_run is one such run. */
#include "testutil.h"

#include <stdatomic.h>
#include <string.h>
#include <threads.h>
#include <time.h>

#include "../../src/core/pool.h"

enum { RUNS = 300, MAX_SHARES = 8 };

typedef struct tally {
    uint32_t run;                 /* written by the caller before each run */
    uint32_t seen[MAX_SHARES];    /* share t: the run it last saw (plain writes: each its own) */
    atomic_uint count[MAX_SHARES]; /* share t: how many times it ran */
    thrd_t caller;
    atomic_uint on_caller;        /* shares that ran on the calling thread */
    atomic_bool bad_share;        /* a share numbered past its run's count (asserted by the caller:
                                   * cmocka's failures are the calling thread's) */
} tally;

static void count_share(void *ctx, uint32_t thread, uint32_t threads)
{
    tally *t = ctx;
    if (thread >= threads || thread >= MAX_SHARES) {
        atomic_store(&t->bad_share, true);
        return;
    }
    t->seen[thread] = t->run;
    atomic_fetch_add(&t->count[thread], 1);
    if (thrd_equal(thrd_current(), t->caller)) atomic_fetch_add(&t->on_caller, 1);
}

/* About a millisecond of the caller's own work between runs (not a wait for anything): long
 * enough that the pool's threads stop checking and sleep, whatever the machine's load. */
static void busy_a_while(void)
{
    struct timespec start, now;
    clock_gettime(CLOCK_MONOTONIC, &start);
    do clock_gettime(CLOCK_MONOTONIC, &now);
    while ((now.tv_sec - start.tv_sec) * 1000000000L + (now.tv_nsec - start.tv_nsec) < 1000000L);
}

/* RUNS runs of `shares` shares on `pool`; every other run after a pause when `pauses`. */
static void run_many(cb_pool *pool, uint32_t shares, bool pauses, tally *t)
{
    memset(t, 0, sizeof *t);
    t->caller = thrd_current();
    for (uint32_t r = 1; r <= RUNS; ++r) {
        t->run = r;
        cb_pool_dispatch(pool, shares, count_share, t);
        for (uint32_t s = 0; s < shares; ++s) { /* all done, and saw this run's value */
            assert_int_equal(atomic_load(&t->count[s]), r);
            assert_int_equal(t->seen[s], r);
        }
        if (pauses && r % 2) busy_a_while();
    }
    for (uint32_t s = shares; s < MAX_SHARES; ++s) assert_int_equal(atomic_load(&t->count[s]), 0);
    assert_false(atomic_load(&t->bad_share));
}

static void test_every_share_once_per_run(void **state)
{
    (void)state;
    static tally t;
    cb_pool *pool = cb_pool_create(4);
    assert_non_null(pool);
    run_many(pool, 4, false, &t);
    assert_int_equal(atomic_load(&t.on_caller), RUNS); /* share 0 only */
    run_many(pool, 2, false, &t); /* fewer shares than threads: the others skip the run */
    assert_int_equal(atomic_load(&t.on_caller), RUNS);
    cb_pool_free(pool);
}

static void test_threads_that_slept_wake_for_the_next_run(void **state)
{
    (void)state;
    static tally t;
    cb_pool *pool = cb_pool_create(3);
    assert_non_null(pool);
    run_many(pool, 3, true, &t);
    cb_pool_free(pool);
}

static void test_shares_without_a_thread_run_on_the_caller(void **state)
{
    (void)state;
    static tally t;
    cb_pool *pool = cb_pool_create(2);
    assert_non_null(pool);
    run_many(pool, 5, false, &t); /* shares 2..4 have no thread */
    assert_int_equal(atomic_load(&t.on_caller), 4 * RUNS);
    cb_pool_free(pool);
    run_many(NULL, 3, false, &t); /* no pool: all of them */
    assert_int_equal(atomic_load(&t.on_caller), 3 * RUNS);
    assert_null(cb_pool_create(1)); /* one thread is the caller's: nothing to start */
    assert_null(cb_pool_create(0));
    cb_pool_free(NULL);
}

static void test_one_run_on_threads_of_its_own(void **state)
{
    (void)state;
    static tally t;
    for (uint32_t threads = 0; threads <= 5; ++threads) {
        memset(&t, 0, sizeof t);
        t.caller = thrd_current(), t.run = 7;
        cb_pool_run(threads, count_share, &t);
        uint32_t shares = threads ? threads : 1; /* none asked for: the caller's own */
        for (uint32_t s = 0; s < MAX_SHARES; ++s) {
            assert_int_equal(atomic_load(&t.count[s]), s < shares);
            if (s < shares) assert_int_equal(t.seen[s], 7);
        }
        assert_false(atomic_load(&t.bad_share));
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_every_share_once_per_run),
        cmocka_unit_test(test_threads_that_slept_wake_for_the_next_run),
        cmocka_unit_test(test_shares_without_a_thread_run_on_the_caller),
        cmocka_unit_test(test_one_run_on_threads_of_its_own),
    };
    return cmocka_run_group_tests_name("pool", tests, NULL, NULL);
}
