/* pool.c - see pool.h. */
#include "pool.h"

#include <stdatomic.h>
#include <stdbool.h>
#include <stdlib.h>
#include <sched.h>
#include <threads.h>
#include <time.h>

typedef struct share {
    void (*work)(void *ctx, uint32_t thread, uint32_t threads);
    void *ctx;
    uint32_t thread, threads;
} share;

static int share_main(void *arg)
{
    share *s = arg;
    s->work(s->ctx, s->thread, s->threads);
    return 0;
}

void cb_pool_run(uint32_t threads, void (*work)(void *ctx, uint32_t thread, uint32_t threads), void *ctx)
{
    if (threads < 1) threads = 1;
    if (threads > CB_POOL_MAX_THREADS) threads = CB_POOL_MAX_THREADS;
    share shares[CB_POOL_MAX_THREADS];
    thrd_t ids[CB_POOL_MAX_THREADS];
    bool started[CB_POOL_MAX_THREADS] = {false};
    for (uint32_t t = 0; t < threads; ++t) {
        shares[t] = (share){work, ctx, t, threads};
        started[t] = t > 0 && thrd_create(&ids[t], share_main, &shares[t]) == thrd_success;
    }
    share_main(&shares[0]);
    for (uint32_t t = 1; t < threads; ++t) {
        if (started[t]) thrd_join(ids[t], NULL);
        else share_main(&shares[t]); /* no thread: do its share here */
    }
}

/* ---- a pool whose threads wait between runs ---- */

/* How long a thread keeps checking for what it waits for before it sleeps: longer than the
 * serial steps between a bake's runs, short enough not to matter after the last one. */
#define SPIN_NS 200000

typedef struct helper {
    cb_pool *pool;
    uint32_t thread;
} helper;

struct cb_pool {
    uint32_t started; /* threads running, as shares 1..started */
    thrd_t ids[CB_POOL_MAX_THREADS];
    helper helpers[CB_POOL_MAX_THREADS];
    mtx_t lock;
    cnd_t wake, done;
    atomic_uint generation; /* one more at each run */
    atomic_uint remaining;  /* the threads' shares of this run not done yet */
    atomic_bool quit;
    /* this run's; written before `generation` moves (release), read after (acquire) */
    void (*work)(void *ctx, uint32_t thread, uint32_t threads);
    void *ctx;
    uint32_t shares;
};

typedef struct spin {
    struct timespec until;
    uint32_t tries;
} spin;

/* Whether to check again: true for SPIN_NS from the first call (the clock read every 64). */
static bool spin_again(spin *s)
{
    if (s->tries++ % 64 == 0) {
        struct timespec now;
        clock_gettime(CLOCK_MONOTONIC, &now);
        if (s->tries == 1) {
            s->until = now;
            s->until.tv_nsec += SPIN_NS;
            if (s->until.tv_nsec >= 1000000000) s->until.tv_sec++, s->until.tv_nsec -= 1000000000;
        } else if (now.tv_sec > s->until.tv_sec || (now.tv_sec == s->until.tv_sec && now.tv_nsec > s->until.tv_nsec)) {
            return false;
        }
    }
    /* Not a pause instruction: in a VM a loop of them can make the hypervisor take the CPU away
     * (pause-loop exiting); on the VMs measured, a thread spinning on pauses while another
     * analyzed Fox's clips made that 0.2 ms pass take 0.5. A thread that yields keeps its CPU
     * awake and gives way to anything else that wants it. */
    sched_yield();
    return true;
}

static int helper_main(void *arg)
{
    helper *h = arg;
    cb_pool *pool = h->pool;
    unsigned seen = 0;
    for (;;) {
        spin s = {0};
        while (atomic_load_explicit(&pool->generation, memory_order_acquire) == seen && spin_again(&s)) continue;
        if (atomic_load(&pool->generation) == seen) { /* asleep until advance() */
            mtx_lock(&pool->lock);
            while (atomic_load(&pool->generation) == seen) cnd_wait(&pool->wake, &pool->lock);
            mtx_unlock(&pool->lock);
        }
        if (atomic_load(&pool->quit)) return 0;
        seen = atomic_load(&pool->generation);
        if (h->thread < pool->shares) pool->work(pool->ctx, h->thread, pool->shares);
        if (atomic_fetch_sub_explicit(&pool->remaining, 1, memory_order_acq_rel) == 1) {
            mtx_lock(&pool->lock);
            cnd_signal(&pool->done);
            mtx_unlock(&pool->lock);
        }
    }
}

/* The next run: `generation` moves, and sleeping threads wake. */
static void advance(cb_pool *pool)
{
    mtx_lock(&pool->lock);
    atomic_fetch_add_explicit(&pool->generation, 1, memory_order_release);
    cnd_broadcast(&pool->wake);
    mtx_unlock(&pool->lock);
}

cb_pool *cb_pool_create(uint32_t threads)
{
    if (threads < 2) return NULL;
    if (threads > CB_POOL_MAX_THREADS) threads = CB_POOL_MAX_THREADS;
    cb_pool *pool = calloc(1, sizeof *pool);
    if (!pool) return NULL;
    if (mtx_init(&pool->lock, mtx_plain) != thrd_success) return free(pool), NULL;
    if (cnd_init(&pool->wake) != thrd_success) return mtx_destroy(&pool->lock), free(pool), NULL;
    if (cnd_init(&pool->done) != thrd_success) return cnd_destroy(&pool->wake), mtx_destroy(&pool->lock), free(pool), NULL;
    for (uint32_t t = 1; t < threads; ++t) {
        pool->helpers[t] = (helper){pool, t};
        if (thrd_create(&pool->ids[t], helper_main, &pool->helpers[t]) != thrd_success) break;
        pool->started = t;
    }
    if (pool->started) return pool;
    cb_pool_free(pool);
    return NULL;
}

void cb_pool_dispatch(cb_pool *pool, uint32_t shares, void (*work)(void *ctx, uint32_t thread, uint32_t threads),
                      void *ctx)
{
    uint32_t threads = pool ? pool->started + 1 : 1;
    if (shares < 1) shares = 1;
    if (shares > CB_POOL_MAX_THREADS) shares = CB_POOL_MAX_THREADS;
    if (pool) {
        pool->work = work, pool->ctx = ctx, pool->shares = shares;
        atomic_store_explicit(&pool->remaining, pool->started, memory_order_relaxed);
        advance(pool);
    }
    work(ctx, 0, shares);
    for (uint32_t t = threads; t < shares; ++t) work(ctx, t, shares); /* no thread for these */
    if (!pool) return;
    spin s = {0};
    while (atomic_load_explicit(&pool->remaining, memory_order_acquire) && spin_again(&s)) continue;
    if (atomic_load(&pool->remaining)) { /* asleep until the last share signals */
        mtx_lock(&pool->lock);
        while (atomic_load(&pool->remaining)) cnd_wait(&pool->done, &pool->lock);
        mtx_unlock(&pool->lock);
    }
}

void cb_pool_free(cb_pool *pool)
{
    if (!pool) return;
    atomic_store(&pool->quit, true);
    advance(pool);
    for (uint32_t t = 1; t <= pool->started; ++t) thrd_join(pool->ids[t], NULL);
    cnd_destroy(&pool->done), cnd_destroy(&pool->wake);
    mtx_destroy(&pool->lock);
    free(pool);
}
