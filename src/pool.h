/* pool.h - the library's one way to run work on several threads (private to libcrowdbake). */
#ifndef CB_POOL_H
#define CB_POOL_H

#include <stdint.h>

/* Runs work(ctx, t, threads) for t = 0..threads-1, t = 0 on the calling thread and the others
 * on threads of their own (a share whose thread cannot start runs on the caller afterwards),
 * and returns when every share is done. threads is clamped to 1..CB_POOL_MAX_THREADS. How the
 * shares split the work is the caller's: by a fixed stride when the result must not depend on
 * timing, or from a shared atomic counter. */
#define CB_POOL_MAX_THREADS 64
void cb_pool_run(uint32_t threads, void (*work)(void *ctx, uint32_t thread, uint32_t threads), void *ctx);

/* The same for work that comes in several runs one after the other (a bake's sampling,
 * encoding and measuring): threads started once, which wait between runs. A thread that has
 * done its share keeps checking for the next run for a short while before it sleeps, as
 * waking a sleeping thread can take longer than a small run (on the VMs this was measured on,
 * from 50 us to over 1 ms). cb_pool_create(threads) starts threads - 1 threads (clamped to
 * 0..CB_POOL_MAX_THREADS - 1; NULL when none is needed or none starts); cb_pool_dispatch runs
 * shares 0..shares-1 of `work` as cb_pool_run does (shares clamped to 1..CB_POOL_MAX_THREADS;
 * those without a thread, all of them with a NULL pool, run on the caller) and returns when
 * every share is done; cb_pool_free stops
 * the threads. One caller dispatches at a time. */
typedef struct cb_pool cb_pool;
cb_pool *cb_pool_create(uint32_t threads);
void cb_pool_dispatch(cb_pool *pool, uint32_t shares, void (*work)(void *ctx, uint32_t thread, uint32_t threads),
                      void *ctx);
void cb_pool_free(cb_pool *pool);

#endif
